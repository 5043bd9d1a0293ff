"""Offscreen frames of 2D runs: FrameRenderer draws one or more tracks (a run's states and figures) side by
side on a canvas (canvases.py), each frame a beam panel per track, a colour bar when the body is coloured by a
field, and a trace panel of the chambers' area and pressure against the step (what a frame shows:
docs/guide/output.md). Every beam panel shares one world-to-pixel map fitted to all states of all tracks, their
rest shapes and the obstacles near them; the rest outline is drawn as a light ghost under the body, and a scale
bar (scalebar.py, in the scene's length unit) in a corner of the first panel that no step's body covers."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import require
from ..fem.mesh import Mesh
from ..io.units import AREA, LENGTH, PRESSURE
from . import COLOR_FIELDS
from .canvases import open_canvas
from .colours import (
    AREA_CURVE,
    AXES,
    CHAMBER_FILL,
    CHAMBER_WALL,
    COLORBAR_PX,
    CURSOR,
    EDGE,
    FACE,
    GHOST,
    GROUND,
    OBSTACLE,
    OBSTACLE_FILL,
    OUTLINE,
    PIN,
    PRESSURE_CURVE,
    TARGET,
    TEXT,
    TIP_PATH,
    colormap,
)
from .scalebar import emptiest, scale_bar
from .text import LINE_PX, MARGIN_PX, Label, draw_labels, label_box, number
from .ticks import colorbar_ticks, nice_ticks, tick_label
from .view2d import chamber_triangles, mesh_edges, view_bounds

HEADER_LINES = 3  # title (if any), step and area, pressure and tip: the band above the body, title or not
HEADER_CHAMBERS = 4  # more chambers than this show their areas (and differing pressures) as a range in the header
# the trace panel: the plot box's margins (pixels: left, top, right, bottom) and the smallest box worth
# drawing (a smaller --size leaves the panel out); room per tick label along x and y
TRACE_MARGINS_PX = (58, MARGIN_PX + 3 * LINE_PX + 8, 58, 2 * LINE_PX + 12)
TRACE_MIN_BOX_PX = (60, 40)
TICK_ROOM_PX = (34, 20)
PIN_HALF_PX = 3.5  # half the side of a clamp marker
SCALE_BAR_PX = (4, 14)  # the scale bar's end ticks (half height) and the room its label takes above it


@dataclass(frozen=True)
class Track:
    """One run to show: its mesh, its states (steps, n, 2) and the per-step figures of the overlay:
    area_ratio and pressure as (steps, chambers), tip_dy as (steps,); color: a value per element
    (steps, m) to colour the body by (fields.py's element mean), named color_label."""

    mesh: Mesh
    states: np.ndarray
    area_ratio: np.ndarray
    pressure: np.ndarray
    tip_dy: np.ndarray
    title: str = ""
    ground: float | None = None  # height of the ground line y = ground, drawn when the scene has one
    targets: np.ndarray | None = None  # (steps, 2) inverse control's target point per frame: a cross and the tip's path
    color: np.ndarray | None = None
    color_label: str = ""
    target_index: np.ndarray | None = None  # (steps,) inverse control: the target a frame pursues
    descent: np.ndarray | None = None  # (steps,) inverse control: the descent a frame belongs to (restarts)
    chamber_names: tuple[str, ...] = ()  # for the trace panel's legend (several chambers)
    obstacles: tuple = ()  # per rigid obstacle: (outline (k, 2), closed, its offset (steps, 2) per step)
    units: tuple[str, str, str] = ("", "", "")  # the suffixes of a length, an area and a pressure (' mm', ...)
    area: np.ndarray | None = None  # (steps, chambers) the chambers' areas, shown in the header with units

    @classmethod
    def from_result(cls, result, title: str = "", color: str = "none") -> Track:
        """A track of a run (a solve.result.Result: every chamber of its scene, its ground line, a reach's
        targets from its target_x/target_y columns); color: 'none' or a COLOR_FIELDS key."""
        require(
            color == "none" or color in COLOR_FIELDS, f"color = {color!r} is not one of none, {', '.join(COLOR_FIELDS)}"
        )
        mesh, history = result.mesh, result.history
        values, label = None, ""
        if color != "none":
            label, key = COLOR_FIELDS[color]
            fields = mesh.fields
            values = np.array([fields.at(x)[key] for x in result.positions])
        targets = np.column_stack([history["target_x"], history["target_y"]]) if "target_x" in history else None
        return cls(
            mesh,
            result.positions,
            result.area_ratio,
            result.pressure,
            history["tip_dy"],
            title,
            result.ground_height,
            targets,
            values,
            label,
            history.get("target"),
            history.get("descent"),
            tuple(result.chamber_names),
            tuple(
                (*o.shape.outline(2 * float(np.ptp(mesh.vertices, axis=0).max())), offsets)
                for o in result.scene.obstacles
                for offsets in [np.array([o.offset(s.step)[:2] for s in result.steps])]
            ),
            tuple(result.scene.units.suffix(d) for d in (LENGTH, AREA, PRESSURE)),
            np.column_stack([history[f"{name}.area"] for name in result.chamber_names]),
        )

    def header(self, i: int) -> list[str]:
        """The lines above the body at step i (a title may have several, split at newlines). In a scene with
        units the areas, pressures and the tip's deflection say their unit; without, areas are area ratios.
        Chambers at one pressure over the whole run show it once ("p = 900.0 (all 6)"); more than HEADER_CHAMBERS
        chambers show their areas as a range ("x1.02 .. x1.31 (10)"), and their pressures too where they differ,
        so that the line stays clear of the trace panel."""
        length, area, pressure = self.units
        many = len(self.area_ratio[i]) > HEADER_CHAMBERS
        if area and self.area is not None:
            values, text, unit = self.area[i], "{:.4g}", area
        else:
            values, text, unit = self.area_ratio[i], "x{:.2f}", ""
        if many:
            areas = f"{text.format(values.min())} .. {text.format(values.max())}{unit} ({len(values)})"
        else:
            areas = ", ".join(text.format(v) for v in values) + unit
        shared = len(self.pressure[i]) > 1 and np.allclose(self.pressure, self.pressure[:, :1], rtol=1e-9, atol=0)
        pressures = (  # chambers at one pressure over the whole run (a PneuNet's): it once
            f"{number(self.pressure[i, 0], '.1f')}{pressure} (all {len(self.pressure[i])})"
            if shared
            else f"{number(self.pressure[i].min(), '.1f')} .. {number(self.pressure[i].max(), '.1f')}{pressure} "
            f"({len(self.pressure[i])})"
            if many
            else ", ".join(number(p, ".1f") for p in self.pressure[i]) + pressure
        )
        tip = f"{self.tip_dy[i]:+.4g}{length}" if length else f"{self.tip_dy[i]:+.4f}"
        return (self.title.split("\n") if self.title else []) + [
            f"step {i}/{len(self.states) - 1}   area {areas}",
            f"p = {pressures}   tip dy = {tip}",
        ]


class FrameRenderer:
    """Draws frame i of one or more tracks of equal length: beam panels side by side, a colour bar when
    the tracks are coloured, and a trace panel.

    width, height: frame size in pixels; trace: draw the area/pressure trace panel at the right;
    bounds: the world box (lo, hi) every panel must show, default the bounds of all states;
    canvas: draw on this canvas instead of opening one.
    """

    def __init__(
        self,
        tracks: list[Track],
        width: int = 960,
        height: int = 384,
        trace: bool = True,
        backend: str = "auto",
        log=print,
        canvas=None,
        bounds=None,
    ):
        require(len(tracks) >= 1, "nothing to render: no tracks")
        lengths = {len(t.states) for t in tracks}
        require(len(lengths) == 1, f"tracks have different step counts {sorted(lengths)}")
        self.tracks = tracks
        self.frames = lengths.pop()
        self.canvas = canvas or open_canvas(width, height, backend, log=log)
        self.width, self.height = self.canvas.width, self.canvas.height
        colored = [t.color for t in tracks if t.color is not None]
        self.color_range: tuple[float, float] | None = None
        if colored:
            values = np.concatenate([color.ravel() for color in colored])
            self.color_range = (float(values.min()), float(values.max()))
        self._art = [
            (
                mesh_edges(t.mesh, boundary_only=t.color is not None),
                t.mesh.display_triangles(),
                chamber_triangles(t.mesh),
            )
            for t in tracks
        ]
        # horizontal layout in normalised units: beam panels | colour bar | trace panel (left out when its
        # plot box would be too small to read, at a small --size)
        left, top, right, bottom = TRACE_MARGINS_PX
        self.trace = trace and (
            0.38 * self.width - left - right >= TRACE_MIN_BOX_PX[0]
            and self.height - top - bottom >= TRACE_MIN_BOX_PX[1]
        )
        trace_w = 0.38 if self.trace else 0.0
        bar_w = COLORBAR_PX / self.width if colored else 0.0
        beam_w = 1.0 - trace_w - bar_w
        n = len(tracks)
        self.panels = [(beam_w * i / n, beam_w * (i + 1) / n) for i in range(n)]
        self.colorbar_panel = (beam_w, beam_w + bar_w)
        self.trace_panel = (beam_w + bar_w, 1.0)
        # the same view whether a track has a title or not; a title of several lines takes more room
        lines = max([HEADER_LINES] + [len(t.header(0)) for t in tracks])
        self.header_px = MARGIN_PX + LINE_PX * lines
        self._lo, self._hi = (np.asarray(b, float) for b in (bounds if bounds is not None else view_bounds(tracks)))
        self._fit_view(self._lo, self._hi)
        self._ghosts = [mesh_edges(t.mesh, boundary_only=True) for t in tracks]
        self.scale_bar = self._place_scale_bar()

    def _fit_view(self, lo: np.ndarray, hi: np.ndarray) -> None:
        """One map world -> normalised canvas for every beam panel showing the box lo..hi, equal axes,
        below the header band."""
        centre, extent = (lo + hi) / 2, np.maximum(hi - lo, 1e-12)
        panel_px = np.array([(self.panels[0][1] - self.panels[0][0]) * self.width, self.height])
        usable = np.maximum(panel_px - 2 * MARGIN_PX - np.array([0, self.header_px]), 1.0)  # (a tiny frame: 1 px)
        self._scale = float(np.min(usable / extent))  # pixels per world unit
        self._centre, self._offset_px = centre, np.array([0.0, -self.header_px / 2])

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

    def _place_scale_bar(self) -> tuple[float, str, np.ndarray]:
        """(length, label, pixel box (left, top, right, bottom)) of the first panel's scale bar: scalebar.py's
        round length for the panel's width in world units, in the first corner (bottom left, bottom right, top
        left, top right, below the header) whose box holds no point of any step's body (else the one holding
        fewest)."""
        x0, x1 = (v * self.width for v in self.panels[0])
        length, label = scale_bar((x1 - x0) / self._scale, self.tracks[0].units[0])
        text = label_box(Label(label, 0, 0, "mb"))
        box_w = max(length * self._scale, text[2] - text[0]) + 8
        box_h = SCALE_BAR_PX[1] + SCALE_BAR_PX[0] + 6
        lefts, tops = (x0 + MARGIN_PX, x1 - MARGIN_PX - box_w), (self.height - MARGIN_PX - box_h, self.header_px)
        boxes = np.array([[left, top, left + box_w, top + box_h] for top in tops for left in lefts])
        points = np.concatenate([self.to_canvas(0, t.states.reshape(-1, 2)) for t in self.tracks])
        return length, label, boxes[emptiest(boxes, points * (self.width, self.height) * (1, -1) + (0, self.height))]

    def _draw_scale_bar(self) -> list[Label]:
        """The scale bar: a line of its length with end ticks at the bottom of its box, its label above."""
        length, text, (left, _, right, bottom) = self.scale_bar
        half, y = SCALE_BAR_PX[0], bottom - 4
        a, b = (left + right) / 2 - length * self._scale / 2, (left + right) / 2 + length * self._scale / 2
        bar = np.array([[[a, y], [b, y]], [[a, y - half], [a, y + half]], [[b, y - half], [b, y + half]]])
        self.canvas.segments(self._norm(bar), TEXT, 2.0)
        return [Label(text, (a + b) / 2, y - half - 2, "mb")]

    def frame(self, i: int) -> np.ndarray:
        """Frame i as an (height, width, 3) uint8 image, text included."""
        labels = self.draw(i)
        return draw_labels(self.canvas.image(), labels)

    def _draw_obstacle(self, panel: int, outline: np.ndarray, closed: bool) -> None:
        """A rigid obstacle: a closed (convex) outline filled as a fan from its centroid, then its edge; a plane's
        line as one segment."""
        x = self.to_canvas(panel, outline)
        if closed:
            centre = np.broadcast_to(x.mean(axis=0), x.shape)
            self.canvas.triangles(np.stack([centre, x, np.roll(x, -1, axis=0)], axis=1), OBSTACLE_FILL)
            self.canvas.segments(np.stack([x, np.roll(x, -1, axis=0)], axis=1), OBSTACLE, 2.0)
        else:
            self.canvas.segments(x[None], OBSTACLE, 3.0)

    def draw(self, i: int) -> list[Label]:
        """Draw frame i's shapes on the canvas; return its text labels (drawn by frame())."""
        require(0 <= i < self.frames, f"frame {i} is outside 0..{self.frames - 1}")
        c = self.canvas
        c.begin()
        labels = []
        for p, (track, (edges, faces, chamber)) in enumerate(zip(self.tracks, self._art)):
            x = self.to_canvas(p, track.states[i])
            if track.ground is not None:
                ends = self.to_canvas(p, np.array([[self._lo[0], track.ground], [self._hi[0], track.ground]]))
                c.segments(ends[None], GROUND, 3.0)
            for outline, closed, offsets in track.obstacles:
                self._draw_obstacle(p, outline + offsets[i], closed)
            rest = self.to_canvas(p, track.mesh.vertices)
            c.segments(rest[self._ghosts[p]], GHOST, 1.5)
            if track.color is None:
                c.triangles(x[faces], FACE)
                c.segments(x[edges], EDGE, 1.0)
            else:  # a quadratic element's four display triangles share its value (split_in_four's order)
                assert self.color_range is not None  # (set when a track is coloured)
                c.triangles(
                    x[faces], colormap(np.tile(track.color[i], len(faces) // len(track.color[i])), *self.color_range)
                )
                c.segments(x[edges], OUTLINE, 1.0)
            c.triangles(x[chamber], CHAMBER_FILL)
            for loop in track.mesh.chambers:
                c.segments(np.stack([x[loop], x[np.roll(loop, -1)]], axis=1), CHAMBER_WALL, 2.5)
            c.triangles(_squares(x[track.mesh.pinned], PIN_HALF_PX / np.array([self.width, self.height])), PIN)
            if track.targets is not None:
                self._draw_target(p, track, i)
            left = self.panels[p][0] * self.width + MARGIN_PX
            labels += [Label(line, left, MARGIN_PX / 2 + LINE_PX * k) for k, line in enumerate(track.header(i))]
        labels += self._draw_scale_bar()
        if self.color_range is not None:
            labels += self._draw_colorbar(*self.color_range)
        if self.trace:
            labels += self._draw_trace(i)
        return labels

    def _draw_target(self, panel: int, track: Track, i: int) -> None:
        """A cross at frame i's target; the tip (the mean of the tip vertices) where each earlier target was
        reached, joined in order (the trajectory); and as dots, the tip at the earlier equilibria of frame
        i's descent (Gauss-Newton's iterates: equilibria apart, not a path the tip moved along, so not
        joined; a restart begins a new descent)."""
        c = self.canvas
        tips = self.to_canvas(panel, track.states[: i + 1, track.mesh.tip].mean(axis=1))
        if track.target_index is not None:
            done = np.flatnonzero(np.diff(track.target_index[: i + 1]) != 0)  # the last frame of each earlier target
            if len(done) > 1:
                c.segments(np.stack([tips[done[:-1]], tips[done[1:]]], axis=1), TIP_PATH, 2.0)
            if len(done):
                c.triangles(_squares(tips[done], 4.0 / np.array([self.width, self.height])), TIP_PATH)
        same = np.ones(i, bool) if track.descent is None else track.descent[:i] == track.descent[i]
        if same.any():
            c.triangles(_squares(tips[:i][same], 2.0 / np.array([self.width, self.height])), TIP_PATH)
        assert track.targets is not None  # (drawn for a track with targets only)
        centre = self.to_canvas(panel, track.targets[i])
        arm = 9.0 / np.array([self.width, self.height])
        c.segments(
            np.array([[centre - arm, centre + arm], [centre + arm * (-1, 1), centre + arm * (1, -1)]]), TARGET, 3.0
        )

    def _draw_colorbar(self, lo: float, hi: float) -> list[Label]:
        """A vertical colour bar with numbered ticks over the colour range lo..hi."""
        c = self.canvas
        x0 = self.colorbar_panel[0] * self.width + 8
        top, bottom = self.header_px + LINE_PX + 4, self.height - MARGIN_PX - 8
        k = 64
        ys = np.linspace(bottom, top, k + 1)
        quads = np.array(
            [[[x0, a], [x0 + 14, a], [x0 + 14, b]] for a, b in zip(ys[:-1], ys[1:])]
            + [[[x0, a], [x0 + 14, b], [x0, b]] for a, b in zip(ys[:-1], ys[1:])]
        )
        colors = colormap(lo + (hi - lo) * (np.arange(k) + 0.5) / k, lo, hi)
        c.triangles(self._norm(quads), np.vstack([colors, colors]))
        labels = [
            Label(
                self.tracks[0].color_label
                if all(t.color_label == self.tracks[0].color_label for t in self.tracks)
                else "colour",
                x0 - 4,
                self.header_px,
            )
        ]
        for y, figure in colorbar_ticks(lo, hi, top, bottom):
            c.segments(self._norm(np.array([[[x0 + 14, y], [x0 + 19, y]]])), AXES, 1.0)
            labels.append(Label(figure, x0 + 22, y, "lm"))
        return labels

    def _norm(self, px: np.ndarray) -> np.ndarray:
        """Pixel coordinates (origin top-left) -> normalised canvas coordinates (origin bottom-left)."""
        return np.stack([px[..., 0] / self.width, 1 - px[..., 1] / self.height], axis=-1)

    def trace_axes(self) -> dict:
        """The trace panel's plot box in pixels (left, top, right, bottom) and its three axes as
        (lo, hi, ticks): 'step' (x), 'area' (left y), 'pressure' (right y); as many ticks as have room."""
        x0, x1 = (v * self.width for v in self.trace_panel)
        left, top, right, bottom = TRACE_MARGINS_PX
        box = (x0 + left, top, x1 - right, self.height - bottom)
        bins_x, bins_y = ((box[2] - box[0]) // TICK_ROOM_PX[0], (box[3] - box[1]) // TICK_ROOM_PX[1])
        axes = {
            "step": (
                0.0,
                float(self.frames - 1),
                nice_ticks(0, max(self.frames - 1, 1), integer=True, bins=min(5, bins_x)),
            )
        }
        for key, attr in (("area", "area_ratio"), ("pressure", "pressure")):
            values = np.concatenate([getattr(t, attr).ravel() for t in self.tracks])
            ticks = nice_ticks(float(values.min()), float(values.max()), bins=min(5, bins_y))
            axes[key] = (float(ticks[0]), float(ticks[-1]), ticks)
        return {"box": box, **axes}

    def chamber_colors(self) -> list[tuple] | None:
        """One colour per chamber when the tracks have several (matplotlib's tab10 cycle), else None: a
        single chamber's curves are coloured by quantity (area blue, pressure red)."""
        chambers = max(t.area_ratio.shape[1] for t in self.tracks)
        if chambers == 1:
            return None
        import matplotlib

        tab10 = matplotlib.colormaps["tab10"]  # a ListedColormap of 10 colours: tab10(k) is the k-th, RGBA
        return [tuple(tab10(k % tab10.N)[:3]) for k in range(chambers)]

    def _draw_trace(self, i: int) -> list[Label]:
        """Area / rest area (left axis) and pressure (right axis) of every chamber against the step, on
        numbered axes; cursor at step i. One chamber: two lines, area blue and pressure red. Several: each
        chamber in its own colour (named in a legend), its area ratio as a line, its pressure as dots; a
        quantity the same in every chamber (chambers on one supply) is drawn once, in black."""
        c, spec = self.canvas, self.trace_axes()
        left, top, right, bottom = spec["box"]
        corners = np.array([[left, bottom], [right, bottom], [right, top], [left, top]])
        c.segments(self._norm(np.stack([corners, np.roll(corners, -1, axis=0)], axis=1)), AXES, 1.0)
        to_x = lambda s: left + (right - left) * s / max(self.frames - 1, 1)

        def to_y(axis, v):
            lo, hi, _ = spec[axis]
            return bottom + (top - bottom) * (v - lo) / (hi - lo)

        per_chamber = self.chamber_colors()
        labels, ticks = [], []
        for s in spec["step"][2]:
            if 0 <= s <= self.frames - 1:
                ticks.append([[to_x(s), bottom], [to_x(s), bottom + 5]])
                labels.append(Label(f"{s:g}", to_x(s), bottom + 7, "mt"))
        labels.append(Label("step", (left + right) / 2, bottom + 7 + LINE_PX, "mt"))
        for axis, x, sign, anchor, color in (
            ("area", left, -1, "rm", AREA_CURVE),
            ("pressure", right, 1, "lm", PRESSURE_CURVE),
        ):
            for v in spec[axis][2]:
                ticks.append([[x, to_y(axis, v)], [x + 5 * sign, to_y(axis, v)]])
                labels.append(Label(tick_label(v), x + 7 * sign, to_y(axis, v), anchor, TEXT if per_chamber else color))
        c.segments(self._norm(np.array(ticks)), AXES, 1.0)
        steps = np.arange(self.frames)
        marker = 4.0 / np.array([self.width, self.height])
        shared = {}
        for track in self.tracks:
            for k in range(track.area_ratio.shape[1]):
                for axis, values in (("area", track.area_ratio[:, k]), ("pressure", track.pressure[:, k])):
                    every = track.area_ratio if axis == "area" else track.pressure
                    shared[axis] = per_chamber is not None and bool(np.all(every == every[:, :1]))
                    if shared[axis] and k > 0:
                        continue
                    pts = self._norm(np.column_stack([to_x(steps), to_y(axis, values)]))
                    if per_chamber is None:
                        color = AREA_CURVE if axis == "area" else PRESSURE_CURVE
                        c.segments(np.stack([pts[:-1], pts[1:]], axis=1), color, 2.0)
                    elif axis == "area":
                        color = TEXT if shared[axis] else per_chamber[k]
                        c.segments(np.stack([pts[:-1], pts[1:]], axis=1), color, 2.0)
                    else:
                        color = TEXT if shared[axis] else per_chamber[k]
                        c.triangles(_squares(pts, 0.5 * marker), color)
                    c.triangles(_squares(pts[i : i + 1], marker), color)
        c.segments(self._norm(np.array([[[to_x(i), bottom], [to_x(i), top]]])), CURSOR, 1.0)
        x_text = self.trace_panel[0] * self.width + MARGIN_PX
        if per_chamber is None:
            titles = [("area / rest area (left axis)", AREA_CURVE), ("pressure p (right axis)", PRESSURE_CURVE)]
        else:
            same = lambda axis: " (all, black)" if shared.get(axis) else ""
            titles = [(f"area / rest area{same('area')}: lines, left axis", TEXT)]
            titles += [(f"pressure p{same('pressure')}: dots, right axis", TEXT)]
        labels += [
            Label(text, x_text, MARGIN_PX / 2 + LINE_PX * k, color=color) for k, (text, color) in enumerate(titles)
        ]
        cursor = Label(f"cursor: step {i}", x_text, MARGIN_PX / 2 + 2 * LINE_PX)
        labels.append(cursor)
        if per_chamber is not None:
            labels += self._legend(cursor, per_chamber)
        return labels

    def _legend(self, after: Label, colors: list[tuple]) -> list[Label]:
        """The chambers' names in their colours, on the line of `after`, as many as fit in the panel."""
        x, edge = label_box(after)[2] + 12, self.width - MARGIN_PX
        labels = []
        for name, color in zip(self.tracks[0].chamber_names or [f"#{k + 1}" for k in range(len(colors))], colors):
            label = Label(name[:12], x, after.y, color=color)
            x = label_box(label)[2] + 8
            if x > edge:
                break
            labels.append(label)
        return labels


def _squares(centres: np.ndarray, half: np.ndarray) -> np.ndarray:
    """Two triangles (2k, 3, 2) per square marker of half-size `half` (normalised) at each centre."""
    lo, hi = centres - half, centres + half
    a, b, c, d = lo, np.column_stack([hi[:, 0], lo[:, 1]]), hi, np.column_stack([lo[:, 0], hi[:, 1]])
    return np.concatenate([np.stack([a, b, c], axis=1), np.stack([a, c, d], axis=1)])
