"""Offscreen frames of a 3D ramp: the deforming body's surface seen by one fixed camera, cut open by an exact
section to show its chambers, shaded to show its shape, with the axes, a scale bar, the clamp, obstacles, the rest
shape's ghost, a colour bar, a header and a trace panel.

A frame is laid out as

    header (title, the step's caption lines, the key: what the section cuts, what the colours mark)  |
    3D view (axes bottom-left, scale bar bottom-right)   | colour bar |  trace panel

- the 3D view: the body's outer surface (light green, or coloured per face or per node by a field on one scale for
  all steps, the colour map lightened by LIFT so shading reads on its dark end) and the chamber walls (blue),
  flat-shaded under a key light and a highlight (render.surface), seen by a camera (render.camera) fitted once
  to every state of the ramp, so the body never leaves the frame and the view does not jump. The section
  (render.section) cuts the body exactly by the mid-plane of the rest body normal to the world axis closest to
  the viewing direction (chosen once, at rest) and removes the camera's side: the surface is clipped at the
  plane and the cut face of every tetrahedron it crosses is drawn flat in that tetrahedron's colour, with holes
  where the chambers are (the inside of the far wall drawn darker, surface.BACK_FACE). The clamped faces (all
  corners pinned) are drawn CLAMP; a ground plane y = ground grey; each obstacle opaque and shaded (a box or a
  plane's square with dark edges; a sphere, cylinder or capsule as its surface); the rest body's silhouette as a
  grey ghost behind (render.guides3d).
- the colour bar: the field's scale with numbered ticks, its quantity and unit as one label above it;
- the trace panel: up to two series against the step, the first on the left axis and the second on the
  right (e.g. chamber volume / rest volume and pressure), drawn once by matplotlib; a cursor marks the
  current step.

Two views draw the same shaded triangles: GGUI's 3D scene (render.ggui3d) where Vulkan works and the
NumPy z-buffer rasteriser (render.surface) everywhere; 'auto' takes GGUI and falls back to NumPy. The ghost,
axes, scale bar and text are drawn onto the view's image after, the same on both.
The renderer knows nothing of meshes or solvers: it takes positions (steps, n, 3), triangles and values.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ..errors import PneumaInputError, require, shape_of
from ..io.units import LENGTH, PRESSURE
from . import guides3d
from .camera import Camera
from .colours import BACKGROUND, COLORBAR_PX, OBSTACLE_FILL, colormap
from .section import AXES, Section, plane_facing, section_of
from .surface import NumpyView, shade_faces
from .text import LINE_PX, MARGIN_PX, Label, draw_labels
from .ticks import colorbar_ticks, tick_label
from .trace3d import TracePanel

if TYPE_CHECKING:
    from .ggui3d import GGUIView

VIEWS = ("auto", "numpy", "ggui")
# the apps' --renderer (render.RENDERERS) -> the 3D view: the software renderers' counterpart is the NumPy rasteriser
VIEW_OF_RENDERER = {"auto": "auto", "ggui": "ggui", "gui": "numpy", "pillow": "numpy"}
BODY = (0.72, 0.89, 0.66)
CHAMBER = (0.3, 0.5, 0.95)
CLAMP = (0.85, 0.2, 0.35)
GROUND = (0.78, 0.76, 0.72)
LIFT = 0.35  # a field's colour: (1 - LIFT) map + LIFT white
TRACE_SHARE = 0.36  # of the frame's width
MIN_VIEW_PX = 64  # the smallest 3D view (open_view); a smaller frame drops its trace panel, then its key line
EDGE_PX = 1.5  # an obstacle's edges
FRAME_CAMERA = Camera(azimuth=-35.0)  # from the clamped end's side (scenes clamp the left end): the clamp in view


def body_colormap(values: np.ndarray, lo: float, hi: float) -> np.ndarray:
    """The 3D body's colour of values on the scale lo..hi: the colour map lightened by LIFT."""
    return (1 - LIFT) * colormap(values, lo, hi) + LIFT


