"""The canvases a 2D frame is drawn on: (width, height) pixels, coordinates normalised to [0, 1], origin
bottom-left, with the same primitives (filled triangles, line segments) on each:
- ti.GUI(show_gui=False), Taichi's software rasteriser: the default ('auto'), the faster one measured;
- GGUI, ti.ui.Window (offscreen unless shown), on request, where Vulkan works (on CPU-only machines mesa's
  lavapipe, apt-get install mesa-vulkan-drivers, provides it, with ti.cpu);
- Pillow (pillow_canvas.py) where the backend has neither GUI (Quadrants), or when asked for.
open_canvas picks one; a shown canvas is a live window (sliders, the mouse)."""

from __future__ import annotations

import numpy as np

from .. import runtime
from ..backend import INSTALL, NAME, VERSION, has_ggui, has_gui, ti
from ..errors import PneumaInputError, require
from . import RENDERERS
from .colours import BACKGROUND


class GGUICanvas:
    """Taichi GGUI (Vulkan) window; offscreen unless show=True."""

    name = "GGUI (Vulkan)"
    slider_row_px = 45  # each slider takes a row this high at the bottom of the window

    def __init__(self, width: int, height: int, show: bool = False, title: str = "taichi-pneuma"):
        self.width, self.height = width, height
        self.window = ti.ui.Window(title, (width, height), show_window=show, vsync=False)
        self.canvas = self.window.get_canvas()
        self._fields: dict[tuple[int, int, int], ti.Field] = {}
        self._calls = 0

    def begin(self) -> None:
        # GGUI's own staging kernels warn "f32 <- f64" when compiled under default_fp=f64; they are harmless.
        ti.set_logging_level(ti.ERROR)
        self.canvas.set_background_color(BACKGROUND)
        self._calls = 0

    def _field(self, values: np.ndarray):
        """A float32 vector field holding values (k, 2 or 3); one per draw call, reused frame to frame."""
        key = (self._calls, len(values), values.shape[1])
        self._calls += 1
        if key not in self._fields:
            self._fields[key] = ti.Vector.field(values.shape[1], ti.f32, len(values))
        field = self._fields[key]
        field.from_numpy(values.astype(np.float32))
        return field

    def triangles(self, corners: np.ndarray, color) -> None:
        """corners (m, 3, 2); color: one RGB, or one RGB per triangle (m, 3)."""
        color = np.asarray(color, dtype=float)
        points = self._field(corners.reshape(-1, 2))
        if color.ndim == 1:
            self.canvas.triangles(points, color=tuple(color))
        else:
            self.canvas.triangles(points, per_vertex_color=self._field(np.repeat(color, 3, axis=0)))

    def segments(self, ends: np.ndarray, color, width_px: float) -> None:
        self.canvas.lines(self._field(ends.reshape(-1, 2)), width_px / self.height, color=tuple(color))

    def image(self) -> np.ndarray:
        image = _to_rgb8(self.window.get_image_buffer_as_numpy())
        ti.set_logging_level(ti.WARN)
        return image

    def show_image(self, image: np.ndarray) -> None:
        """Put an (height, width, 3) uint8 image on the canvas (for a shown window)."""
        self.canvas.set_image(_from_rgb8(image))

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

    def close(self) -> None:
        """Destroy the window now (GGUI allows one live window per process; garbage collection may come late)."""
        self.window.destroy()


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
        """corners (m, 3, 2); color: one RGB, or one RGB per triangle (m, 3)."""
        self.gui.triangles(corners[:, 0], corners[:, 1], corners[:, 2], color=_hex(color))

    def segments(self, ends: np.ndarray, color, width_px: float) -> None:
        self.gui.lines(ends[:, 0], ends[:, 1], radius=width_px / 2, color=_hex(color))

    def image(self) -> np.ndarray:
        return _to_rgb8(self.gui.get_image())

    def show_image(self, image: np.ndarray) -> None:
        """Put an (height, width, 3) uint8 image on the canvas (for a shown window)."""
        self.gui.set_image(_from_rgb8(image))

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

    def close(self) -> None:
        self.gui.close()


def _hex(color):
    """RGB in [0, 1] -> 0xRRGGBB: an int for one colour (3,), a uint32 array for one per row (k, 3)."""
    r, g, b = np.rint(255 * np.asarray(color, dtype=float)).astype(np.uint32).T
    packed = (r << 16) | (g << 8) | b
    return int(packed) if packed.ndim == 0 else packed


def _to_rgb8(buffer: np.ndarray) -> np.ndarray:
    """(width, height, 4) float buffer, origin bottom-left -> (height, width, 3) uint8, top row first.

    The canvases hold colours c = k / 255 (ti.GUI: the 8-bit colours it was given; GGUI: an 8-bit image),
    so floor(255.99 c) is k again, without a rounding or clipping pass (a value a little past 0 or 1
    still lands on 0 or 255). The whole RGBA buffer is converted (contiguous: faster than its RGB view)
    and turned upright by Pillow (2.4 against 4.7-6.6 ms a 960x384 frame with NumPy's transpose)."""
    from PIL import Image

    rgba = Image.fromarray((buffer * np.float32(255.99)).astype(np.uint8), "RGBA")
    return np.array(rgba.transpose(Image.Transpose.ROTATE_90).convert("RGB"))


def _from_rgb8(image: np.ndarray) -> np.ndarray:
    """The inverse of _to_rgb8: (height, width, 3), top row first -> (width, height, 3), origin bottom-left."""
    return np.ascontiguousarray(np.rot90(image, -1))


def open_canvas(width: int, height: int, backend: str = "auto", show: bool = False, log=print):
    """A canvas on `backend`: 'gui' (ti.GUI's software rasteriser), 'ggui' (GGUI on Vulkan; PneumaInputError
    when Vulkan is unavailable), 'pillow' (pillow_canvas.py) or 'auto': ti.GUI, the faster of the two Taichi
    canvases wherever measured (the frame is read back to the CPU for its text and the encoder, and on lavapipe
    GGUI's read-back alone costs more than ti.GUI's whole frame; see docs/performance.md), else
    Pillow where the Taichi backend has no GUI. Says through log() which it uses (and why it fell back)."""
    require(backend in RENDERERS, f"renderer = {backend!r} is not one of {', '.join(RENDERERS)}")
    require(width >= 64 and height >= 64, f"frame size {width}x{height} must be at least 64x64")
    runtime.ensure_initialised()
    if backend == "pillow" or not (has_ggui() or has_gui()):
        from .pillow_canvas import PillowCanvas

        missing = f"Taichi's GUI (ti.GUI or GGUI), which {NAME} {VERSION} does not have"
        require(backend in ("auto", "pillow"), f"renderer = {backend!r} needs {missing}: use --renderer pillow")
        require(
            not show or backend == "pillow",
            f"a live window needs {missing}: install taichi "
            f"({INSTALL['taichi']}; Python < 3.14, not Linux aarch64) and run with PNEUMA_BACKEND=taichi",
        )
        pillow = PillowCanvas(width, height, show)
        log(f"renderer: {pillow.name}" + ("" if backend == "pillow" else f" ({NAME} has no GUI)"))
        return pillow
    canvas: GGUICanvas | GUICanvas
    if backend == "ggui" or (backend == "auto" and not has_gui()):
        try:
            canvas = GGUICanvas(width, height, show)
        except RuntimeError as exc:
            raise PneumaInputError(f"renderer = 'ggui' is unavailable: {exc}") from None
    else:
        canvas = GUICanvas(width, height, show)
    log(f"renderer: {canvas.name}")
    return canvas
