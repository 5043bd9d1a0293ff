"""Syringe-driven chamber: a syringe pushes air through a tube into the sealed chamber.

The command is the syringe's displaced volume dV (the plunger's travel times the barrel's cross-section).
At rest (dV = 0) the air at atmospheric pressure p_atm fills the chamber (A_rest), the tube (its dead volume
V_d) and the barrel (V_s0, the syringe's initial air volume: how far the plunger was drawn back); the
plunger can push at most V_s0 (dV <= V_s0), and drawn back (dV < 0) it lets air out of the chamber. That
air, a fixed amount, fills the gas volume

    G = A + V_d + V_s0 - dV,     p_abs G^gamma = p_atm (A_rest + V_d + V_s0)^gamma,

isothermally by default (gamma = 1: p_abs G = n R T). It is closed_gas.py's gas with V_atm = A_rest + V_d +
V_s0 and c = V_d + V_s0 - dV outside the chamber: the same energy, pressure and Hessian, and

    -dr/d(dV) = dp/d(dV) dA/dx = gamma p_abs / G dA/dx.

Near a limit point of the chamber's pressure-volume curve the air's stiffness gamma p_abs / G decides:
past the peak the equilibrium is stable while it exceeds the structure's falling slope -dp/dA, so a
small dead volume passes the peak like volume control and a large one snaps like pressure control.
"""

from dataclasses import dataclass, field

from ...errors import require, require_finite
from ...io.units import AREA, unit
from .closed_gas import ClosedGas, ClosedGasChamber
from .kind import KINDS


@KINDS.register
@dataclass(frozen=True, kw_only=True)
class Syringe(ClosedGas):
    """A syringe of initial air volume syringe_volume (> 0) pushing through a tube of dead_volume (>= 0) into
    the chamber; atmosphere and gamma as for closed_gas. Volumes in the scene's units (areas in 2D)."""

    syringe_volume: float = field(metadata=unit(AREA))
    dead_volume: float = field(default=0.0, metadata=unit(AREA))
    name = "syringe"
    quantity = "displaced volume"

    def __post_init__(self):
        super().__post_init__()
        require(
            require_finite("syringe_volume", self.syringe_volume) > 0,
            f"syringe_volume = {self.syringe_volume!r} must be > 0",
        )
        require(
            require_finite("dead_volume", self.dead_volume) >= 0, f"dead_volume = {self.dead_volume!r} must be >= 0"
        )

    def check(self, what: str, values: list[float]) -> None:
        for value in values:
            require(
                value <= self.syringe_volume,
                f"{what} displaced volume {value!r} exceeds syringe_volume = "
                f"{self.syringe_volume!r} (the plunger stops at the barrel's end)",
            )

    def term(self, config, loop, name: str, order: int, origin=None) -> "SyringeChamber":
        return SyringeChamber(self, config, loop, name, order, origin)


class SyringeChamber(ClosedGasChamber):
    """The chamber's air shares the tube and the barrel, whose volume the command shrinks."""

    def set_command(self, displaced: float) -> None:
        """Command the displaced volume dV: V_atm = A_rest + V_d + V_s0, c = V_d + V_s0 - dV."""
        tube_and_barrel = self.kind.dead_volume + self.kind.syringe_volume
        self.air, self.outside = self.rest_area + tube_and_barrel, tube_and_barrel - float(displaced)

    def command_scale_at(self, area: float) -> float:
        """-dr/d(dV) = gamma p_abs / G dA/dx (the same air in a smaller gas volume)."""
        return self.stiffness_at(area)
