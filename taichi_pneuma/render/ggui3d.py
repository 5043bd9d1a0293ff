"""3D views drawn by Taichi GGUI's scene (Vulkan; on CPU-only machines mesa's lavapipe provides it).

The triangles arrive already shaded (render.surface.shade_faces): each gets three vertices of its own
(so a face keeps its flat shade) coloured per corner, under a white ambient light and no other light,
so GGUI only rasterises: the same camera (render.camera: GGUI's eye, look-at point, y up and vertical
field of view) and the same colours as the NumPy rasteriser, pixel for pixel up to edge rounding.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np

from .. import runtime
from ..backend import ti
from .camera import Camera
from .surface import NumpyView

IMGUI_INI = Path("imgui.ini")  # where imgui (GGUI's widgets) saves its settings: the current folder
BLANK_RETRIES = 2  # draws again of a frame that came back blank before the NumPy rasteriser draws it


class GGUIView:
    """An offscreen (or shown) GGUI window of (width, height) pixels drawing shaded triangles."""

    name = "GGUI 3D scene (Vulkan)"

    def __init__(self, width: int, height: int, show: bool = False, title: str = "taichi-pneuma 3D"):
        runtime.ensure_initialised()
        self.width, self.height = width, height
        # imgui saves its window settings into the current folder when a window closes: an offscreen one leaves none
        self._imgui_ini = None if show or IMGUI_INI.exists() else IMGUI_INI.resolve()
        self.window = ti.ui.Window(title, (width, height), show_window=show, vsync=False)
        self.canvas = self.window.get_canvas()
        self.scene = self.window.get_scene()
        self.camera = ti.ui.Camera()
        self._fields: dict[tuple[str, int], ti.Field] = {}
        self.blank_frames = 0  # frames GGUI gave back blank, drawn by the NumPy rasteriser instead (render)

    def _field(self, name: str, values: np.ndarray):
        """A float32 3-vector field holding values (k, 3), reused while k stays the same."""
        key = (name, len(values))
        if key not in self._fields:
            self._fields[key] = ti.Vector.field(3, ti.f32, len(values))
        self._fields[key].from_numpy(values.astype(np.float32))
        return self._fields[key]

    def draw(self, corners: np.ndarray, colors: np.ndarray, camera: Camera, background) -> None:
        """Put world triangles (f, 3, 3) with corner colours (f, 3, 3) on the canvas, seen by camera."""
        # GGUI's own staging kernels warn "f32 <- f64" when compiled under default_fp=f64; they are harmless
        ti.set_logging_level(ti.ERROR)
        self.camera.position(*camera.eye)
        self.camera.lookat(*camera.target)
        self.camera.up(0.0, 1.0, 0.0)
        self.camera.fov(camera.fov)
        self.camera.z_near(1e-3 * camera.distance)
        self.camera.z_far(1e3 * camera.distance)
        self.scene.set_camera(self.camera)
        self.scene.ambient_light((1.0, 1.0, 1.0))
        if len(corners):
            with warnings.catch_warnings():  # GGUI's normals kernel casts its f64 loop bound to i32: harmless
                warnings.simplefilter("ignore")
                self.scene.mesh(
                    self._field("vertices", corners.reshape(-1, 3)),
                    per_vertex_color=self._field("colors", colors.reshape(-1, 3)),
                    two_sided=True,
                )
        self.canvas.set_background_color(tuple(background))
        self.canvas.scene(self.scene)

    def render(self, corners: np.ndarray, colors: np.ndarray, camera: Camera, background) -> np.ndarray:
        """The (height, width, 3) float image of the triangles (draw(), then read back). Under load lavapipe has
        been seen to hand back a frame of background only, the triangles missing: a frame with triangles in view
        that comes back blank is drawn again (up to BLANK_RETRIES times), then by the NumPy rasteriser, so that a
        picture never silently lacks the body."""
        pixels, depth = camera.project(corners.reshape(-1, 3), self.width, self.height)
        inside = (depth > 0) & np.all((pixels >= 0) & (pixels < (self.width, self.height)), axis=-1)
        visible = bool(inside.any())  # a triangle corner in view: the frame cannot be background only
        for _ in range(1 + BLANK_RETRIES):
            self.draw(corners, colors, camera, background)
            image = np.clip(np.rot90(self.window.get_image_buffer_as_numpy()[:, :, :3]).astype(float), 0.0, 1.0)
            ti.set_logging_level(ti.WARN)
            if not visible or np.abs(image - np.asarray(background, float)).max() > 1.5 / 255:
                return image
        self.blank_frames += 1
        return NumpyView(self.width, self.height).render(corners, colors, camera, background)

    def close(self) -> None:
        """Destroy the window now (GGUI allows one live window per process), and the imgui.ini it wrote into the
        current folder if it was offscreen and the file was not there before."""
        self.window.destroy()
        if self._imgui_ini is not None:
            self._imgui_ini.unlink(missing_ok=True)
