"""Parts of the live page (realtime/web.py) that need no server: the colour bar's HTML, viser's console silenced,
the notebook iframe's height checked, a number from the page checked finite."""

from __future__ import annotations

import contextlib
import html
import math

import numpy as np

from ..errors import quoted, require
from ..render.colours import COLORMAP, colormap

HEIGHTS = (100, 4000)  # the notebook iframe's heights allowed (pixels)
BAR_STOPS = 16  # the colour bar's gradient: this many colours of the map, evenly spaced


def iframe_height(height) -> int:
    """A notebook iframe's height: an integer number of pixels in HEIGHTS."""
    require(
        isinstance(height, int) and not isinstance(height, bool) and HEIGHTS[0] <= height <= HEIGHTS[1],
        f"height {quoted(height)} is not an integer number of pixels in {HEIGHTS[0]} .. {HEIGHTS[1]}",
    )
    return height


def finite(value) -> bool:
    """Whether value is a finite number (an int or a float, not a bool)."""
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


@contextlib.contextmanager
def quiet_viser():
    """viser's own lines (its banner, "Server stopped") silenced while in the block: viser prints them with rich's
    console, which in a notebook kernel shows them in the cell's output through IPython's display, past sys.stdout;
    verbose=False only silences its connection lines. rich's console drops all it is given while quiet."""
    import rich

    console = rich.get_console()
    quiet, console.quiet = console.quiet, True
    try:
        yield
    finally:
        console.quiet = quiet


def colour_bar(label: str, lo: float, hi: float, suffix: str) -> str:
    """The colour bar under the figures, as HTML: the field's label over a strip of the colour map (BAR_STOPS of its
    colours, lo at the left end, hi at the right, colormap's own mapping of lo + t (hi - lo) for t = 0 .. 1), the
    range's ends under its ends, in the field's unit."""
    colours = colormap(np.linspace(lo, hi, BAR_STOPS), lo, hi)
    stops = ", ".join(
        f"#{r:02x}{g:02x}{b:02x} {100 * k / (BAR_STOPS - 1):.4g}%"
        for k, (r, g, b) in enumerate((colours * 255).round().astype(int))
    )
    end = "<span>{:.4g}{}</span>"
    return (
        f'<div style="font-size: 0.85em; padding: 0 0.75em">{html.escape(label)} ({COLORMAP})'
        f'<div style="height: 0.9em; border: 1px solid #888; background: linear-gradient(to right, {stops})"></div>'
        f'<div style="display: flex; justify-content: space-between">{end.format(lo, suffix)}{end.format(hi, suffix)}'
        "</div></div>"
    )
