"""Offscreen frames of a 3D ramp: the deforming body's surface seen by one fixed camera, with its
chambers shown through a section, a colour field, a header and a trace panel.

A frame is laid out as

    header (title, then the step's caption lines)   |           |
    3D view                                         | colour bar | trace panel

- the 3D view: the body's outer surface (light green, or coloured per face or per node by a field on
  one viridis scale for all steps) and the chamber walls (blue), flat-shaded (render.surface), seen by
  a camera (render.camera) fitted once to every state of the ramp, so the body never leaves the frame
  and the view does not jump. The section removes the outer faces on the camera's side of the mid-plane
  of the rest body normal to the world axis closest to the viewing direction (chosen once, at rest, so
  no face pops in or out), which opens the body and shows the chambers whole inside it; the inside of
  the far wall is drawn darker (surface.BACK_FACE). An optional ground plane y = ground is drawn grey.
- the colour bar: the field's scale with numbered ticks (matplotlib's tick choice);
- the trace panel: up to two series against the step, the first on the left axis and the second on the
  right (e.g. chamber volume / rest volume and pressure), drawn once by matplotlib; a cursor marks the
  current step.

Two views draw the same shaded triangles: GGUI's 3D scene (render.ggui3d) where Vulkan works and the
NumPy z-buffer rasteriser (render.surface) everywhere; 'auto' takes GGUI and falls back to NumPy.
The renderer knows nothing of meshes or solvers: it takes positions (steps, n, 3), triangles and values.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ..errors import PneumaInputError, require, shape_of
from ..fem.fields import ElementFields
from ..io.units import LENGTH, PRESSURE
from .camera import Camera
from .colours import BACKGROUND, COLORBAR_PX, colormap
from .surface import NumpyView, shade_faces
from .text import LINE_PX, MARGIN_PX, Label, draw_labels
from .ticks import colorbar_ticks

if TYPE_CHECKING:
    from .ggui3d import GGUIView

VIEWS = ("auto", "numpy", "ggui")
# the apps' --renderer (render.RENDERERS) -> the 3D view: the software renderers' counterpart is the NumPy rasteriser
VIEW_OF_RENDERER = {"auto": "auto", "ggui": "ggui", "gui": "numpy", "pillow": "numpy"}
BODY = (0.72, 0.89, 0.66)
CHAMBER = (0.3, 0.5, 0.95)
GROUND = (0.78, 0.76, 0.72)
TRACE_SHARE = 0.36  # of the frame's width
TRACE_COLORS = ("#1f3fe0", "#d62718")


@dataclass(frozen=True, eq=False)
class Track3D:
    """One 3D ramp to draw: positions (steps, n, 3), the outer surface's triangles (b, 3) and each chamber's
    wall triangles (any orientation); color: a value per boundary face (steps, b) or per node (steps, n),
    named color_label; title; captions: the header lines under the title, one tuple per step; trace: up
    to two (label, values (steps,) or (steps, k)) series; ground: the height y of a ground plane."""

    positions: np.ndarray
    boundary: np.ndarray
    chambers: tuple[np.ndarray, ...] = ()
    color: np.ndarray | None = None
    color_label: str = ""
    title: str = ""
    captions: tuple[tuple[str, ...], ...] | None = None
    trace: tuple[tuple[str, np.ndarray], ...] = ()
    ground: float | None = None

    def __post_init__(self):
        steps = shape_of(self.positions)
        require(
            steps is not None and len(steps) == 3 and steps[2] == 3 and steps[0] >= 1 and steps[1] >= 3,
            f"positions must be (steps, nodes, 3), not {steps}",
        )
        steps, n = steps[0], steps[1]
        for faces in (self.boundary, *self.chambers):
            require(
                shape_of(faces) is not None
                and np.ndim(faces) == 2
                and np.shape(faces)[1] == 3
                and np.all((np.asarray(faces) >= 0) & (np.asarray(faces) < n)),
                f"triangles must be (k, 3) node indices in 0..{n - 1}",
            )
        if self.color is not None:
            require(
                np.shape(self.color) in ((steps, len(self.boundary)), (steps, n)),
                f"color must be (steps, boundary faces) = {(steps, len(self.boundary))} or (steps, nodes) = "
                f"{(steps, n)}, not {np.shape(self.color)}",
            )
        require(self.captions is None or len(self.captions) == steps, f"captions must give {steps} steps")
        require(len(self.trace) <= 2, f"trace: {len(self.trace)} series given, at most 2 (left and right axis)")
        for label, values in self.trace:
            require(len(values) == steps, f"trace {label!r} must give {steps} steps")

    @classmethod
    def from_result(cls, result, color: str = "none") -> Track3D:
        """The track of a 3D run (a solve.result.Result): its outer surface and chamber walls (a quadratic
        facet drawn as its four linear triangles), coloured per face by a COLOR_FIELDS field of the tetrahedron
        under it ('none': plain), captions of the chambers' volume ratios and pressures and the tip, the
        volume ratio and pressure traced, and the scene's ground."""
        from . import COLOR_FIELDS

        require(
            color == "none" or color in COLOR_FIELDS, f"color = {color!r} is not one of none, {', '.join(COLOR_FIELDS)}"
        )
        mesh, history, units = result.mesh, result.history, result.scene.units
        outer, walls, under = surface_triangles(mesh)
        values, label = None, ""
        if color != "none":
            label, key = COLOR_FIELDS[color]
            fields = ElementFields(mesh.vertices, mesh.elements)
            values = np.array([fields.at(x)[key][under] for x in result.positions])
        steps = len(result.positions)
        names = result.chamber_names
        captions = tuple(
            (
                f"step {i}/{steps - 1}   volume "
                + ", ".join(f"x{r:.2f}" for r in result.area_ratio[i])
                + "   p = "
                + ", ".join(f"{p:.4g}" for p in result.pressure[i])
                + units.suffix(PRESSURE),
                f"tip dy = {history['tip_dy'][i]:+.4f}   dz = {history['tip_dz'][i]:+.4f}{units.suffix(LENGTH)}"
                f"   bend {history['tip_rotation'][i]:+.1f} deg",
            )
            for i in range(steps)
        )
        trace = (("volume / rest volume", result.area_ratio), (f"pressure{units.suffix(PRESSURE)}", result.pressure))
        return cls(
            result.positions,
            outer,
            walls,
            values,
            label,
            f"{result.scene.name}: " + ", ".join(names),
            captions,
            trace,
            result.ground_height,
        )

    @property
    def per_node(self) -> bool:
        return self.color is not None and np.shape(self.color)[1] == len(self.positions[0]) != len(self.boundary)


