"""Text on a frame: labels at pixel positions, written onto the finished image (Pillow, matplotlib's DejaVu
Sans), the same whichever canvas drew the shapes."""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache, lru_cache
from pathlib import Path

import numpy as np

from .colours import TEXT

FONT_PX, LINE_PX = 13, 17  # the font size and a line of text's height
MARGIN_PX = 10  # the margin text and panels keep from the frame's edges


def number(value: float, spec: str) -> str:
    """value formatted by spec, a zero never signed ('-0.0' from -0.0 or -0.01 at '.1f' reads '0.0'; a padded one
    keeps its width)."""
    text = f"{value:{spec}}"
    if text.lstrip().startswith("-") and float(text) == 0:
        return text.replace("-", " " if text.startswith(" ") else "", 1)
    return text


@dataclass(frozen=True)
class Label:
    """A line of text at pixel (x, y) (origin top-left); anchor as Pillow's: 'la' left-ascender, 'rm'
    right-middle, 'mt' middle-top, ..."""

    text: str
    x: float
    y: float
    anchor: str = "la"
    color: tuple = TEXT


@cache  # a memo: the font file matplotlib ships does not change
def _font():
    import matplotlib
    from PIL import ImageFont

    return ImageFont.truetype(str(Path(matplotlib.get_data_path()) / "fonts" / "ttf" / "DejaVuSans.ttf"), FONT_PX)


def label_box(label: Label) -> tuple[float, float, float, float]:
    """The pixel box (left, top, right, bottom) the label's text covers."""
    from PIL import Image, ImageDraw

    return ImageDraw.Draw(Image.new("RGB", (1, 1))).textbbox(
        (label.x, label.y), label.text, font=_font(), anchor=label.anchor
    )


@lru_cache(maxsize=4096)  # a memo of (text, anchor) in the one font, its array read-only: shared by every call
def _coverage(text: str, anchor: str) -> tuple[np.ndarray, int, int]:
    """The text's glyph coverage (h, w) in [0, 1] (a read-only array), drawn with its anchor at the origin, and the
    offset of its top-left pixel from the anchor point. Cached: most labels (axis numbers, titles) repeat every
    frame."""
    from PIL import Image, ImageDraw

    left, top, right, bottom = _font().getbbox(text, anchor=anchor)
    mask = Image.new("L", (max(right - left, 1), max(bottom - top, 1)))
    ImageDraw.Draw(mask).text((-left, -top), text, fill=255, font=_font(), anchor=anchor)
    coverage = np.asarray(mask, dtype=np.float32) / 255
    coverage.flags.writeable = False
    return coverage, left, top


def draw_labels(image: np.ndarray, labels: list[Label]) -> np.ndarray:
    """The image (height, width, 3) uint8 with the labels written on it (blended in place by glyph coverage,
    each label at its anchor rounded to a pixel)."""
    height, width = image.shape[:2]
    for label in labels:
        alpha, left, top = _coverage(label.text, label.anchor)
        x0, y0 = int(round(label.x)) + left, int(round(label.y)) + top
        h, w = alpha.shape
        cx0, cy0, cx1, cy1 = max(x0, 0), max(y0, 0), min(x0 + w, width), min(y0 + h, height)
        if cx0 >= cx1 or cy0 >= cy1:
            continue
        a = alpha[cy0 - y0 : cy1 - y0, cx0 - x0 : cx1 - x0, None]
        region = image[cy0:cy1, cx0:cx1].astype(np.float32)
        color = np.array(label.color, dtype=np.float32) * 255
        image[cy0:cy1, cx0:cx1] = (region + (color - region) * a + 0.5).astype(np.uint8)
    return image
