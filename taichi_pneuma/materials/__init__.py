"""Material laws, registered by name: each written once as Taichi functions (materials/law.py) and used
by the elastic term's kernels and by the output fields alike.

    LAWS["stable_neo_hookean"]   StableNeoHookean (materials/neo_hookean.py), parameters (mu, lam)

A scene's Material(E, nu) maps to the stable neo-Hookean law.
"""

from ..errors import require
from .law import Law, cauchy_stresses
from .neo_hookean import StableNeoHookean, lame_parameters

LAWS = {law.name: law for law in (StableNeoHookean,)}


def law_named(name: str) -> type[Law]:
    """The registered law of that name (PneumaInputError naming the registered ones otherwise)."""
    require(name in LAWS, f"material law = {name!r} is not one of {', '.join(LAWS)}")
    return LAWS[name]


__all__ = ["LAWS", "Law", "StableNeoHookean", "cauchy_stresses", "lame_parameters", "law_named"]
