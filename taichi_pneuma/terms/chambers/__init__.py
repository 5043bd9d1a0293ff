"""Sealed chambers: the wall geometry every kind shares (wall.py), what a kind is and the registry of
kinds by name (kind.py), and one module per kind: area control (also named "volume") and pressure control.

A new kind is one module: a @register'ed ChamberKind dataclass and its wall.Chamber term (docs/extending.md).
"""

from .area import MAX_AREA_RATIO, AreaChamber, AreaControl
from .kind import KINDS, ChamberKind, chamber_kind, register
from .pressure import PressureChamber, PressureControl
from .wall import Chamber

__all__ = ["KINDS", "MAX_AREA_RATIO", "AreaChamber", "AreaControl", "Chamber", "ChamberKind", "PressureChamber",
           "PressureControl", "chamber_kind", "register"]
