"""Material laws, registered by name: each written once as Taichi functions (materials/law.py) and used
by the elastic term's kernels and by the output fields alike.

    stable_neo_hookean     StableNeoHookean (materials/neo_hookean.py), parameters (mu, lam)
    isochoric_polynomial   IsochoricPolynomial (materials/isochoric.py), parameters (C10, C01, C20, C30, K):
                           neo-Hookean, Mooney-Rivlin and Yeoh on the isochoric invariants

and the material forms by which a scene names them (registry.py): Material(E, nu) the stable neo-Hookean law,
an IsochoricMaterial (a form of the polynomial law and its coefficients) or a silicone preset (presets.py) the
polynomial one. A new law is a Law subclass decorated with @LAWS.register and a MaterialForm dataclass, its fields
its keys (io/registry.py key), decorated with @LAW_FORMS.register, in a module imported here; the tests check every
registered law by finite differences.
"""

from .isochoric import FORMS, IsochoricMaterial, IsochoricPolynomial, bulk_modulus
from .law import LAWS, Law, cauchy_stresses
from .neo_hookean import Material, StableNeoHookean, lame_parameters
from .presets import PRESETS, PresetMaterial
from .registry import LAW_FORMS, PRESET_FORMS, Compressible, MaterialForm

__all__ = [
    "FORMS",
    "LAWS",
    "LAW_FORMS",
    "PRESETS",
    "PRESET_FORMS",
    "Compressible",
    "IsochoricMaterial",
    "IsochoricPolynomial",
    "Law",
    "Material",
    "MaterialForm",
    "PresetMaterial",
    "StableNeoHookean",
    "bulk_modulus",
    "cauchy_stresses",
    "lame_parameters",
]
