"""Closed gas chamber: a sealed amount of air, compressed isothermally (gamma = 1) or adiabatically (gamma = 1.4).

The command q is the air pumped into the sealed chamber, as the volume it occupies at atmospheric
pressure p_atm; at q = 0 (rest) the chamber holds its own rest volume of air at p_atm, no gauge pressure.
The air, V_atm = A_rest + q of it measured at p_atm, fills the gas volume G = A + c: the chamber's area A
(its volume per unit depth in 2D) plus c, gas volume outside the chamber (none here; a syringe's tube and
barrel in syringe.py). The polytropic law p_abs G^gamma = p_atm V_atm^gamma gives the gauge pressure
p = p_abs - p_atm and the energy of the gas and of the atmosphere it displaces,

    E = -p_atm V_atm ln G + p_atm A                                    (gamma = 1: p_abs G = n R T)
    E = p_atm V_atm^gamma G^(1 - gamma) / (gamma - 1) + p_atm A        (gamma > 1: p_abs G^gamma constant)

(+inf where G <= 0), so that dE/dx = -p dA/dx, with Hessian gamma p_abs / G dA dA^T - p d2A (a PSD rank-1
part and the wall's load stiffness) and -dr/dq = dp/dq dA/dx = gamma p_abs / V_atm dA/dx. The atmosphere
also presses on the body's outer faces; that uniform part only compresses the rubber (by p_atm / bulk
modulus) and is left out: the wall carries the gauge pressure.
"""

import math
from dataclasses import dataclass

import numpy as np

from ...errors import require, require_finite
from ...io.units import PRESSURE, si_default
from .kind import KINDS, ChamberKind
from .wall import Chamber


@KINDS.register
@dataclass(frozen=True)
class ClosedGas(ChamberKind):
    """A sealed chamber of air at ambient pressure `atmosphere` (in the scene's pressure unit; its default None
    is 101325 Pa, which the Scene converts into it: 101.325 in kPa), compressed with polytropic exponent gamma:
    1 isothermal, 1.4 adiabatic air."""

    atmosphere: float | None = si_default(101325.0, PRESSURE)
    gamma: float = 1.0
    name = "closed_gas"
    quantity = "air pumped in"
    rest = 0.0
    dimension = "area"  # the chamber measure's unit: a volume per unit depth in 2D, a volume in 3D (units.in_dimension)

    def __post_init__(self):
        require(
            self.atmosphere is None or require_finite("atmosphere", self.atmosphere) > 0,
            f"atmosphere = {self.atmosphere!r} must be > 0",
        )
        require(
            1 <= require_finite("gamma", self.gamma) <= 5 / 3,
            f"gamma = {self.gamma!r} must lie in [1, 5/3] (1: isothermal, 1.4: adiabatic air)",
        )

    def check(self, what: str, values: list[float]) -> None:
        for value in values:
            require(value >= 0, f"{what} air pumped in {value!r} must be >= 0 (a syringe drawn back lets air out)")

    def term(self, config, loop, name: str, order: int, origin=None) -> "ClosedGasChamber":
        return ClosedGasChamber(self, config, loop, name, order, origin)


class ClosedGasChamber(Chamber):
    """Air of volume `air` at p_atm filling the gas volume G = A + `outside`."""

    def __init__(self, kind: ClosedGas, config, loop: np.ndarray, name: str = "main", order: int = 1, origin=None):
        super().__init__(kind, config, loop, name, order, origin)
        self.set_command(kind.rest)

    def set_command(self, pumped: float) -> None:
        """Command the air pumped in, q: V_atm = A_rest + q, no gas outside the chamber."""
        self.air, self.outside = self.rest_area + float(pumped), 0.0

    def absolute_pressure(self, area: float) -> float:
        """p_abs = p_atm (V_atm / G)^gamma, +inf where the gas volume G = A + c is not positive."""
        gas = area + self.outside
        return self.kind.atmosphere * (self.air / gas) ** self.kind.gamma if gas > 0 else math.inf

    def pressure_at(self, area: float) -> float:
        return self.absolute_pressure(area) - self.kind.atmosphere

    def energy_at(self, area: float) -> float:
        gas, p_atm, gamma = area + self.outside, self.kind.atmosphere, self.kind.gamma
        if gas <= 0:
            return math.inf
        if gamma == 1:
            return -p_atm * self.air * math.log(gas) + p_atm * area
        return p_atm * self.air**gamma * gas ** (1 - gamma) / (gamma - 1) + p_atm * area

    def stiffness_at(self, area: float) -> float:
        """-dp/dA = gamma p_abs / G."""
        return self.kind.gamma * self.absolute_pressure(area) / (area + self.outside)

    def command_scale_at(self, area: float) -> float:
        """-dr/dq = gamma p_abs / V_atm dA/dx (more air in the same gas volume)."""
        return self.kind.gamma * self.absolute_pressure(area) / self.air

    def max_step(self, dx: np.ndarray) -> float:
        """Largest step fraction t along dx that keeps the gas volume positive: A(u + t dx) is a polynomial of
        degree d (the dimension: an area is quadratic, a volume cubic in the positions), so it is interpolated
        through t = 0 .. d (step_within)."""
        t = np.arange(self.config.dim + 1.0)
        measures = [self.area_and_gradient(self.config.u + s * dx)[0] for s in t]
        return self.step_within(np.polynomial.polynomial.polyfit(t, measures, len(t) - 1))

    def step_within(self, measure: np.ndarray) -> float:
        """The smallest positive real root of the gas volume G(t) = A(t) + c, A(t) the polynomial of coefficients
        `measure` (lowest first) in the step fraction t (inf if none)."""
        gas = np.array(measure, dtype=np.float64)
        gas[0] += self.outside
        roots = np.polynomial.polynomial.polyroots(gas)
        ahead = roots.real[(np.abs(roots.imag) <= 1e-9 * np.abs(roots)) & (roots.real > 0)]
        return float(ahead.min()) if len(ahead) else math.inf
