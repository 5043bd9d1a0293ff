"""Material laws, registered by name: each written once as Taichi functions (materials/law.py) and used
by the elastic term's kernels and by the output fields alike.

    stable_neo_hookean     StableNeoHookean (materials/neo_hookean.py), parameters (mu, lam)
    isochoric_polynomial   IsochoricPolynomial (materials/isochoric.py), parameters (C10, C01, C20, C30, K):
                           neo-Hookean, Mooney-Rivlin and Yeoh on the isochoric invariants

A scene's Material(E, nu) maps to the stable neo-Hookean law, an IsochoricMaterial (a form of the
polynomial law and its coefficients) or a silicone preset (materials/presets.py) to the polynomial one.
A new law is a Law subclass decorated with @register (in a module imported here); the tests check every
registered law by finite differences.
"""

from .isochoric import FORMS, IsochoricMaterial, IsochoricPolynomial, bulk_modulus
from .law import LAWS, Law, cauchy_stresses, register
from .neo_hookean import StableNeoHookean, lame_parameters

__all__ = ["FORMS", "LAWS", "IsochoricMaterial", "IsochoricPolynomial", "Law", "StableNeoHookean", "bulk_modulus",
           "cauchy_stresses", "lame_parameters", "register"]