@dataclass(frozen=True, eq=False)
class Track3D:
    """One 3D ramp to draw: positions (steps, n, 3), the outer surface's triangles (b, 3) and each chamber's
    wall triangles (any orientation); color: a value per boundary face (steps, b) or per node (steps, n),
    named color_label (quantity and unit); tetrahedra: the linear tetrahedra (m, 4) (the section draws their
    cut faces; none: only the surface is clipped) and cell_color their values (steps, m) (the cut faces' colour);
    title; captions: the header lines under the title, one tuple per step; trace: up to two (label, values (steps,)
    or (steps, k)) series; ground: the height y of a ground plane; pinned: the clamped nodes; obstacles: per obstacle
    its triangles (steps, t, 3, 3) and edges (steps, e, 2, 3); length_unit: the scale bar's unit suffix."""

    positions: np.ndarray
    boundary: np.ndarray
    chambers: tuple[np.ndarray, ...] = ()
    color: np.ndarray | None = None
    color_label: str = ""
    title: str = ""
    captions: tuple[tuple[str, ...], ...] | None = None
    trace: tuple[tuple[str, np.ndarray], ...] = ()
    ground: float | None = None
    tetrahedra: np.ndarray | None = None
    cell_color: np.ndarray | None = None
    pinned: tuple | np.ndarray = ()
    obstacles: tuple[tuple[np.ndarray, np.ndarray], ...] = ()
    length_unit: str = ""

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
        if self.cell_color is not None:
            require(
                self.tetrahedra is not None and np.shape(self.cell_color) == (steps, len(self.tetrahedra)),
                "cell_color must be (steps, tetrahedra)",
            )
        require(self.captions is None or len(self.captions) == steps, f"captions must give {steps} steps")
        require(len(self.trace) <= 2, f"trace: {len(self.trace)} series given, at most 2 (left and right axis)")
        for label, values in self.trace:
            require(len(values) == steps, f"trace {label!r} must give {steps} steps")

    @classmethod
    def from_result(cls, result, color: str = "none") -> Track3D:
        """The track of a 3D run (a solve.result.Result): its outer surface and chamber walls (a quadratic
        facet drawn as its four linear triangles) and tetrahedra (their corners), coloured by a COLOR_FIELDS
        field of each tetrahedron ('none': plain), captions of the chambers' volume ratios and pressures and the
        tip with their units, the volume ratio and pressure traced, the scene's ground, clamp and obstacles."""
        from . import COLOR_FIELDS

        require(
            color == "none" or color in COLOR_FIELDS, f"color = {color!r} is not one of none, {', '.join(COLOR_FIELDS)}"
        )
        mesh, history, units = result.mesh, result.history, result.scene.units
        outer, walls, under = surface_triangles(mesh)
        values, cells, label = None, None, ""
        if color != "none":
            name, key = COLOR_FIELDS[color]
            label = f"{name} [-]"  # both fields are ratios of lengths or volumes
            fields = mesh.fields
            cells = np.array([fields.at(x)[key] for x in result.positions])
            values = cells[:, under]
        captions = step_captions(result.area_ratio, result.pressure, history, units)
        pressure = units.suffix(PRESSURE)
        trace = (("volume / rest volume", result.area_ratio), (f"pressure{pressure}", result.pressure))
        return cls(
            result.positions,
            outer,
            walls,
            values,
            label,
            f"{result.scene.name}: " + ", ".join(result.chamber_names),
            captions,
            trace,
            result.ground_height,
            mesh.elements[:, :4],
            cells,
            np.asarray(mesh.pinned, np.int64),
            guides3d.obstacle_geometry(result),
            units.suffix(LENGTH),
        )

    @property
    def per_node(self) -> bool:
        return self.color is not None and np.shape(self.color)[1] == len(self.positions[0]) != len(self.boundary)


