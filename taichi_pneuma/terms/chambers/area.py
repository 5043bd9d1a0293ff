"""Area control ("volume" control in 3D): the command is the area ratio r, held by a stiff penalty.

    E = 1/2 k (A(x) - A*)^2,   A* = r A_rest,   dE/dx = -p dA/dx,   p = k (A* - A),
    Hessian  k dA dA^T - p d2A,

a PSD rank-1 Gauss-Newton part, handed to the solver as a low-rank term, plus the wall's load
stiffness -p d2A. The load stiffness does not vanish at equilibrium (there A - A* = -p/k), so dropping
it would leave Newton converging only linearly. Past a limit point of the pressure-area curve area
control still has an equilibrium nearby (pressure control has not).

Sensitivity: dr/dr_cmd = d(-p dA/dx)/dr = -k A_rest dA/dx.
"""

from dataclasses import dataclass

import numpy as np

from ...errors import require, require_finite
from ...io.units import MEASURE_STIFFNESS, given, si_default
from .kind import KINDS, ChamberKind
from .wall import Chamber

MAX_AREA_RATIO = 1e3  # far past any rubber (the hard cases reach 8); keeps (A - A*)^2 from overflowing


@KINDS.register
@dataclass(frozen=True)
class AreaControl(ChamberKind):
    """Area control with penalty stiffness k > 0; commands are area ratios A* / A_rest in (0, MAX_AREA_RATIO]."""

    stiffness: float | None = si_default(1e5, MEASURE_STIFFNESS, scaled=False)  # None: 1e5 in unitless scenes
    name = "area"
    aliases = ("volume",)
    quantity = "area ratio"
    rest = 1.0

    def __post_init__(self):
        require(
            self.stiffness is None or require_finite("stiffness", self.stiffness) > 0,
            f"chamber stiffness k = {self.stiffness!r} must be > 0",
        )

    def check(self, what: str, values: list[float]) -> None:
        for value in values:
            require(0 < value <= MAX_AREA_RATIO, f"{what} area ratio {value!r} must lie in (0, {MAX_AREA_RATIO:g}]")

    def term(self, config, loop, name: str, order: int, origin=None) -> "AreaChamber":
        return AreaChamber(self, config, loop, name, order, origin)


class AreaChamber(Chamber):
    """Stiffness k pulls the enclosed area A(x) to target_area = command x rest area."""

    def __init__(self, kind: AreaControl, config, loop: np.ndarray, name: str = "main", order: int = 1, origin=None):
        super().__init__(kind, config, loop, name, order, origin)
        self.k = float(given(kind.stiffness, "area stiffness"))
        self.target_area = self.rest_area

    def set_command(self, ratio: float) -> None:
        """Command the area ratio A* / A_rest."""
        self.target_area = float(ratio) * self.rest_area

    def pressure_at(self, area: float) -> float:
        """p = k (A* - A): positive when the chamber pushes its walls outward."""
        return self.k * (self.target_area - area)

    def energy_at(self, area: float) -> float:
        return 0.5 * self.k * (area - self.target_area) ** 2

    def stiffness_at(self, area: float) -> float:
        return self.k

    def command_scale_at(self, area: float) -> float:
        """-dr/d(ratio) = k A_rest dA/dx."""
        return self.k * self.rest_area

    def describe(self, command: float, reached: float) -> str:
        return f"commanded area {command * self.rest_area:.6g} ({command:.4g} x rest)"
