"""A closed gas chamber: a worked example of a new chamber kind (docs/extending.md), registered on import.

The chamber holds an isothermal ideal gas, n R T fixed by the command q, the amount of gas relative
to that which fills the rest chamber at atmospheric pressure p_atm: n R T = q p_atm A_rest. Then

    E = -n R T ln A + p_atm A,   p = n R T / A - p_atm (gauge),   dE/dx = -p dA/dx,
    Hessian  n R T / A^2 dA dA^T - p d2A,      -dr/dq = p_atm A_rest / A dA/dx.
"""

import math
from dataclasses import dataclass

from taichi_pneuma.errors import require, require_finite
from taichi_pneuma.terms.chambers import Chamber, ChamberKind, register


@register
@dataclass(frozen=True)
class ClosedGas(ChamberKind):
    """A sealed chamber of ideal gas at ambient pressure `atmosphere` (the scene's pressure unit)."""

    atmosphere: float = 101325.0
    name = "closed_gas"
    quantity = "gas amount"
    rest = 1.0

    def __post_init__(self):
        require(require_finite("atmosphere", self.atmosphere) > 0, f"atmosphere = {self.atmosphere!r} must be > 0")

    def check(self, what, values):
        for value in values:
            require(value > 0, f"{what} gas amount {value!r} must be > 0")

    def term(self, config, loop, name, order, origin=None):
        return ClosedGasChamber(self, config, loop, name, order, origin)


class ClosedGasChamber(Chamber):
    def __init__(self, kind, config, loop, name="main", order=1, origin=None):
        super().__init__(kind, config, loop, name, order, origin)
        self.set_command(kind.rest)

    def set_command(self, amount):
        self.nrt = float(amount) * self.kind.atmosphere * self.rest_area

    def pressure_at(self, area):
        return self.nrt / area - self.kind.atmosphere

    def energy(self):
        area = self.area()
        return -self.nrt * math.log(area) + self.kind.atmosphere * area if area > 0 else math.inf

    def low_rank(self):
        area, gradient = self.area_and_gradient()
        return [(self.dofs, gradient.ravel(), self.nrt / area ** 2)]

    def command_force(self):
        area, gradient = self.area_and_gradient()
        return self.kind.atmosphere * self.rest_area / area * gradient.ravel()
