"""A run's history as a matplotlib figure with axes: six panels, one curve per chamber where there are several.

    pressure against area ratio        tip deflection against the command   bending angle (and twist) against p
    area ratio against the command     pressure against the command         extension (and blocked force) against p

The last column is what an actuator is judged by, against the pressure p of the first chamber: the bending
angle (tip_rotation) and, in 3D, the twist about the body's axis (tip_twist); the axial extension (tip_dx) and,
when the scene has obstacles, the blocked force (blocked_force, on its own axis at the right).

"The command" is the chambers' commanded value (area ratio or pressure) when every chamber gets the
same command at every step (one chamber, or chambers driven together); otherwise the step. In a scene
with units every axis with a dimension says its unit ("pressure p [kPa]").
"""

from __future__ import annotations

import io
import warnings

import numpy as np
from matplotlib.figure import Figure

from ..io.units import ANGLE, FORCE, LENGTH, PRESSURE, in_dimension


def command_axis(command: np.ndarray, quantities: list[str]) -> tuple[np.ndarray, str]:
    """The x values and label of the 'against the command' panels: command (steps, chambers) and what each
    chamber's command is (its kind's quantity: 'area ratio', 'pressure'); see the module docstring."""
    if len(set(quantities)) == 1 and np.all(command == command[:, :1]):
        return command[:, 0], f"commanded {quantities[0]}"
    return np.arange(len(command), dtype=float), "step"


class NotebookFigure(Figure):
    """A matplotlib Figure made without pyplot (no global state, nothing left open) that a notebook shows:
    IPython displays an object's _repr_png_."""

    def _repr_png_(self) -> bytes:
        buffer = io.BytesIO()
        self.savefig(buffer, format="png", dpi=100)
        return buffer.getvalue()


# the four panels' margins and gaps on the 10 x 7 inch figure, fixed: matplotlib's constrained layout
# would find them itself, at twice the time of the whole plot (0.75 against 1.7 s measured)
# the ratio a chamber's axis shows, and what it measures, by the body's dimension
RATIO = {2: ("area ratio A / A_rest", "area"), 3: ("volume ratio V / V_rest", "volume")}
LAYOUT = dict(left=0.05, right=0.95, bottom=0.07, top=0.89, wspace=0.3, hspace=0.35)


def history_figure(result, figure=None):
    """Draw the history of an api.Result on `figure` (a new NotebookFigure, laid out by LAYOUT, by default)."""
    fig = figure if figure is not None else NotebookFigure(figsize=(15, 7))
    if figure is None:
        fig.subplots_adjust(**LAYOUT)
    (pa, tip, bending), (area, pressure, extension) = fig.subplots(2, 3)
    units, kinds = result.scene.units, [c.kind for c in result.scene.controls]
    x, x_label = command_axis(result.command, [kind.quantity for kind in kinds])
    x_label = x_label if x_label == "step" else units.label(x_label, in_dimension(kinds[0].dimension, result.mesh.dim))
    pressure_label = units.label("pressure p", PRESSURE)
    for c, name in enumerate(result.chamber_names):
        pa.plot(result.area_ratio[:, c], result.pressure[:, c], ".-", label=short(name))
        area.plot(x, result.area_ratio[:, c], ".-", label=short(name))
        pressure.plot(x, result.pressure[:, c], ".-", label=short(name))
    tip.plot(x, result.history["tip_dy"], ".-", color="k")
    ratio, measure = RATIO[result.mesh.dim]
    for ax, xl, yl, title in (
        (pa, ratio, pressure_label, f"pressure against {measure} ratio"),
        (tip, x_label, units.label("tip deflection dy", LENGTH), "tip deflection (mean y displacement of the tip)"),
        (area, x_label, ratio, f"chamber {measure}"),
        (pressure, x_label, pressure_label, "chamber pressure"),
    ):
        ax.set(xlabel=xl, ylabel=yl, title=title)
        ax.grid(True, alpha=0.3)
    if len(result.chamber_names) > 1:
        pa.legend(fontsize="small")
    actuator_panels(result, bending, extension)
    fig.suptitle(short(result.scene.name, 80))
    return fig


def actuator_panels(result, bending, extension) -> None:
    """Draw the bending angle and twist (on `bending`) and the extension and blocked force (on `extension`, the force
    on a twin axis) against the first chamber's pressure (module docstring)."""
    units, history = result.scene.units, result.history
    names = result.chamber_names
    x = result.pressure[:, 0]
    x_label = units.label("pressure p" + (f" of {short(names[0])}" if len(names) > 1 else ""), PRESSURE)
    bending.plot(x, history["tip_rotation"], ".-", color="k", label="bending angle")
    if "tip_twist" in history:
        bending.plot(x, history["tip_twist"], ".-", color="tab:orange", label="twist about x")
        bending.legend(fontsize="small")
    extension.plot(x, history["tip_dx"], ".-", color="k")
    for ax, yl, title in (
        (
            bending,
            units.label("angle", ANGLE),
            "bending angle (tip rotation)" + (" and twist" if "tip_twist" in history else ""),
        ),
        (extension, units.label("extension dx", LENGTH), "axial extension (mean x displacement of the tip)"),
    ):
        ax.set(xlabel=x_label, ylabel=yl, title=title)
        ax.grid(True, alpha=0.3)
    if "blocked_force" in history:
        force = extension.twinx()
        force.plot(x, history["blocked_force"], ".-", color="tab:red")
        force.set_ylabel(units.label("blocked force", FORCE), color="tab:red")
        extension.set_title("extension, and the force on the obstacles (red)")


def short(text: str, most: int = 24) -> str:
    """A name for a legend or title: cut to `most` characters, unprintable characters (tabs, ...) as '?'."""
    text = "".join(c if c.isprintable() else "?" for c in text)
    return text if len(text) <= most else text[: most - 3] + "..."


def save_history_png(result, path) -> None:
    """Write the history figure to path (PNG). A name's character without a glyph in the font is drawn as
    a box; matplotlib says so each time, but the figure is still whole, so it is not passed on as a warning."""
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message="Glyph .* missing from font")
        history_figure(result).savefig(path, dpi=100, format="png")
