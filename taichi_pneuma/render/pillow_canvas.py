"""A canvas that needs no Taichi GUI: Pillow draws the frame's triangles and segments into an RGB image.

It has the primitives of the canvases in canvases.py, so FrameRenderer draws the same picture on it; it is
the renderer where neither Taichi GUI exists (Quadrants has neither). Offscreen only: a live window refuses it.
"""

from __future__ import annotations

import numpy as np
from PIL import Image, ImageDraw

from ..errors import PneumaInputError
from .colours import BACKGROUND


class PillowCanvas:
    """Pillow's ImageDraw on an RGB image of (width, height) pixels, drawn SUPERSAMPLE times larger and
    averaged down (anti-aliased edges, line widths in fractions of a pixel); offscreen only."""

    name = "Pillow (software)"
    slider_row_px = 0
    SUPERSAMPLE = 3

    def __init__(self, width: int, height: int, show: bool = False):
        if show:
            raise PneumaInputError("the Pillow renderer draws offscreen only and opens no window")
        self.width, self.height = width, height
        self._background = _rgb8(BACKGROUND)
        self._picture = Image.new("RGB", (width * self.SUPERSAMPLE, height * self.SUPERSAMPLE), self._background)
        self._draw = ImageDraw.Draw(self._picture)

    def begin(self) -> None:
        self._draw.rectangle((0, 0, *self._picture.size), fill=self._background)

    def _pixels(self, points: np.ndarray) -> np.ndarray:
        """Normalised points (..., 2), origin bottom-left -> coordinates on the large image, origin top-left
        (Pillow samples its pixel k at coordinate k: pixel i of the frame, [i, i + 1), is large pixels
        S i .. S i + S - 1 at coordinates S x - 1/2)."""
        pixels = np.stack([points[..., 0] * self.width, (1.0 - points[..., 1]) * self.height], axis=-1)
        return pixels * self.SUPERSAMPLE - 0.5

    def triangles(self, corners: np.ndarray, color) -> None:
        """corners (m, 3, 2); color: one RGB, or one RGB per triangle (m, 3)."""
        color = np.asarray(color, dtype=float)
        polygon, flat = self._draw.polygon, self._pixels(corners).reshape(-1, 6).tolist()
        if color.ndim == 1:
            fill = _rgb8(color)
            for triangle in flat:
                polygon(triangle, fill=fill)
        else:
            for triangle, fill in zip(flat, map(tuple, np.rint(255 * color).astype(int).tolist())):
                polygon(triangle, fill=fill)

    def segments(self, ends: np.ndarray, color, width_px: float) -> None:
        """ends (k, 2, 2): each segment's two ends; width_px: the line width in pixels."""
        fill, width, line = _rgb8(color), max(1, int(round(width_px * self.SUPERSAMPLE))), self._draw.line
        for segment in self._pixels(ends).reshape(-1, 4).tolist():
            line(segment, fill=fill, width=width)

    def image(self) -> np.ndarray:
        """The frame as an (height, width, 3) uint8 image, top row first."""
        return np.array(self._picture.reduce(self.SUPERSAMPLE))  # writable: draw_labels blends in place

    def close(self) -> None:
        pass


def _rgb8(color) -> tuple[int, ...]:
    return tuple(int(round(255 * c)) for c in color)
