"""Interactive 3D: a GGUI window with a slider per chamber and a camera orbiting the body.

Every frame calls the caller's solve function at the commands on screen (moved or not: a live solve takes a
step toward the equilibrium per frame and keeps converging while the sliders rest) and redraws the body;
dragging with the left mouse button outside the slider panel turns the camera about the body (a drag across
the whole window width: DRAG_DEGREES of azimuth; up and down: elevation, held short of the poles), and `spin`
turns it by that many degrees every frame. The window knows nothing of the solver: solve(commands) ->
(positions (n, 3), caption lines).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from ..backend import ti
from ..errors import require, require_finite
from ..render.camera import Camera
from ..render.colours import BACKGROUND
from ..render.frames3d import open_section, shaded_triangles
from ..render.ggui3d import GGUIView

DRAG_DEGREES = (360.0, 180.0)  # (azimuth, elevation) turned by a drag across the whole window
PANEL_WIDTH = 0.34  # the slider panel's width, as a share of the window's
ROW_HEIGHT_PX = 30


@dataclass(frozen=True)
class Slider:
    """A chamber's command slider: its name, range and starting value."""

    name: str
    low: float
    high: float
    value: float

    def __post_init__(self):
        low, high, value = (require_finite(f"slider {self.name!r}", v) for v in (self.low, self.high, self.value))
        require(
            low < high and low <= value <= high,
            f"slider {self.name!r}: need low < high and the value within, got {low:g}, {high:g}, {value:g}",
        )


def commands_from(sliders: list[Slider], shown: np.ndarray, values: list[float]) -> np.ndarray | None:
    """The new commands if the user moved a slider, else None: `values` as GGUI returns them (float32,
    clamped to each range here) compared with the commands on screen, to 1e-6 of each range."""
    low, high = np.array([s.low for s in sliders]), np.array([s.high for s in sliders])
    clipped = np.clip(np.asarray(values, dtype=float), low, high)
    return clipped if np.any(np.abs(clipped - shown) > 1e-6 * (high - low)) else None


def dragged(camera: Camera, start: tuple[float, float], end: tuple[float, float]) -> Camera:
    """The camera turned by a mouse drag from start to end (normalised window coordinates, origin bottom-left):
    rightwards turns the eye to the left round the body (the body seems to turn right), upwards lowers it."""
    dx, dy = end[0] - start[0], end[1] - start[1]
    return camera.orbit(-DRAG_DEGREES[0] * dx, -DRAG_DEGREES[1] * dy)


def in_panel(cursor: tuple[float, float], rows: int, height: int) -> bool:
    """Whether a cursor position (normalised, origin bottom-left) lies on the slider panel (top left)."""
    return cursor[0] <= PANEL_WIDTH and cursor[1] >= 1 - (rows + 1) * ROW_HEIGHT_PX / height


def explore_3d(
    solve,
    sliders: list[Slider],
    rest: np.ndarray,
    boundary: np.ndarray,
    chambers: tuple,
    size: tuple[int, int] = (960, 640),
    camera: Camera | None = None,
    spin: float = 0.0,
    section: bool = True,
    max_frames: int | None = None,
) -> dict:
    """Run the window until it is closed (or for max_frames frames). Returns {'solves' (slider moves, and the
    first solve), 'frames', 'fps' (frames per second over the frames after the first), 'commands', 'azimuth',
    'elevation'}."""
    width, height = size
    view = GGUIView(width, height, show=True)
    window, gui = view.window, view.window.get_gui()
    camera = (camera or Camera()).fitted(rest, width, height, margin=0.2)
    walls = np.concatenate(chambers) if len(chambers) else np.zeros((0, 3), np.int64)
    cut = open_section(rest, boundary, walls, camera) if section and len(chambers) else None  # the surface clipped
    shown = np.array([s.value for s in sliders], dtype=float)
    x, caption = solve(shown)
    solves, frames, seconds, last = 1, 0, 0.0, None
    print(f"interactive: {len(sliders)} sliders (top left); drag to turn the view; close the window to quit")
    try:
        while window.running and (max_frames is None or frames < max_frames):
            start = time.perf_counter()
            with gui.sub_window("chambers", 0.0, 0.0, PANEL_WIDTH, (len(sliders) + 1) * ROW_HEIGHT_PX / height):
                values = [gui.slider_float(s.name, float(v), s.low, s.high) for s, v in zip(sliders, shown)]
                for line in caption:
                    gui.text(line)
            moved = commands_from(sliders, shown, values)
            if moved is not None:
                shown = moved
                solves += 1
            x, caption = solve(shown)
            cursor_x, cursor_y = window.get_cursor_pos()
            cursor = (float(cursor_x), float(cursor_y))
            pressed = window.is_pressed(ti.ui.LMB)
            if pressed and last is not None:
                camera = dragged(camera, last, cursor)
            last = cursor if pressed and not in_panel(cursor, len(sliders), height) else None
            camera = camera.orbit(spin, 0.0)
            if cut is None:
                view.draw(*shaded_triangles(x, boundary, walls, camera), camera, BACKGROUND)
            else:
                view.draw(*shaded_triangles(cut.points(x), cut.surface, cut.walls, camera), camera, BACKGROUND)
            window.show()
            if frames:
                seconds += time.perf_counter() - start
            frames += 1
    finally:
        view.close()
    return {
        "solves": solves,
        "frames": frames,
        "fps": (frames - 1) / seconds if seconds else None,
        "commands": shown.tolist(),
        "azimuth": camera.azimuth,
        "elevation": camera.elevation,
    }