def surface_triangles(mesh) -> tuple[np.ndarray, tuple[np.ndarray, ...], np.ndarray]:
    """A 3D Mesh's linear triangles to draw: the outer surface, each chamber's wall, and for each outer triangle
    the tetrahedron under it. A quadratic facet is split in four (its facet family's split_cells)."""
    from ..fem.tetmesh import facet_keys

    n, family = mesh.n_vertices, mesh.family
    on_walls = np.concatenate([facet_keys(wall, n) for wall in mesh.chambers]) if mesh.chambers else np.zeros(0)
    outer = mesh.surface[~np.isin(facet_keys(mesh.surface, n), on_walls)]
    faces = mesh.elements[:, np.array(family.facets)]  # (m, 4, nodes per facet)
    keys = facet_keys(faces.reshape(-1, faces.shape[2]), n)
    order = np.argsort(keys)
    under = order[np.searchsorted(keys, facet_keys(outer, n), sorter=order)] // faces.shape[1]
    drawn = family.facet_family  # each piece of a facet lies on the facet's tetrahedron (split_cells' order)
    return (
        drawn.split_cells(outer),
        tuple(drawn.split_cells(wall) for wall in mesh.chambers),
        np.tile(under, len(drawn.split)),
    )


def open_view(backend: str, width: int, height: int, show: bool = False, log=print):
    """A 3D view on `backend` ('numpy', 'ggui', or 'auto': GGUI when Vulkan is available, else NumPy),
    saying through log() which one (and why it fell back)."""
    require(backend in VIEWS, f"renderer = {backend!r} is not one of {', '.join(VIEWS)}")
    require(width >= 64 and height >= 64, f"view size {width}x{height} must be at least 64x64")
    view: NumpyView | GGUIView
    if backend == "numpy":
        view = NumpyView(width, height)
    else:
        from ..backend import has_ggui
        from .ggui3d import GGUIView

        try:
            if not has_ggui():
                raise RuntimeError("this Taichi backend has no GGUI (ti.ui)")
            view = GGUIView(width, height, show)
        except RuntimeError as exc:
            if backend == "ggui":
                raise PneumaInputError(f"renderer = 'ggui' is unavailable: {exc}") from None
            log(f"renderer: {NumpyView.name} (GGUI unavailable: {exc})")
            return NumpyView(width, height)
    log(f"renderer: {view.name}")
    return view


