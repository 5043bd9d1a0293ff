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

Stability (Drucker's condition, the check Abaqus makes of a hyperelastic fit): along uniaxial, equibiaxial and
pure shear deformation of the incompressible material the nominal stress must grow with the stretch. Along
such a path of stretch lam, with w(lam) = W(I1(lam), I2(lam)), the nominal stress is dw/dlam (uniaxial, pure
shear; 2 x it equibiaxially), so the condition is

    d2w/dlam2 = W1 I1'' + W11 I1'^2 + C01 I2'' > 0,
    uniaxial     (lam, lam^-1/2, lam^-1/2):  I1 = lam^2 + 2/lam,       I2 = 2 lam + lam^-2,
    equibiaxial  (lam, lam, lam^-2):         I1 = 2 lam^2 + lam^-4,    I2 = lam^4 + 2 lam^-2,
    pure shear   (lam, 1, 1/lam):            I1 = I2 = lam^2 + 1 + lam^-2,

checked at load for every principal stretch in [1/3, 3] (STRETCHES): the presets are fitted to uniaxial tension
up to 200 % engineering strain (lam = 3, presets.py), and 1/3 is its reciprocal in compression. With every
coefficient >= 0 (and C10 + C01 > 0) the law is stable at every stretch (I1'', I2'' > 0); a negative C01, C20
or C30 may make it unstable, and such a law is refused naming the coefficient, the path and the stretch.
"""

from __future__ import annotations

from dataclasses import MISSING, dataclass

import numpy as np

from ..backend import ti
from ..errors import require, require_finite
from ..io.registry import key
from ..io.units import PRESSURE
from .invariants import isochoric_gradients, isochoric_hessians, isochoric_invariants
from .law import LAWS, Law
from .registry import LAW_FORMS, Compressible

FORMS = {"neo_hookean": ("C10",), "mooney_rivlin": ("C10", "C01"), "yeoh": ("C10", "C20", "C30")}
COEFFICIENTS = ("C10", "C01", "C20", "C30")
DEFAULT_POISSON_RATIO = 0.49  # when a material gives neither K nor nu: nearly incompressible, as silicones are
STRETCHES = (1 / 3, 3.0)  # the principal stretches a law must be stable for (module docstring)


def coefficient_key(coefficient: str, default=MISSING):
    """The field of the coefficient named `coefficient` (its key), in the scene's pressure unit."""
    return key(
        default,
        f"coefficient of the isochoric law's {coefficient} term (the forms taking it; none: 0, C10 required)",
        unit=PRESSURE,
    )


def path_invariants(lam: np.ndarray) -> dict:
    """(I1 - 3, I1', I1'', I2'') along each stability path, at stretches lam of that path keeping every principal
    stretch within STRETCHES (equibiaxially lam in [3^-1/2, 3^1/2]: its third stretch is lam^-2)."""
    return {
        "uniaxial": (lam**2 + 2 / lam - 3, 2 * lam - 2 / lam**2, 2 + 4 / lam**3, 6 / lam**4),
        "equibiaxial": (2 * lam**2 + lam**-4 - 3, 4 * lam - 4 * lam**-5, 4 + 20 * lam**-6, 12 * lam**2 + 12 * lam**-4),
        "pure shear": (lam**2 + lam**-2 - 2, 2 * lam - 2 * lam**-3, 2 + 6 * lam**-4, 2 + 6 * lam**-4),
    }


def unstable_stretch(C10: float, C01: float, C20: float, C30: float) -> tuple[str, float] | None:
    """The (path, stretch) nearest to the rest state (lam = 1) at which d2w/dlam2 <= 0 (module docstring), on the
    first path that has one; None when the law is stable over STRETCHES."""
    low, high = np.log(STRETCHES)
    lam = np.exp(np.linspace(low, high, 4001))
    bounds = {"equibiaxial": np.sqrt(STRETCHES)}
    for path, (a, da, dda, ddb) in path_invariants(lam).items():
        W1, W11 = C10 + 2 * C20 * a + 3 * C30 * a**2, 2 * C20 + 6 * C30 * a
        inside = (lam >= bounds.get(path, STRETCHES)[0]) & (lam <= bounds.get(path, STRETCHES)[1])
        falling = inside & (W1 * dda + W11 * da**2 + C01 * ddb <= 0)
        if falling.any():
            return path, float(lam[falling][np.argmin(np.abs(np.log(lam[falling])))])
    return None


def bulk_modulus(shear_modulus, poisson_ratio):
    """K of an isotropic material from its shear modulus and Poisson's ratio: 2 mu (1 + nu) / (3 (1 - 2 nu))."""
    return 2.0 * shear_modulus * (1.0 + poisson_ratio) / (3.0 * (1.0 - 2.0 * poisson_ratio))


@LAWS.register
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
    def youngs_modulus(parameters) -> np.ndarray:
        """2 mu0 (1 + nu), mu0 = 2 (C10 + C01), nu = poisson_ratio: the small-strain E, the inverse of parameters."""
        mu0 = 2.0 * (parameters[:, 0] + parameters[:, 1])
        return 2.0 * mu0 * (1.0 + IsochoricPolynomial.poisson_ratio(parameters))

    @staticmethod
    def poisson_ratio(parameters) -> np.ndarray:
        """(3 K - 2 mu0) / (2 (3 K + mu0)), mu0 = 2 (C10 + C01): the inverse of bulk_modulus."""
        mu0, K = 2.0 * (parameters[:, 0] + parameters[:, 1]), parameters[:, 4]
        return (3.0 * K - 2.0 * mu0) / (2.0 * (3.0 * K + mu0))

    @staticmethod
    @ti.func
    def energy(F, p):
        I1, I2, J = isochoric_invariants(F)
        a = I1 - 3.0
        return (p[0] * a + p[1] * (I2 - 3.0) + p[2] * a * a + p[3] * a * a * a) + 0.5 * p[4] * (J - 1.0) ** 2

    @staticmethod
    @ti.func
    def volumetric(J, p):
        """(U, U', U'') of U(J) = K/2 (J - 1)^2."""
        return ti.Vector([0.5 * p[4] * (J - 1.0) ** 2, p[4] * (J - 1.0), p[4]], dt=ti.f64)

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
        return (
            W11 * dI1.outer_product(dI1)
            + W1 * d2I1
            + p[1] * d2I2
            + p[4] * dJ.outer_product(dJ)
            + p[4] * (J - 1.0) * d2J
        )


@ti.func
def slopes(F, p):
    """(W1, W11, J): dW/dIbar1 = C10 + 2 C20 a + 3 C30 a^2 and d2W/dIbar1^2 = 2 C20 + 6 C30 a, a = Ibar1 - 3."""
    I1, _, J = isochoric_invariants(F)
    a = I1 - 3.0
    return p[0] + 2.0 * p[2] * a + 3.0 * p[3] * a * a, 2.0 * p[2] + 6.0 * p[3] * a, J


@LAW_FORMS.register
@dataclass(frozen=True)
class IsochoricMaterial(Compressible):
    """A material of the isochoric law in one of its FORMS: coefficients in the scene's pressure unit (those
    the form does not take are zero), and the bulk modulus K, or else Poisson's ratio nu (default 0.49; both
    keyword-only, registry.py Compressible). A scene file names it by `law = "<form>"` (registry.py)."""

    law: str
    C10: float = coefficient_key("C10")
    C01: float = coefficient_key("C01", 0.0)
    C20: float = coefficient_key("C20", 0.0)
    C30: float = coefficient_key("C30", 0.0)
    selector = "law"
    name, aliases = tuple(FORMS)[0], tuple(FORMS)[1:]
    summary = (
        f"a form of the isochoric law (law = {', '.join(FORMS)}: C10, ... and K or nu, in the scene's pressure unit)"
    )

    def __post_init__(self):
        require(self.law in FORMS, f"law = {self.law!r} is not one of {', '.join(FORMS)}")
        for name in COEFFICIENTS:
            value = require_finite(name, getattr(self, name))
            require(
                name in FORMS[self.law] or value == 0,
                f"{name} = {value!r}: law {self.law!r} takes only {', '.join(FORMS[self.law])}",
            )
        require(
            self.shear_modulus > 0,
            f"C10 = {self.C10!r}, C01 = {self.C01!r}: the initial shear modulus "
            f"2 (C10 + C01) = {self.shear_modulus:g} must be > 0",
        )
        self.require_stable()
        require(
            self.bulk_modulus is None or self.poisson_ratio is None,
            f"K = {self.bulk_modulus!r} and nu = {self.poisson_ratio!r}: give one of them, not both",
        )
        if self.bulk_modulus is not None:
            require(require_finite("K", self.bulk_modulus) > 0, f"K = {self.bulk_modulus!r} must be > 0")
        if self.poisson_ratio is not None:
            nu = require_finite("nu", self.poisson_ratio)
            require(-1 < nu < 0.5, f"nu = {self.poisson_ratio!r} must lie in (-1, 0.5)")

    @classmethod
    def form_keys(cls, values: dict) -> dict:
        """law, the coefficients its form takes, K and nu."""
        return dict.fromkeys(("law", *FORMS.get(values.get("law", ""), ()), "K", "nu"))

    @classmethod
    def refusal(cls, extra: list[str], values: dict) -> str:
        return f"{extra[0]} = {values[extra[0]]!r}: law = {values['law']!r} takes C10, ... and K or nu, not {extra[0]}"

    def scene_values(self) -> dict:
        """law, K, nu and the coefficients its form takes (those it does not are zero, and not written)."""
        return {
            "law": self.law,
            "K": self.bulk_modulus,
            "nu": self.poisson_ratio,
            **{c: getattr(self, c) for c in FORMS[self.law]},
        }

    def require_stable(self) -> None:
        """Refuse a law that is not stable over STRETCHES (module docstring), naming its negative coefficients,
        the path and the stretch at which its nominal stress stops growing."""
        found = unstable_stretch(self.C10, self.C01, self.C20, self.C30)
        if found is None:
            return
        path, lam = found
        given = ", ".join(f"{c} = {getattr(self, c)!r}" for c in FORMS[self.law])
        negative = [c for c in COEFFICIENTS if getattr(self, c) < 0]
        mode = path if path == "pure shear" else f"{path} {'tension' if lam > 1 else 'compression'}"
        require(
            False,
            f"law = {self.law!r} with {given} is not stable (Drucker): in {mode} at stretch {lam:.3g} "
            f"its nominal stress stops growing with the stretch, because of "
            f"{' and '.join(f'{c} = {getattr(self, c)!r}' for c in negative)} < 0; a law must be stable "
            f"for principal stretches 1/{1 / STRETCHES[0]:g} to {STRETCHES[1]:g} (the presets' fitted "
            f"range)",
        )

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

    def law_parameters(self, units=None) -> tuple[type[Law], np.ndarray]:
        """The law and its parameter vector (the coefficients are in the scene's units already)."""
        return IsochoricPolynomial, self.row()

    def scaled(self, factor: float) -> IsochoricMaterial:
        """The same material with every modulus (coefficients and a given K) multiplied by factor (a unit change)."""
        return IsochoricMaterial(
            self.law,
            factor * self.C10,
            factor * self.C01,
            factor * self.C20,
            factor * self.C30,
            bulk_modulus=None if self.bulk_modulus is None else factor * self.bulk_modulus,
            poisson_ratio=self.poisson_ratio,
        )