def step_captions(area_ratio: np.ndarray, pressure: np.ndarray, history: dict, units) -> tuple[tuple[str, ...], ...]:
    """Each step's header lines: the chambers' volume ratios (steps, chambers) and pressures, the tip's dy and dz
    (history's tip_dy, tip_dz) and bend (tip_rotation), every value with its unit (units: io.units.Units)."""
    length, p = units.suffix(LENGTH), units.suffix(PRESSURE)
    steps = len(area_ratio)
    return tuple(
        (
            f"step {i}/{steps - 1}   volume "
            + ", ".join(f"x{r:.2f}" for r in area_ratio[i])
            + "   p = "
            + ", ".join(f"{v:.4g}{p}" for v in pressure[i]),
            f"tip dy = {history['tip_dy'][i]:+.3g}{length}   dz = {history['tip_dz'][i]:+.3g}{length}"
            f"   bend {history['tip_rotation'][i]:+.1f} deg",
        )
        for i in range(steps)
    )


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
    require(
        width >= MIN_VIEW_PX and height >= MIN_VIEW_PX,
        f"view size {width}x{height} must be at least {MIN_VIEW_PX}x{MIN_VIEW_PX}",
    )
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


def open_section(
    rest: np.ndarray, boundary: np.ndarray, walls: np.ndarray, camera: Camera, tetrahedra: np.ndarray | None = None
) -> Section:
    """The exact section (render.section) of the rest body that opens it towards camera: by the mid-plane of its
    bounding box normal to the world axis closest to the direction from the target to the eye, the eye's side
    removed (tetrahedra None: the surface clipped, no cut faces)."""
    plane = plane_facing(rest, camera.eye - np.asarray(camera.target))
    return section_of(rest, boundary, walls, tetrahedra, *plane)


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
    return shade(np.concatenate([p for p, _ in parts]), np.concatenate([c for _, c in parts]), camera)


def shade(corners: np.ndarray, colors: np.ndarray, camera: Camera) -> tuple[np.ndarray, np.ndarray]:
    """The triangles (f, 3, 3) and their corner colours (f, 3, 3) shaded for camera: base shade + highlight
    (surface.shade_faces), clipped to 1."""
    factor, highlight = shade_faces(corners, camera)
    return corners, np.minimum(colors * factor[:, None, None] + highlight[:, None, None], 1.0)


