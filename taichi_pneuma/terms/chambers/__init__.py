"""Sealed chambers: the wall geometry every kind shares (wall.py), what a kind is and the registry of
kinds by name (kind.py), and one module per kind: area control (also named "volume"), pressure control
(a pressure regulator), a closed gas chamber (a sealed amount of air) and a syringe pushing air through a tube.

A new kind is one module: a @KINDS.register'ed ChamberKind dataclass and its wall.Chamber term (docs/extending.md).
"""

from .area import MAX_AREA_RATIO, AreaChamber, AreaControl
from .closed_gas import ClosedGas, ClosedGasChamber
from .kind import KINDS, ChamberKind, chamber_kind, default_kind
from .pressure import PressureChamber, PressureControl
from .syringe import Syringe, SyringeChamber
from .wall import Chamber

__all__ = [
    "KINDS",
    "MAX_AREA_RATIO",
    "AreaChamber",
    "AreaControl",
    "Chamber",
    "ChamberKind",
    "ClosedGas",
    "ClosedGasChamber",
    "PressureChamber",
    "PressureControl",
    "Syringe",
    "SyringeChamber",
    "chamber_kind",
    "default_kind",
]
