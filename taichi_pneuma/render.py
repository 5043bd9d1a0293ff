"""Offscreen frames of inflation ramps, drawn by Taichi's own renderers.

One frame shows, for each ramp (a *track*), a beam panel:
- the body mesh, faces filled light green, edges darker green;
- the chamber, its deformed wall loop filled translucent blue (alpha-blended onto the background:
  the chamber is a hole in the mesh, so only background lies under it) and outlined in strong blue;
- the pinned vertices as dark square markers;
- for inverse control, the target as a red cross and the tip's path so far in orange;
- a text overlay: step, commanded area ratio, chamber pressure, tip deflection (and the panel's title).
and, optionally, beside the beam panels a trace panel: chamber area / rest area (blue) and chamber
pressure (red) against inflation %, each scaled to the panel, with a cursor at the current step.

Every beam panel uses one world-to-pixel map (equal x and y scale) fitted to the bounds of all
states of all tracks, so panels share a frame of reference and the beam is never cropped.

Two backends draw the same primitives (filled triangles, line segments, text):
- GGUI offscreen, ti.ui.Window(show_window=False), when Vulkan is available; on CPU-only machines
  mesa's lavapipe (apt-get install mesa-vulkan-drivers) provides it, and it works with ti.cpu;
- ti.GUI(show_gui=False), a software rasteriser, otherwise.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import taichi as ti
import triangle

from . import runtime
from .errors import PneumaInputError, require
from .geometry import Mesh

BACKENDS = ("auto", "ggui", "gui")
BACKGROUND = (1.0, 1.0, 1.0)
FACE = (0.72, 0.89, 0.66)
EDGE = (0.18, 0.49, 0.20)
CHAMBER_ALPHA = 0.35
CHAMBER_FILL = tuple(CHAMBER_ALPHA * c + (1 - CHAMBER_ALPHA) * b for c, b in zip((0.1, 0.3, 1.0), BACKGROUND))
CHAMBER_WALL = (0.05, 0.2, 0.95)
PIN = (0.15, 0.15, 0.15)
GROUND = (0.45, 0.3, 0.15)
AXES = (0.35, 0.35, 0.35)
AREA_CURVE = (0.05, 0.2, 0.95)
PRESSURE_CURVE = (0.85, 0.15, 0.1)
CURSOR = (0.2, 0.2, 0.2)
TARGET = (0.9, 0.1, 0.1)
TIP_PATH = (0.95, 0.55, 0.0)


# --- backends: one canvas of (width, height) pixels, coordinates normalised to [0, 1], origin bottom-left ---

class GGUICanvas:
    """Taichi GGUI (Vulkan) window; offscreen unless show=True. Text goes into small imgui boxes."""

    name = "GGUI (Vulkan)"
    slider_row_px = 45  # each slider takes a row this high at the bottom of the window

    def __init__(self, width: int, height: int, show: bool = False, title: str = "taichi-pneuma"):
        self.width, self.height = width, height
        self.window = ti.ui.Window(title, (width, height), show_window=show, vsync=False)
        self.canvas = self.window.get_canvas()
        self._fields: dict[tuple[int, int], ti.Field] = {}
        self._calls = 0
        self._boxes = 0

    def begin(self) -> None:
        # GGUI's own staging kernels warn "f32 <- f64" when compiled under default_fp=f64; they are harmless.
        ti.set_logging_level(ti.ERROR)
        self.canvas.set_background_color(BACKGROUND)
        self._calls = self._boxes = 0

    def _points(self, points: np.ndarray):
        key = (self._calls, len(points))
        self._calls += 1
        if key not in self._fields:
            self._fields[key] = ti.Vector.field(2, ti.f32, len(points))
        field = self._fields[key]
        field.from_numpy(points.astype(np.float32))
        return field

    def triangles(self, corners: np.ndarray, color) -> None:
        self.canvas.triangles(self._points(corners.reshape(-1, 2)), color=tuple(color))

    def segments(self, ends: np.ndarray, color, width_px: float) -> None:
        self.canvas.lines(self._points(ends.reshape(-1, 2)), width_px / self.height, color=tuple(color))

    def text(self, lines: list[str], x: float, y: float, width: float) -> None:
        gui = self.window.get_gui()
        height = (len(lines) * 19 + 30) / self.height
        with gui.sub_window(f"##{self._boxes}", x, 1 - y, width, height):
            for line in lines:
                gui.text(line)
        self._boxes += 1

    def image(self) -> np.ndarray:
        image = _to_rgb8(self.window.get_image_buffer_as_numpy())
        ti.set_logging_level(ti.WARN)
        return image

    def slider(self, label: str, value: float, low: float, high: float, row: int = 0) -> float:
        """An imgui slider showing value, in row `row` (slider_row_px high) counted up from the bottom
        of the window; returns its value (the user's, if they moved it)."""
        gui = self.window.get_gui()
        height = self.slider_row_px / self.height
        with gui.sub_window(f"##slider{row}", 0.0, 1 - (row + 1) * height, 1.0, height):
            return gui.slider_float(label, value, low, high)

    def mouse(self) -> tuple[float, float, bool]:
        """The cursor (normalised, origin bottom-left) and whether the left button is down."""
        x, y = self.window.get_cursor_pos()
        return float(x), float(y), bool(self.window.is_pressed(ti.ui.LMB))

    @property
    def running(self) -> bool:
        return self.window.running

    def show(self) -> None:
        ti.set_logging_level(ti.WARN)
        self.window.show()


class GUICanvas:
    """Taichi's ti.GUI software rasteriser; offscreen unless show=True."""

    name = "ti.GUI (software)"
    slider_row_px = 0  # ti.GUI draws its sliders over the top of the window, taking no row

    def __init__(self, width: int, height: int, show: bool = False, title: str = "taichi-pneuma"):
        self.width, self.height = width, height
        self.gui = ti.GUI(title, res=(width, height), show_gui=show, background_color=_hex(BACKGROUND))

    def begin(self) -> None:
        self.gui.clear(_hex(BACKGROUND))

    def triangles(self, corners: np.ndarray, color) -> None:
        self.gui.triangles(corners[:, 0], corners[:, 1], corners[:, 2], color=_hex(color))

    def segments(self, ends: np.ndarray, color, width_px: float) -> None:
        self.gui.lines(ends[:, 0], ends[:, 1], radius=width_px / 2, color=_hex(color))

    def text(self, lines: list[str], x: float, y: float, width: float) -> None:
        for i, line in enumerate(lines):
            self.gui.text(line, (x + 4 / self.width, y - (4 + 16 * i) / self.height), font_size=15, color=0x202020)

    def image(self) -> np.ndarray:
        return _to_rgb8(self.gui.get_image())

    def slider(self, label: str, value: float, low: float, high: float, row: int = 0) -> float:
        """ti.GUI's slider named label (created on first call): shows value unless the user moved it
        since the last call; returns its value (the user's, if they moved it). row: unused (ti.GUI
        stacks its sliders itself)."""
        sliders = self.__dict__.setdefault("_sliders", {})
        if label not in sliders:
            sliders[label] = [self.gui.slider(label, low, high, step=(high - low) / 200), value]
            sliders[label][0].value = value
        widget, shown = sliders[label]
        if widget.value == shown:  # not moved by the user: show the caller's value
            widget.value = value
        sliders[label][1] = float(widget.value)
        return sliders[label][1]

    def mouse(self) -> tuple[float, float, bool]:
        """The cursor (normalised, origin bottom-left) and whether the left button is down."""
        list(self.gui.get_events())  # consuming the events updates the pressed keys
        x, y = self.gui.get_cursor_pos()
        return float(x), float(y), bool(self.gui.is_pressed(ti.GUI.LMB))

    @property
    def running(self) -> bool:
        return self.gui.running

    def show(self) -> None:
        self.gui.show()


def _hex(color) -> int:
    r, g, b = (int(round(255 * c)) for c in color)
    return (r << 16) | (g << 8) | b


def _to_rgb8(buffer: np.ndarray) -> np.ndarray:
    """(width, height, 4) float buffer, origin bottom-left -> (height, width, 3) uint8, top row first."""
    return np.ascontiguousarray((np.clip(np.rot90(buffer[:, :, :3]), 0, 1) * 255 + 0.5).astype(np.uint8))


def open_canvas(width: int, height: int, backend: str = "auto", show: bool = False, log=print):
    """A canvas on `backend` ('ggui', 'gui', or 'auto': GGUI when Vulkan is available, else ti.GUI).

    Says through log() which renderer it uses (and why it fell back).
    """
    require(backend in BACKENDS, f"renderer = {backend!r} is not one of {', '.join(BACKENDS)}")
    require(width >= 64 and height >= 64, f"frame size {width}x{height} must be at least 64x64")
    runtime.ensure_initialised()
    if backend in ("auto", "ggui"):
        try:
            canvas = GGUICanvas(width, height, show)
        except RuntimeError as exc:
            if backend == "ggui":
                raise PneumaInputError(f"renderer = 'ggui' is unavailable: {exc}") from None
            log(f"renderer: {GUICanvas.name} (GGUI unavailable: {exc})")
            return GUICanvas(width, height, show)
        log(f"renderer: {canvas.name}")
        return canvas
    log(f"renderer: {GUICanvas.name}")
    return GUICanvas(width, height, show)


# --- what is drawn ---

@dataclass(frozen=True)
class Track:
    """One run to show: its mesh, its states (steps, n, 2) and the per-step figures of the overlay:
    area_ratio and pressure as (steps, chambers), tip_dy as (steps,)."""

    mesh: Mesh
    states: np.ndarray
    area_ratio: np.ndarray
    pressure: np.ndarray
    tip_dy: np.ndarray
    title: str = ""
    ground: float | None = None  # height of the ground line y = ground, drawn when the scene has one
    targets: np.ndarray | None = None  # (steps, 2) inverse control's target point per frame: a cross and the tip's path

    @classmethod
    def from_ramp(cls, mesh: Mesh, result, title: str = "", ground: float | None = None) -> "Track":
        """A track from a simulate.RampResult (every chamber of the scene)."""
        names = list(result.steps[0].chambers)
        columns = lambda key: np.column_stack([result.column(f"{n}.{key}") for n in names])
        return cls(mesh, result.states, columns("area_ratio"), columns("pressure"), result.column("tip_dy"), title,
                   ground)

    @property
    def progress_percent(self) -> np.ndarray:
        """Position in the schedule: 0 % at the first step, 100 % at the last."""
        steps = len(self.states)
        return 100 * np.arange(steps) / max(steps - 1, 1)


def chamber_triangles(mesh: Mesh) -> np.ndarray:
    """Triangulate every chamber's rest wall loop (no added points); reused on every deformed loop."""
    parts = []
    for loop in mesh.chambers:
        k = len(loop)
        ring = np.column_stack([np.arange(k), (np.arange(k) + 1) % k])
        out = triangle.triangulate({"vertices": mesh.vertices[loop], "segments": ring}, "p")
        require(len(out["vertices"]) == k, "chamber wall loop could not be triangulated without extra points")
        parts.append(loop[out["triangles"]])
    return np.concatenate(parts)


def mesh_edges(mesh: Mesh) -> np.ndarray:
    """Unique undirected edges (e, 2) of the element outlines: a quadratic triangle's sides are drawn as
    two segments each, through their midside nodes."""
    ring = [0, 1, 2] if mesh.order == 1 else [0, 3, 1, 4, 2, 5]
    t = mesh.triangles[:, ring]
    edges = np.sort(np.stack([t, np.roll(t, -1, axis=1)], axis=2).reshape(-1, 2), axis=1)
    return np.unique(edges, axis=0)


class FrameRenderer:
    """Draws frame i of one or more tracks of equal length: beam panels side by side, plus a trace panel.

    width, height: frame size in pixels; trace: draw the area/pressure trace panel at the right;
    bounds: the world box (lo, hi) every panel must show, default the bounds of all states;
    canvas: draw on this canvas instead of opening one.
    """

    def __init__(self, tracks: list[Track], width: int = 960, height: int = 384, trace: bool = True,
                 backend: str = "auto", log=print, canvas=None, bounds=None):
        require(len(tracks) >= 1, "nothing to render: no tracks")
        lengths = {len(t.states) for t in tracks}
        require(len(lengths) == 1, f"tracks have different step counts {sorted(lengths)}")
        self.tracks, self.trace = tracks, trace
        self.frames = lengths.pop()
        self.canvas = canvas or open_canvas(width, height, backend, log=log)
        self.width, self.height = self.canvas.width, self.canvas.height
        self._art = [(mesh_edges(t.mesh), t.mesh.display_triangles(), chamber_triangles(t.mesh)) for t in tracks]
        beam_width = 0.62 if trace else 1.0
        n = len(tracks)
        self.panels = [(beam_width * i / n, beam_width * (i + 1) / n) for i in range(n)]
        self.trace_panel = (beam_width, 1.0)
        points = np.concatenate([t.states.reshape(-1, 2) for t in self.tracks]
                                + [t.targets for t in self.tracks if t.targets is not None])
        self._lo, self._hi = (np.asarray(b, float) for b in (bounds if bounds is not None else
                                                             (points.min(axis=0), points.max(axis=0))))
        self._fit_view(self._lo, self._hi)

    def _fit_view(self, lo: np.ndarray, hi: np.ndarray) -> None:
        """One map world -> normalised canvas for every beam panel showing the box lo..hi, equal axes."""
        lo, hi = np.asarray(lo, float), np.asarray(hi, float)
        centre, extent = (lo + hi) / 2, np.maximum(hi - lo, 1e-12)
        panel_px = np.array([(self.panels[0][1] - self.panels[0][0]) * self.width, self.height])
        usable = panel_px - 2 * 12 - np.array([0, 70])  # margins; room for the text overlay at the top
        self._scale = float(np.min(usable / extent))  # pixels per world unit
        self._centre, self._offset_px = centre, np.array([0.0, -35.0])

    def to_canvas(self, panel: int, points: np.ndarray) -> np.ndarray:
        """World points (..., 2) -> normalised canvas coordinates inside beam panel `panel`."""
        x0, x1 = self.panels[panel]
        centre_px = np.array([(x0 + x1) / 2 * self.width, self.height / 2]) + self._offset_px
        px = centre_px + (points - self._centre) * self._scale
        return px / np.array([self.width, self.height])

    def to_world(self, panel: int, uv: np.ndarray) -> np.ndarray:
        """Normalised canvas coordinates (..., 2) inside beam panel `panel` -> world points (to_canvas inverted)."""
        x0, x1 = self.panels[panel]
        centre_px = np.array([(x0 + x1) / 2 * self.width, self.height / 2]) + self._offset_px
        return self._centre + (np.asarray(uv) * np.array([self.width, self.height]) - centre_px) / self._scale

    def frame(self, i: int) -> np.ndarray:
        """Frame i as an (height, width, 3) uint8 image."""
        self.draw(i)
        return self.canvas.image()

    def draw(self, i: int) -> None:
        """Draw frame i on the canvas."""
        require(0 <= i < self.frames, f"frame {i} is outside 0..{self.frames - 1}")
        c = self.canvas
        c.begin()
        for p, (track, (edges, faces, chamber)) in enumerate(zip(self.tracks, self._art)):
            x = self.to_canvas(p, track.states[i])
            if track.ground is not None:
                ends = self.to_canvas(p, np.array([[self._lo[0], track.ground], [self._hi[0], track.ground]]))
                c.segments(ends[None], GROUND, 3.0)
            c.triangles(x[faces], FACE)
            c.segments(x[edges], EDGE, 1.0)
            c.triangles(x[chamber], CHAMBER_FILL)
            for loop in track.mesh.chambers:
                c.segments(np.stack([x[loop], x[np.roll(loop, -1)]], axis=1), CHAMBER_WALL, 2.5)
            c.triangles(_squares(x[track.mesh.pinned], 3.5 / np.array([self.width, self.height])), PIN)
            if track.targets is not None:
                self._draw_target(p, track, i)
            lines = [track.title] if track.title else []
            areas = ", ".join(f"x{r:.2f}" for r in track.area_ratio[i])
            pressures = ", ".join(f"{p_:.1f}" for p_ in track.pressure[i])
            lines += [f"step {i}/{self.frames - 1}   area {areas}",
                      f"p = {pressures}   tip dy = {track.tip_dy[i]:+.4f}"]
            x0, x1 = self.panels[p]
            c.text(lines, x0 + 0.005, 0.995, x1 - x0 - 0.01)
        if self.trace:
            self._draw_trace(i)

    def _draw_target(self, panel: int, track: Track, i: int) -> None:
        """The tip's path up to frame i (the mean of the tip vertices) and a cross at frame i's target."""
        c = self.canvas
        path = self.to_canvas(panel, track.states[:i + 1, track.mesh.tip].mean(axis=1))
        if len(path) > 1:
            c.segments(np.stack([path[:-1], path[1:]], axis=1), TIP_PATH, 2.0)
        centre = self.to_canvas(panel, track.targets[i])
        arm = 9.0 / np.array([self.width, self.height])
        c.segments(np.array([[centre - arm, centre + arm], [centre + arm * (-1, 1), centre + arm * (1, -1)]]),
                   TARGET, 3.0)

    def _draw_trace(self, i: int) -> None:
        """Area / rest area and pressure of every chamber against schedule progress %, each scaled to the
        plot box; cursor at step i."""
        c = self.canvas
        x0, x1 = self.trace_panel
        box = np.array([[x0 + 0.04, 0.1], [x1 - 0.03, 0.72]])  # (left, bottom), (right, top)
        corners = np.array([box[0], [box[1, 0], box[0, 1]], box[1], [box[0, 0], box[1, 1]]])
        c.segments(np.stack([corners, np.roll(corners, -1, axis=0)], axis=1), AXES, 1.0)
        texts = []
        for track in self.tracks:
            u = track.progress_percent / 100
            for values, color, label in ((track.area_ratio, AREA_CURVE, "area / rest"),
                                         (track.pressure, PRESSURE_CURVE, "pressure p")):
                lo, hi = float(values.min()), float(values.max())
                for curve in values.T:  # one curve per chamber, all on the same scale
                    v = (curve - lo) / (hi - lo if hi > lo else 1.0)
                    pts = box[0] + np.column_stack([u, v]) * (box[1] - box[0])
                    c.segments(np.stack([pts[:-1], pts[1:]], axis=1), color, 2.0)
                    c.triangles(_squares(pts[i:i + 1], 4.0 / np.array([self.width, self.height])), color)
                texts.append(f"{label}: {_nice(lo)} .. {_nice(hi)}  ({'blue' if color is AREA_CURVE else 'red'})")
        cursor_x = box[0, 0] + self.tracks[0].progress_percent[i] / 100 * (box[1, 0] - box[0, 0])
        c.segments(np.array([[[cursor_x, box[0, 1]], [cursor_x, box[1, 1]]]]), CURSOR, 1.0)
        texts.append(f"x: schedule 0 .. 100 %   now {self.tracks[0].progress_percent[i]:.0f} %")
        c.text(texts, x0 + 0.005, 0.995, x1 - x0 - 0.01)


def _nice(value: float) -> str:
    """A figure for the trace legend: 4 significant digits, round-off below 1e-9 shown as 0."""
    return f"{value if abs(value) > 1e-9 else 0.0:.4g}"


def _squares(centres: np.ndarray, half: np.ndarray) -> np.ndarray:
    """Two triangles (2k, 3, 2) per square marker of half-size `half` (normalised) at each centre."""
    lo, hi = centres - half, centres + half
    a, b, c, d = lo, np.column_stack([hi[:, 0], lo[:, 1]]), hi, np.column_stack([lo[:, 0], hi[:, 1]])
    return np.concatenate([np.stack([a, b, c], axis=1), np.stack([a, c, d], axis=1)])