class FrameRenderer3D:
    """Draws frame i of a Track3D (module docstring) on a view (`backend`, or the given `view`).

    camera: its direction and field of view (default FRAME_CAMERA); it is aimed and fitted to every state.
    section: cut the body open to show the chambers; trace: draw the trace panel (if the track has series);
    guides: draw the ghost, axes and scale bar."""

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
        guides: bool = True,
    ):
        self.track, self.frames, self.guides = track, len(track.positions), guides
        self.width, self.height = width, height
        rest, camera = track.positions[0], camera or FRAME_CAMERA
        cut = section and bool(track.chambers)
        walls = np.concatenate(track.chambers) if track.chambers else np.zeros((0, 3), np.int64)
        self.section: Section = (
            open_section(rest, track.boundary, walls, camera, track.tetrahedra)
            if cut
            else section_of(rest, track.boundary, walls, None, 0, np.inf, 1.0)  # a plane at infinity: all kept
        )
        self.bar_px = COLORBAR_PX if track.color is not None else 0
        self.trace_px = int(TRACE_SHARE * width) if trace and track.trace else 0
        if width - self.trace_px - self.bar_px < MIN_VIEW_PX:  # a narrow frame keeps the view, not the trace
            self.trace_px = 0
        self.key = guides3d.place_key(self._key(cut), width - self.trace_px - MARGIN_PX)
        lines = max((len(c) for c in track.captions or [()]), default=0) + bool(track.title)
        self.header_px = MARGIN_PX + LINE_PX * (lines + max((row + 1 for _, _, row in self.key), default=0))
        if height - self.header_px < MIN_VIEW_PX:  # a low frame keeps the view, not the key line
            self.key, self.header_px = [], MARGIN_PX + LINE_PX * lines
        view_size = (width - self.trace_px - self.bar_px, height - self.header_px)
        self.canvas = view or open_view(backend, *view_size, log=log)
        require(
            (self.canvas.width, self.canvas.height) == view_size,
            f"the view is {self.canvas.width}x{self.canvas.height}, the layout needs {view_size[0]}x{view_size[1]}",
        )
        margin = (0.05, max(0.06, (LINE_PX + 12) / view_size[1]))  # room for the scale bar and colour bar label
        self.camera = camera.fitted(track.positions, *view_size, margin=margin)
        pinned = np.zeros(len(rest), bool)
        pinned[np.asarray(track.pinned, np.int64)] = True
        self.clamped = pinned[track.boundary[self.section.surface_of]].all(axis=1)
        self.range: tuple[float, float] | None = None
        if track.color is not None:
            values = track.cell_color if track.cell_color is not None else track.color
            self.range = (float(values.min()), float(values.max()))
        self.ground = None if track.ground is None else self._ground_quad(track.ground)
        drawn = self.section.points(rest)[np.concatenate([self.section.surface, self.section.cut])]  # the rest section
        self.ghost = guides3d.ghost_mask(drawn, self.camera, *view_size) if guides else None
        self.corners = guides3d.quiet_corners(track.positions, self.camera, *view_size, track.length_unit)
        self._trace = TracePanel(track.trace, self.frames, self.trace_px, height) if self.trace_px else None

    def _key(self, cut: bool) -> list[tuple[str, tuple]]:
        """The header's key: what the section cuts away and what the colours mark, as (text, colour) pieces."""
        key = []
        if cut:
            s = self.section
            side = f"{'+' if s.sign > 0 else '-'}{AXES[s.axis]}"
            value = tick_label(s.value) + self.track.length_unit
            shown = "the chamber" if len(self.track.chambers) == 1 else "the chambers"
            key.append((f"section {AXES[s.axis]} = {value}: the {side} half cut away to show {shown}", guides3d.INK))
        if len(self.track.pinned):
            key.append(("clamped face", CLAMP))
        if self.track.obstacles:
            key.append(("obstacle", guides3d.INK))
        if self.guides and self.frames > 1:
            key.append(("rest shape", guides3d.GHOST_EDGE))
        return key

    def _ground_quad(self, y: float) -> np.ndarray:
        """Two triangles of the plane y = ground under the whole ramp, half its extent again each side."""
        points = self.track.positions.reshape(-1, 3)
        lo, hi = points.min(axis=0), points.max(axis=0)
        pad = (hi - lo) / 2
        (x0, z0), (x1, z1) = (lo - pad)[[0, 2]], (hi + pad)[[0, 2]]
        a, b, c, d = [x0, y, z0], [x1, y, z0], [x1, y, z1], [x0, y, z1]
        return np.array([[a, c, b], [a, d, c]], dtype=float)

    def body_colors(self, i: int) -> tuple[np.ndarray, np.ndarray]:
        """Step i's unshaded corner colours (k, 3, 3) of the clipped surface and of the cut faces."""
        track, s = self.track, self.section
        surface = np.broadcast_to(BODY, (len(s.surface), 3, 3)).copy()
        cut = np.broadcast_to(BODY, (len(s.cut), 3, 3)).copy()
        if track.color is not None:
            assert self.range is not None  # (set for a coloured track)
            if track.per_node:
                nodal = s.values(track.color[i])
                surface = body_colormap(nodal[s.surface].ravel(), *self.range).reshape(-1, 3, 3)
                cut = body_colormap(nodal[s.cut].ravel(), *self.range).reshape(-1, 3, 3)
            else:
                surface[:] = body_colormap(track.color[i][s.surface_of], *self.range)[:, None]
                if track.cell_color is not None:
                    cut[:] = body_colormap(track.cell_color[i][s.cut_of], *self.range)[:, None]
        surface[self.clamped] = CLAMP
        return surface, cut

    def triangles(self, i: int) -> tuple[np.ndarray, np.ndarray]:
        """Step i's world triangles (f, 3, 3) and their shaded corner colours (f, 3, 3): the clipped surface,
        the cut faces, the chamber walls, the ground, the obstacles, then the obstacles' edges (unshaded)."""
        s = self.section
        points = s.points(self.track.positions[i])
        surface, cut = self.body_colors(i)
        parts = [(points[s.surface], surface), (points[s.cut], cut)]
        parts.append((points[s.walls], np.broadcast_to(CHAMBER, (len(s.walls), 3, 3))))
        if self.ground is not None:
            parts.append((self.ground, np.broadcast_to(GROUND, (len(self.ground), 3, 3))))
        for triangles, _ in self.track.obstacles:
            parts.append((triangles[i], np.broadcast_to(OBSTACLE_FILL, triangles[i].shape)))
        corners, colors = shade(
            np.concatenate([p for p, _ in parts]), np.concatenate([c for _, c in parts]), self.camera
        )
        for _, edges in self.track.obstacles:
            lines = guides3d.segment_triangles(edges[i], self.camera, EDGE_PX, self.canvas.height)
            corners = np.concatenate([corners, lines])
            colors = np.concatenate([colors, np.broadcast_to(guides3d.INK, lines.shape)])
        return corners, colors

    def compose(self, i: int) -> tuple[np.ndarray, list[Label], list[tuple[float, float, float, float]]]:
        """Frame i without its text: the image (height, width, 3) uint8, its labels, and the boxes (left, top,
        right, bottom) of the drawn guides (axes, scale bar) in frame pixels."""
        require(0 <= i < self.frames, f"frame {i} is outside 0..{self.frames - 1}")
        image = np.full((self.height, self.width, 3), _rgb8(BACKGROUND), dtype=np.uint8)
        view_w, top = self.width - self.trace_px - self.bar_px, self.header_px
        view = _rgb8(self.canvas.render(*self.triangles(i), self.camera, BACKGROUND))
        labels, boxes = self._header(i), []
        if self.guides:
            assert self.ghost is not None
            guides3d.draw_ghost(view, *self.ghost, BACKGROUND)
            axes = guides3d.draw_axes(view, self.camera, self.corners[0])
            bar = guides3d.draw_scale_bar(view, self.camera, self.track.length_unit, self.corners[1])
            for texts, (left, upper, right, lower) in (axes[:2], bar[:2]):
                labels += [Label(t.text, t.x, t.y + top, t.anchor, t.color) for t in texts]
                boxes.append((left, upper + top, right, lower + top))
        image[top:, :view_w] = view
        if self.range is not None:
            labels += self._colorbar(image, view_w, *self.range)
        if self._trace is not None:
            image[:, self.width - self.trace_px :] = self._trace.frame(i)
        return image, labels, boxes

    def frame(self, i: int) -> np.ndarray:
        """Frame i as an (height, width, 3) uint8 image, text included."""
        image, labels, _ = self.compose(i)
        return draw_labels(image, labels)

    def _header(self, i: int) -> list[Label]:
        """The title, step i's captions and the key, a line each (the key's pieces side by side)."""
        captions = list(self.track.captions[i] if self.track.captions else ())
        lines = ([self.track.title] if self.track.title else []) + captions
        labels = [Label(line, MARGIN_PX, MARGIN_PX / 2 + LINE_PX * k) for k, line in enumerate(lines)]
        for label, x, row in self.key:
            labels.append(Label(label.text, x, MARGIN_PX / 2 + LINE_PX * (len(lines) + row), "la", label.color))
        return labels

    def _colorbar(self, image: np.ndarray, x0: int, lo: float, hi: float) -> list[Label]:
        """A vertical colour strip (14 px) with numbered ticks over the colour range lo..hi, drawn into image,
        its quantity above it, right-aligned with the colour bar's column."""
        top, bottom = self.header_px + LINE_PX + 6, self.height - MARGIN_PX - 8
        left = x0 + 8
        t = (bottom - np.arange(top, bottom)) / (bottom - top)
        image[top:bottom, left : left + 14] = _rgb8(body_colormap(lo + (hi - lo) * t, lo, hi))[:, None]
        labels = [Label(self.track.color_label or "colour", x0 + self.bar_px - 4, self.header_px + 2, "ra")]
        for row, figure in colorbar_ticks(lo, hi, top, bottom):
            y = int(round(row))
            image[max(y - 1, 0) : y + 1, left + 14 : left + 19] = 90
            labels.append(Label(figure, left + 22, y, "lm"))
        return labels


def _rgb8(colors) -> np.ndarray:
    """Colours in [0, 1] (any shape ending in 3) as uint8."""
    return (np.asarray(colors) * 255 + 0.5).astype(np.uint8)


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
        if getattr(renderer.canvas, "blank_frames", 0):
            log(f"GGUI gave back {renderer.canvas.blank_frames} frame(s) blank: the NumPy rasteriser drew them")
        renderer.canvas.close()
