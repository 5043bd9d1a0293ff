"""Video export: frames streamed to ffmpeg (imageio-ffmpeg), mp4 (H.264) or gif chosen by the file extension;
render_video: the whole sequence from runs to a video file, as every app and Result.video use it.

Frames go to the encoder one at a time (never all held in memory), into a temporary file beside the
target that is renamed only once the encoder has finished (output.write_atomic): an interrupted export
leaves no truncated file under the real name.
"""

from __future__ import annotations

import time
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import PneumaInputError, require, require_finite
from ..io.output import prepare_directory, write_atomic

# extension -> (codec, output pixel format, extra ffmpeg output parameters). x264's ultrafast preset: a quarter
# of the default preset's encoding time for these flat-shaded frames (0.14 against 0.59 s for the reference
# ramp's 36 frames) at the same quality setting, the file ~3x larger (~200 kB)
FORMATS = {
    ".mp4": ("libx264", "yuv420p", ["-preset", "ultrafast", "-movflags", "+faststart"]),
    ".gif": ("gif", "rgb8", []),
}


def check_video(path: str | Path, fps: float) -> tuple[str, str, list[str]]:
    """Raise PneumaInputError unless path has a known extension and fps > 0; return its encoder settings."""
    require(
        Path(path).suffix.lower() in FORMATS, f"video file {str(path)!r}: extension must be one of {', '.join(FORMATS)}"
    )
    require(require_finite("fps", fps) > 0, f"fps = {fps!r} must be > 0")
    return FORMATS[Path(path).suffix.lower()]


def frame_size(size, what: str = "size") -> tuple[int, int]:
    """A frame size given as (width, height) or as text 'WIDTHxHEIGHT' ('480x192'), checked: both even and
    >= 64 (H.264 needs even sides). Returns (width, height); PneumaInputError naming `what` otherwise."""
    text = size
    if isinstance(size, str):
        try:
            size = tuple(int(v) for v in size.lower().split("x"))
        except ValueError:
            raise PneumaInputError(f"{what} = {text!r} must look like 960x384 (WIDTHxHEIGHT)") from None
    require(
        isinstance(size, (tuple, list)) and len(size) == 2 and all(isinstance(v, int) for v in size),
        f"{what} = {text!r} must be 'WIDTHxHEIGHT' like '960x384' or a pair of integers (960, 384)",
    )
    width, height = size
    require(
        width >= 64 and height >= 64 and width % 2 == 0 and height % 2 == 0,
        f"{what} = {text!r}: width and height must be even and >= 64",
    )
    return width, height


def write_video(path: Path, frames: Iterable[np.ndarray], fps: float = 12.0) -> int:
    """Encode frames ((height, width, 3) uint8, all one size) into path; return how many were written."""
    import imageio_ffmpeg  # here, not at the top: a run without a video does not load it

    path = Path(path)
    codec, pix_fmt, params = check_video(path, fps)
    count = 0

    def write(tmp: Path) -> None:
        nonlocal count
        encoder = None
        try:
            for frame in frames:
                if encoder is None:
                    size = (frame.shape[1], frame.shape[0])
                    encoder = imageio_ffmpeg.write_frames(
                        str(tmp),
                        size,
                        fps=fps,
                        codec=codec,
                        pix_fmt_out=pix_fmt,
                        macro_block_size=1,
                        output_params=params,
                        ffmpeg_log_level="error",
                    )
                    encoder.send(None)
                require(
                    frame.shape == (size[1], size[0], 3) and frame.dtype == np.uint8,
                    f"frame {count} is {frame.shape} {frame.dtype}, expected {(size[1], size[0], 3)} uint8",
                )
                encoder.send(np.ascontiguousarray(frame))
                count += 1
            require(count > 0, f"video file {str(path)!r}: no frames to write")
        finally:
            if encoder is not None:
                encoder.close()

    write_atomic(path, write)
    return count


@dataclass
class Export:
    """What export() wrote and how long drawing the frames took (encoding excluded)."""

    video: Path
    png: Path | None
    frames: int
    width: int
    height: int
    render_seconds: float
    renderer: str = ""

    @property
    def ms_per_frame(self) -> float:
        return 1000 * self.render_seconds / self.frames


def export(
    renderer, video: Path, png: Path | None, fps: float = 12.0, quiet: bool = False, png_frame: int = -1
) -> Export:
    """Stream every frame of renderer (a render.FrameRenderer) into video, then save frame png_frame
    (default the last) as png if given. The progress bar shows on a terminal only (never in a log:
    tqdm's disable=None)."""
    import imageio.v3 as iio
    from tqdm import tqdm

    render_seconds = 0.0
    kept: np.ndarray | None = None
    png_frame = png_frame % renderer.frames

    def frames():
        nonlocal render_seconds, kept
        for i in tqdm(
            range(renderer.frames), desc="rendering", unit="frame", disable=True if quiet else None, leave=False
        ):
            start = time.perf_counter()
            image = renderer.frame(i)
            render_seconds += time.perf_counter() - start
            if i == png_frame:
                kept = image
            yield image

    count = write_video(video, frames(), fps)
    assert kept is not None  # (frames() rendered frame png_frame)
    if png is not None:
        write_atomic(Path(png), lambda tmp: iio.imwrite(tmp, kept))
    return Export(
        Path(video),
        None if png is None else Path(png),
        count,
        kept.shape[1],
        kept.shape[0],
        render_seconds,
        renderer.canvas.name,
    )


def render_video(
    runs: list,
    video,
    png=None,
    size=(960, 384),
    fps: float = 12.0,
    color: str = "stretch",
    backend: str = "auto",
    trace: bool = True,
    titles: list[str] | None = None,
    quiet: bool = True,
    log=print,
    png_frame: int = -1,
) -> Export:
    """Render runs (solve.result.Result, all of one length) side by side, one beam panel each (titled by
    titles), one frame per step, into video (.mp4 or .gif) and frame png_frame (default the last) into png
    if given; their directories are created. size: (width, height) or 'WIDTHxHEIGHT'; color: 'stretch',
    'detF' or 'none'; backend: 'auto', 'ggui' or 'gui'; trace: the area/pressure trace panel. The canvas
    is opened for it and closed after (also when the export fails)."""
    from .frames import FrameRenderer, Track

    check_video(video, fps)
    width, height = frame_size(size)
    for path in (video, png):
        if path is not None:
            prepare_directory(Path(path).parent)
    tracks = [Track.from_result(run, title, color) for run, title in zip(runs, titles or [""] * len(runs))]
    renderer = FrameRenderer(tracks, width, height, trace=trace, backend=backend, log=log)
    try:
        return export(renderer, Path(video), None if png is None else Path(png), fps, quiet, png_frame)
    finally:
        renderer.canvas.close()
