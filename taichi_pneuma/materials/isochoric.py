"""Neo-Hookean, Mooney-Rivlin and Yeoh on the isochoric invariants plus a volumetric term: one law, written once.

Per unit rest volume, with J = det F and the isochoric invariants Ibar1 = J^(-2/3) I1, Ibar2 = J^(-4/3) I2
(materials/invariants.py),

    psi(F) = W(Ibar1, Ibar2) + U(J),
    W = C10 (Ibar1 - 3) + C01 (Ibar2 - 3) + C20 (Ibar1 - 3)^2 + C30 (Ibar1 - 3)^3,
    U = K/2 (J - 1)^2.

The three named forms are restrictions of W: neo-Hookean (C10), Mooney-Rivlin (C10, C01) and Yeoh (C10, C20,
C30); the others are zero. Linearised at F = I the law is linear elasticity with shear modulus
mu0 = 2 (C10 + C01) and bulk modulus K; given a Poisson's ratio nu instead of K,

    K = 2 mu0 (1 + nu) / (3 (1 - 2 nu)).

U is the Abaqus/ANSYS volumetric form (1/D1)(J - 1)^2 with D1 = 2/K; it is finite for any J (inverted
elements too); W grows without bound as J -> 0 (a barrier the line search never crosses).

With a = Ibar1 - 3, W1 = dW/dIbar1 = C10 + 2 C20 a + 3 C30 a^2, W2 = C01, W11 = 2 C20 + 6 C30 a:

    P = dpsi/dF = W1 dIbar1 + W2 dIbar2 + K (J - 1) dJ,
    d2psi/dF2 = W11 dIbar1 dIbar1^T + W1 d2Ibar1 + W2 d2Ibar2 + K dJ dJ^T + K (J - 1) d2J,

written once on a 3 x 3 F (plane strain embeds F with F33 = 1, materials/law.py); the projected Hessian
takes the generic Jacobi path on the d x d block. The invariants make the law compressible only through U:
as nu -> 1/2 (K/mu0 -> inf) it tends to the incompressible material of the same W.

A single law (one compiled kernel set) holds all three forms, so a body whose regions are of different
silicones is one elastic term.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..backend import ti
from ..errors import require, require_finite
from .invariants import isochoric_gradients, isochoric_hessians, isochoric_invariants
from .law import Law, register

FORMS = {"neo_hookean": ("C10",), "mooney_rivlin": ("C10", "C01"), "yeoh": ("C10", "C20", "C30")}
COEFFICIENTS = ("C10", "C01", "C20", "C30")
DEFAULT_POISSON_RATIO = 0.49  # when a material gives neither K nor nu: nearly incompressible, as silicones are


def bulk_modulus(shear_modulus, poisson_ratio):
    """K of an isotropic material from its shear modulus and Poisson's ratio: 2 mu (1 + nu) / (3 (1 - 2 nu))."""
    return 2.0 * shear_modulus * (1.0 + poisson_ratio) / (3.0 * (1.0 - 2.0 * poisson_ratio))


@register
class IsochoricPolynomial(Law):
    name = "isochoric_polynomial"
    parameter_names = (*COEFFICIENTS, "K")

    @staticmethod
    def parameters(youngs_modulus, poisson_ratio) -> np.ndarray:
        """The neo-Hookean form of the given small-strain moduli: C10 = mu / 2, K = E / (3 (1 - 2 nu))."""
        e, nu = np.asarray(youngs_modulus, dtype=np.float64), np.asarray(poisson_ratio, dtype=np.float64)
        mu = e / (2.0 * (1.0 + nu))
        zero = np.zeros_like(mu)
        return np.column_stack([mu / 2.0, zero, zero, zero, bulk_modulus(mu, nu)])

    @staticmethod
    def modulus(parameters) -> np.ndarray:
        return 2.0 * (parameters[:, 0] + parameters[:, 1]) + parameters[:, 4]

    @staticmethod
    @ti.func
    def energy(F, p):
        I1, I2, J = isochoric_invariants(F)
        a = I1 - 3.0
        return (p[0] * a + p[1] * (I2 - 3.0) + p[2] * a * a + p[3] * a * a * a) + 0.5 * p[4] * (J - 1.0) ** 2

    @staticmethod
    @ti.func
    def stress(F, p):
        W1, _, J = slopes(F, p)
        dI1, dI2, dJ = isochoric_gradients(F)
        P = W1 * dI1 + p[1] * dI2 + p[4] * (J - 1.0) * dJ
        return ti.Matrix([[P[3 * i + j] for j in ti.static(range(3))] for i in ti.static(range(3))], dt=ti.f64)

    @staticmethod
    @ti.func
    def stress_derivative(F, p):
        W1, W11, J = slopes(F, p)
        dI1, _, dJ = isochoric_gradients(F)
        d2I1, d2I2, d2J = isochoric_hessians(F)
        return (W11 * dI1.outer_product(dI1) + W1 * d2I1 + p[1] * d2I2
                + p[4] * dJ.outer_product(dJ) + p[4] * (J - 1.0) * d2J)


