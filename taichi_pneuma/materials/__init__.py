"""Material laws, registered by name: each written once as Taichi functions (materials/law.py) and used
by the elastic term's kernels and by the output fields alike.

    stable_neo_hookean   StableNeoHookean (materials/neo_hookean.py), parameters (mu, lam)

A scene's Material(E, nu) maps to the stable neo-Hookean law. A new law is a Law subclass decorated
with @register (in a module imported here); the tests check every registered law by finite differences.
"""

from .law import LAWS, Law, cauchy_stresses, register
from .neo_hookean import StableNeoHookean, lame_parameters

__all__ = ["LAWS", "Law", "StableNeoHookean", "cauchy_stresses", "lame_parameters", "register"]
