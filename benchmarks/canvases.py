"""Time per frame of each offscreen canvas (GGUI, ti.GUI, Pillow) on the same frames, in one process.

    python -m benchmarks.canvases [--size 960x384] [--frames 36] [--colored] [--repeat 3]   (from the repository root)

Draws the reference ramp's frames (mesh, chamber, clamp, trace panel; --colored: each triangle in its
det F colour) on every canvas the backend has, and prints milliseconds per frame: the shapes alone
(FrameRenderer.draw then the canvas's read-back image) and with the text (FrameRenderer.frame), each
the best of --repeat passes over the frames.
A canvas the backend lacks (Quadrants has neither GUI) or cannot open (no Vulkan) is listed as such.
"""

import argparse
import time

from taichi_pneuma import backend, runtime
from taichi_pneuma.errors import PneumaInputError
from taichi_pneuma.render.frames import FrameRenderer, Track
from taichi_pneuma.scene.build import reference_scene
from taichi_pneuma.solve.simulate import run_schedule

CANVASES = ("ggui", "gui", "pillow")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--size", default="960x384")
    parser.add_argument("--frames", type=int, default=36)
    parser.add_argument("--colored", action="store_true")
    parser.add_argument("--repeat", type=int, default=3, help="passes over the frames; the best is kept")
    args = parser.parse_args()
    width, height = (int(v) for v in args.size.split("x"))
    runtime.init("cpu")
    result = run_schedule(reference_scene(cy=0.15, steps=args.frames).build())
    track = Track.from_result(result, color="detF" if args.colored else "none")
    print(
        f"{backend.NAME} {backend.VERSION}, {width}x{height}, {len(track.states)} frames, "
        f"{result.mesh.n_triangles} triangles{', coloured' if args.colored else ''}"
    )
    print("| canvas | shapes + read-back (ms/frame) | with text (ms/frame) |\n|---|---|---|")
    for name in CANVASES:
        try:
            renderer = FrameRenderer([track], width, height, backend=name, log=lambda *_: None)
        except PneumaInputError as exc:
            print(f"| {name} | unavailable: {exc} | |")
            continue
        renderer.frame(0)  # first frame: the canvas's own start-up
        shapes = best_of(
            args.repeat, renderer, lambda i, renderer=renderer: (renderer.draw(i), renderer.canvas.image())
        )
        whole = best_of(args.repeat, renderer, renderer.frame)
        print(f"| {renderer.canvas.name} | {1e3 * shapes:.1f} | {1e3 * whole:.1f} |")
        renderer.canvas.close()


def best_of(repeat: int, renderer, draw) -> float:
    """Seconds per frame of draw(i) over all frames, the best of `repeat` passes (the machine may be shared)."""
    passes = []
    for _ in range(repeat):
        start = time.perf_counter()
        for i in range(renderer.frames):
            draw(i)
        passes.append((time.perf_counter() - start) / renderer.frames)
    return min(passes)


if __name__ == "__main__":
    main()