@ti.func
def slopes(F, p):
    """(W1, W11, J): dW/dIbar1 = C10 + 2 C20 a + 3 C30 a^2 and d2W/dIbar1^2 = 2 C20 + 6 C30 a, a = Ibar1 - 3."""
    I1, _, J = isochoric_invariants(F)
    a = I1 - 3.0
    return p[0] + 2.0 * p[2] * a + 3.0 * p[3] * a * a, 2.0 * p[2] + 6.0 * p[3] * a, J


@dataclass(frozen=True)
class IsochoricMaterial:
    """A material of the isochoric law in one of its FORMS: coefficients in the scene's pressure unit (those
    the form does not take are zero), and the bulk modulus K, or else Poisson's ratio nu (default 0.49)."""

    law: str
    C10: float
    C01: float = 0.0
    C20: float = 0.0
    C30: float = 0.0
    bulk_modulus: float | None = None
    poisson_ratio: float | None = None

    def __post_init__(self):
        require(self.law in FORMS, f"law = {self.law!r} is not one of {', '.join(FORMS)}")
        for name in COEFFICIENTS:
            value = require_finite(name, getattr(self, name))
            require(name in FORMS[self.law] or value == 0,
                    f"{name} = {value!r}: law {self.law!r} takes only {', '.join(FORMS[self.law])}")
        require(self.shear_modulus > 0, f"C10 = {self.C10!r}, C01 = {self.C01!r}: the initial shear modulus "
                                        f"2 (C10 + C01) = {self.shear_modulus:g} must be > 0")
        require(self.bulk_modulus is None or self.poisson_ratio is None,
                f"K = {self.bulk_modulus!r} and nu = {self.poisson_ratio!r}: give one of them, not both")
        if self.bulk_modulus is not None:
            require(require_finite("K", self.bulk_modulus) > 0, f"K = {self.bulk_modulus!r} must be > 0")
        if self.poisson_ratio is not None:
            nu = require_finite("nu", self.poisson_ratio)
            require(-1 < nu < 0.5, f"nu = {self.poisson_ratio!r} must lie in (-1, 0.5)")

    @property
    def shear_modulus(self) -> float:
        """mu0 = 2 (C10 + C01), the small-strain shear modulus."""
        return 2.0 * (self.C10 + self.C01)

    @property
    def bulk(self) -> float:
        """K: given, or from mu0 and nu."""
        if self.bulk_modulus is not None:
            return self.bulk_modulus
        nu = DEFAULT_POISSON_RATIO if self.poisson_ratio is None else self.poisson_ratio
        return bulk_modulus(self.shear_modulus, nu)

    def row(self) -> np.ndarray:
        """The law's parameter vector (C10, C01, C20, C30, K)."""
        row = np.array([self.C10, self.C01, self.C20, self.C30, self.bulk], dtype=np.float64)
        require(np.all(np.isfinite(row)), f"K = {row[-1]!r} from nu = {self.poisson_ratio!r} is not finite")
        return row

    def law_parameters(self, units=None) -> tuple[type, np.ndarray]:
        """The law and its parameter vector (the coefficients are in the scene's units already)."""
        return IsochoricPolynomial, self.row()

    def scaled(self, factor: float) -> "IsochoricMaterial":
        """The same material with every modulus (coefficients and a given K) multiplied by factor (a unit change)."""
        return IsochoricMaterial(self.law, *(factor * getattr(self, n) for n in COEFFICIENTS),
                                 None if self.bulk_modulus is None else factor * self.bulk_modulus, self.poisson_ratio)