def section_faces(rest: np.ndarray, faces: np.ndarray, camera: Camera) -> np.ndarray:
    """Which faces to keep: those whose rest centroid lies on the far side of the mid-plane of the rest
    bounding box normal to the world axis closest to the direction from the target to the eye."""
    towards_eye = camera.eye - np.asarray(camera.target)
    axis = int(np.argmax(np.abs(towards_eye)))
    middle = (rest[:, axis].min() + rest[:, axis].max()) / 2
    return np.sign(towards_eye[axis]) * (rest[faces].mean(axis=1)[:, axis] - middle) <= 0


def shaded_triangles(
    x: np.ndarray, faces: np.ndarray, walls: np.ndarray, camera: Camera, body=None, ground: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """The world triangles (f, 3, 3) of the body's faces, the chamber walls and the ground quad (if any) at
    positions x, and their corner colours shaded for camera: the body's corner colours (len(faces), 3, 3)
    or BODY, the walls CHAMBER, the ground GROUND."""
    body = np.broadcast_to(BODY, (len(faces), 3, 3)) if body is None else body
    parts = [(x[faces], body), (x[walls], np.broadcast_to(CHAMBER, (len(walls), 3, 3)))]
    if ground is not None:
        parts.append((ground, np.broadcast_to(GROUND, (len(ground), 3, 3))))
    corners = np.concatenate([p for p, _ in parts])
    colors = np.concatenate([c for _, c in parts]) * shade_faces(corners, camera)[:, None, None]
    return corners, colors


class FrameRenderer3D:
    """Draws frame i of a Track3D (module docstring) on a view (`backend`, or the given `view`).

    camera: its direction and field of view (default Camera()); it is aimed and fitted to every state.
    section: open the body to show the chambers; trace: draw the trace panel (if the track has series)."""

    def __init__(
        self,
        track: Track3D,
        width: int = 960,
        height: int = 540,
        backend: str = "auto",
        camera: Camera | None = None,
        section: bool = True,
        trace: bool = True,
        log=print,
        view=None,
    ):
        self.track, self.frames = track, len(track.positions)
        self.width, self.height = width, height
        self.header_px = MARGIN_PX + LINE_PX * (1 + max((len(c) for c in track.captions or [()]), default=0))
        self.trace_px = int(TRACE_SHARE * width) if trace and track.trace else 0
        self.bar_px = COLORBAR_PX if track.color is not None else 0
        view_size = (width - self.trace_px - self.bar_px, height - self.header_px)
        self.canvas = view or open_view(backend, *view_size, log=log)
        require(
            (self.canvas.width, self.canvas.height) == view_size,
            f"the view is {self.canvas.width}x{self.canvas.height}, the layout needs {view_size[0]}x{view_size[1]}",
        )
        self.camera = (camera or Camera()).fitted(track.positions, *view_size)
        rest = track.positions[0]
        keep = (
            section_faces(rest, track.boundary, self.camera)
            if section and track.chambers
            else np.ones(len(track.boundary), bool)
        )
        self.kept = np.flatnonzero(keep)
        self.walls = np.concatenate(track.chambers) if track.chambers else np.zeros((0, 3), np.int64)
        self.range: tuple[float, float] | None = None
        if track.color is not None:
            values = track.color if track.per_node else track.color[:, self.kept]
            self.range = (float(values.min()), float(values.max()))
        self.ground = None if track.ground is None else self._ground_quad(track.ground)
        self._trace = TracePanel(track.trace, self.frames, self.trace_px, height) if self.trace_px else None

    def _ground_quad(self, y: float) -> np.ndarray:
        """Two triangles of the plane y = ground under the whole ramp, half its extent again each side."""
        points = self.track.positions.reshape(-1, 3)
        lo, hi = points.min(axis=0), points.max(axis=0)
        pad = (hi - lo) / 2
        (x0, z0), (x1, z1) = (lo - pad)[[0, 2]], (hi + pad)[[0, 2]]
        a, b, c, d = [x0, y, z0], [x1, y, z0], [x1, y, z1], [x0, y, z1]
        return np.array([[a, c, b], [a, d, c]], dtype=float)

    def triangles(self, i: int) -> tuple[np.ndarray, np.ndarray]:
        """Step i's world triangles (f, 3, 3) and their shaded corner colours (f, 3, 3)."""
        track = self.track
        faces = track.boundary[self.kept]
        body = None
        if track.color is not None:
            assert self.range is not None  # (set for a coloured track)
            if track.per_node:
                body = colormap(track.color[i][faces].ravel(), *self.range).reshape(-1, 3, 3)
            else:
                body = np.repeat(colormap(track.color[i][self.kept], *self.range)[:, None], 3, axis=1)
        return shaded_triangles(track.positions[i], faces, self.walls, self.camera, body, self.ground)

    def frame(self, i: int) -> np.ndarray:
        """Frame i as an (height, width, 3) uint8 image, text included."""
        require(0 <= i < self.frames, f"frame {i} is outside 0..{self.frames - 1}")
        image = np.full((self.height, self.width, 3), _rgb8(BACKGROUND), dtype=np.uint8)
        view_w = self.width - self.trace_px - self.bar_px
        image[self.header_px :, :view_w] = _rgb8(self.canvas.render(*self.triangles(i), self.camera, BACKGROUND))
        labels = [
            Label(line, MARGIN_PX, MARGIN_PX / 2 + LINE_PX * k)
            for k, line in enumerate(
                ([self.track.title] if self.track.title else [])
                + list(self.track.captions[i] if self.track.captions else ())
            )
        ]
        if self.range is not None:
            labels += self._colorbar(image, view_w, *self.range)
        if self._trace is not None:
            image[:, self.width - self.trace_px :] = self._trace.frame(i)
        return draw_labels(image, labels)

    def _colorbar(self, image: np.ndarray, x0: int, lo: float, hi: float) -> list[Label]:
        """A vertical colour strip (14 px) with numbered ticks over the colour range lo..hi, drawn into image."""
        top, bottom = self.header_px + LINE_PX, self.height - MARGIN_PX - 8
        left = x0 + 8
        t = (bottom - np.arange(top, bottom)) / (bottom - top)
        image[top:bottom, left : left + 14] = _rgb8(colormap(lo + (hi - lo) * t, lo, hi))[:, None]
        labels = [Label(self.track.color_label or "colour", left - 4, self.header_px)]
        for row, figure in colorbar_ticks(lo, hi, top, bottom):
            y = int(round(row))
            image[max(y - 1, 0) : y + 1, left + 14 : left + 19] = 90
            labels.append(Label(figure, left + 22, y, "lm"))
        return labels


def _rgb8(colors) -> np.ndarray:
    """Colours in [0, 1] (any shape ending in 3) as uint8."""
    return (np.asarray(colors) * 255 + 0.5).astype(np.uint8)


class TracePanel:
    """The series of a track against the step, drawn once by matplotlib onto a (height, width) image;
    frame(i) adds the cursor at step i."""

    def __init__(self, trace, steps: int, width: int, height: int):
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure

        figure = Figure(figsize=(width / 100, height / 100), dpi=100)
        canvas = FigureCanvasAgg(figure)
        axes = figure.add_axes((0.2, 0.14, 0.6, 0.72))
        step = np.arange(steps)
        for k, ((label, values), color) in enumerate(zip(trace, TRACE_COLORS)):
            ax = axes if k == 0 else axes.twinx()
            ax.plot(step, np.reshape(values, (steps, -1)), color=color, marker="o", markersize=2.5, lw=1.5)
            ax.set_ylabel(label, color=color)
            ax.tick_params(axis="y", colors=color)
        axes.set_xlabel("step")
        axes.set_xlim(0, max(steps - 1, 1))
        canvas.draw()
        self.image = np.asarray(canvas.buffer_rgba())[:, :, :3].copy()
        box = axes.get_window_extent()
        self.columns = [int(round(c)) for c in axes.transData.transform(np.column_stack([step, step * 0]))[:, 0]]
        self.rows = (int(round(height - box.y1)), int(round(height - box.y0)))

    def frame(self, i: int) -> np.ndarray:
        image = self.image.copy()
        image[self.rows[0] : self.rows[1], self.columns[i]] = (60, 60, 60)
        return image


def render_video_3d(
    track: Track3D,
    video,
    png=None,
    size=(960, 540),
    fps: float = 12.0,
    backend: str = "auto",
    camera: Camera | None = None,
    section: bool = True,
    trace: bool = True,
    quiet: bool = True,
    log=print,
    png_frame: int = -1,
):
    """Render every step of track into video (.mp4 or .gif) and frame png_frame (default the last) into png if
    given (their directories are created); size: (width, height) or 'WIDTHxHEIGHT'; backend: a view (VIEWS)
    or an app's --renderer (VIEW_OF_RENDERER). The view is opened for it and closed after (also when the
    export fails). Returns video.Export (with ms per frame)."""
    from pathlib import Path

    from ..io.output import prepare_directory
    from .video import check_video, export, frame_size

    check_video(video, fps)
    width, height = frame_size(size)
    for path in (video, png):
        if path is not None:
            prepare_directory(Path(path).parent)
    backend = VIEW_OF_RENDERER.get(backend, backend)
    renderer = FrameRenderer3D(
        track, width, height, backend=backend, camera=camera, section=section, trace=trace, log=log
    )
    try:
        return export(renderer, Path(video), None if png is None else Path(png), fps, quiet, png_frame)
    finally:
        renderer.canvas.close()
