"""Pressure control: the command is the pressure p itself, whose work on the wall is the energy.

    E = -p A(x),   dE/dx = -p dA/dx,   Hessian -p d2A (the wall's load stiffness, no PSD part).

Past a limit point of the pressure-area curve there is no nearby equilibrium (ballooning, snap-through).

Sensitivity: dr/dp = -dA/dx.
"""

from dataclasses import dataclass

import numpy as np

from ...errors import require
from .kind import KINDS, ChamberKind
from .wall import Chamber


@KINDS.register
@dataclass(frozen=True)
class PressureControl(ChamberKind):
    """Pressure control; a pressure below zero (suction) is refused unless allow_vacuum is set."""

    allow_vacuum: bool = False
    name = "pressure"
    quantity = "pressure"
    rest = 0.0
    dimension = "pressure"

    def check(self, what: str, values: list[float]) -> None:
        for value in values:
            require(
                value >= 0 or self.allow_vacuum,
                f"{what} pressure {value!r} is negative; set allow_vacuum = true for suction",
            )

    def term(self, config, loop, name: str, order: int, origin=None) -> "PressureChamber":
        return PressureChamber(self, config, loop, name, order, origin)


class PressureChamber(Chamber):
    """A prescribed pressure p does work p A(x) on the wall."""

    def __init__(
        self, kind: PressureControl, config, loop: np.ndarray, name: str = "main", order: int = 1, origin=None
    ):
        super().__init__(kind, config, loop, name, order, origin)
        self.prescribed = 0.0

    def set_command(self, pressure: float) -> None:
        """Command the pressure p."""
        self.prescribed = float(pressure)

    def pressure_at(self, area: float) -> float:
        return self.prescribed

    def pressure(self) -> float:
        return self.prescribed

    def energy_at(self, area: float) -> float:
        return -self.prescribed * area

    def command_scale_at(self, area: float) -> float:
        """-dr/dp = dA/dx."""
        return 1.0
