"""Stable neo-Hookean (Macklin-Mueller form): rest-stable, finite for inverted elements.

Per unit rest volume, with J = det F and Lame-like parameters p = (mu, lam),

    psi(F) = mu (1 - J) + lam/2 (1 - J)^2 + mu/2 (|F|_F^2 - 3),
    mu = E / (2 (1 + nu)),   lam = E nu / ((1 + nu)(1 - 2 nu)).

In plane strain (F_33 = 1) |F|^2 - 3 = |F2|^2 - 2 and J = det F2: the 2D law of the reference scene.
With g = dJ/dF = cof F and c = mu + lam (1 - J):

    P = dpsi/dF = mu F - c g,   M = d2psi/dF2 = mu I + lam g g^T - c H_J,   H_J = d2J/dF2,
    (H_J)_(ij)(kl) = e_ikm e_jln F_mn   (e: the permutation symbol),

which in the plane is constant: with vec(F) = (F00, F01, F10, F11), H_J has eigenvalue +1 on
span{(1,0,0,1), (0,1,-1,0)} and -1 on span{(1,0,0,-1), (0,1,1,0)}.

The eigensystem of M is analytic in 2D and 3D (the fast path). In 2D, mu I - c H_J is mu - c on the first
plane and mu + c on the second. Split g = a u_+ + b u_- into its parts in the two planes (a, b >= 0, u_+-
unit) and let w_+- complete each plane. Then

    M = (mu - c) w_+ w_+^T + (mu + c) w_- w_-^T + [u_+ u_-] B [u_+ u_-]^T,
    B = [[mu - c + lam a^2, lam a b], [lam a b, mu + c + lam b^2]],

and the 2 x 2 block B has closed-form eigenpairs: four eigenpairs of M, no iteration.

In 3D the eigensystem is that of Smith, de Goes and Kim (2019, "Analytic eigensystems for isotropic
distortion energies"), on the rotation-variant SVD F = U diag(s) V^T (eigen.rotation_variant_svd): for
each axis k, with (i, j) the other two,

    twist  U (e_i e_j^T - e_j e_i^T) V^T / sqrt 2,   eigenvalue mu - c s_k,
    flip   U (e_i e_j^T + e_j e_i^T) V^T / sqrt 2,   eigenvalue mu + c s_k,

and three scaling modes U diag(a) V^T for the eigenvectors a of the 3 x 3 Hessian of psi in s,

    A_ii = mu + lam (s_j s_k)^2,   A_ij = lam s_i s_j s_k^2 - c s_k,

(at s = (s1, s2, 1) the twist and flip of axis z are the in-plane modes of the 2D system above).

A scene names the law by Material(E, nu), the default material form (registry.py DEFAULT_FORM: a [material] table
naming no law or preset).
"""

from dataclasses import MISSING, dataclass

import numpy as np

from ..backend import ti
from ..errors import require, require_finite
from ..io.registry import key
from ..io.units import PRESSURE
from .eigen import SQRT_HALF, rotation_variant_svd, symmetric_eigensystem
from .invariants import cofactor, determinant_hessian, flat
from .law import LAWS, Law
from .registry import DEFAULT_FORM, MaterialForm, poisson_ratio_key, selector_names

DEFAULT_YOUNGS_MODULUS = 1e4  # Pa: Material's E when a scene gives none (in the scene's units)


def lame_parameters(youngs_modulus, poisson_ratio):
    """(mu, lam) of an isotropic material from Young's modulus and Poisson's ratio (scalars or arrays)."""
    e, nu = youngs_modulus, poisson_ratio
    return e / (2.0 * (1.0 + nu)), e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu))


@ti.func
def plane_split(g, p, q):
    """The part of g in the plane spanned by orthonormal p, q: its length a, unit direction u, and the
    unit w completing the plane (u = p, w = q when that part vanishes)."""
    s, t = g.dot(p), g.dot(q)
    a = ti.sqrt(s * s + t * t)
    uu, ww = p, q
    if a > 0:
        uu = (s * p + t * q) / a
        ww = (-t * p + s * q) / a
    return a, uu, ww


@LAWS.register
class StableNeoHookean(Law):
    name = "stable_neo_hookean"
    parameter_names = ("mu", "lam")
    analytic_dims = (2, 3)

    @staticmethod
    def parameters(youngs_modulus, poisson_ratio) -> np.ndarray:
        return np.column_stack(
            lame_parameters(np.asarray(youngs_modulus, dtype=np.float64), np.asarray(poisson_ratio, dtype=np.float64))
        )

    @staticmethod
    def modulus(parameters) -> np.ndarray:
        return parameters[:, 0] + parameters[:, 1]

    @staticmethod
    def poisson_ratio(parameters) -> np.ndarray:
        """lam / (2 (lam + mu)): the energy's small-strain Lame parameters are (mu, lam) (its mu (1 - J) cancels
        the stress mu F at rest)."""
        mu, lam = parameters[:, 0], parameters[:, 1]
        return lam / (2.0 * (lam + mu))

    @staticmethod
    @ti.func
    def energy(F, p):
        mu, lam = p[0], p[1]
        J = F.determinant()
        return mu * (1.0 - J) + 0.5 * lam * (1.0 - J) ** 2 + 0.5 * mu * (F.norm_sqr() - 3.0)

    @staticmethod
    @ti.func
    def stress(F, p):
        mu, lam = p[0], p[1]
        return mu * F - (mu + lam * (1.0 - F.determinant())) * cofactor(F)

    @staticmethod
    @ti.func
    def stress_derivative(F, p):
        mu, lam = p[0], p[1]
        g = cofactor(F)
        c = mu + lam * (1.0 - F.determinant())
        return mu * ti.Matrix.identity(ti.f64, 9) + lam * flat(g).outer_product(flat(g)) - c * determinant_hessian(F)

    @staticmethod
    @ti.func
    def eigensystem(F, p, d: ti.template()):
        """The d^2 eigenvalues and unit eigenvectors (rows of a d^2 x d^2 matrix) of M on the d x d block (module
        docstring)."""
        if ti.static(d == 2):
            return plane_eigensystem(F, p)
        else:
            return solid_eigensystem(F, p)


@ti.func
def plane_eigensystem(F, p):
    """The four eigenvalues and unit eigenvectors (rows of a 4 x 4 matrix) of the in-plane M."""
    mu, lam = p[0], p[1]
    g = ti.Vector([F[1, 1], -F[1, 0], -F[0, 1], F[0, 0]])  # cof of the in-plane block, = that of F
    c = mu + lam * (1.0 - F.determinant())
    r = SQRT_HALF
    a, u_p, w_p = plane_split(g, ti.Vector([r, 0.0, 0.0, r]), ti.Vector([0.0, r, -r, 0.0]))
    b, u_m, w_m = plane_split(g, ti.Vector([r, 0.0, 0.0, -r]), ti.Vector([0.0, r, r, 0.0]))
    pp, q, s = mu - c + lam * a * a, lam * a * b, mu + c + lam * b * b  # B = [[pp, q], [q, s]]
    mean, half = 0.5 * (pp + s), ti.sqrt(0.25 * (pp - s) ** 2 + q * q)
    theta = 0.5 * ti.atan2(2.0 * q, pp - s)  # (cos, sin) theta: the eigenvector of mean + half
    v1 = ti.cos(theta) * u_p + ti.sin(theta) * u_m
    v2 = -ti.sin(theta) * u_p + ti.cos(theta) * u_m
    return ti.Vector([mu - c, mu + c, mean + half, mean - half]), ti.Matrix.rows([w_p, w_m, v1, v2])


@ti.func
def solid_eigensystem(F, p):
    """The nine eigenvalues and unit eigenvectors (rows of a 9 x 9 matrix, over vec(F) row by row) of the 3D M:
    twists, flips, then scalings (module docstring)."""
    mu, lam = p[0], p[1]
    U, s, V = rotation_variant_svd(F)
    c = mu + lam * (1.0 - s[0] * s[1] * s[2])
    values = ti.Vector.zero(ti.f64, 9)
    vectors = ti.Matrix.zero(ti.f64, 9, 9)
    A = ti.Matrix.zero(ti.f64, 3, 3)
    for k in ti.static(range(3)):
        i, j = (k + 1) % 3, (k + 2) % 3
        values[k], values[3 + k] = mu - c * s[k], mu + c * s[k]
        for a, b in ti.static(ti.ndrange(3, 3)):
            vectors[k, 3 * a + b] = SQRT_HALF * (U[a, i] * V[b, j] - U[a, j] * V[b, i])
            vectors[3 + k, 3 * a + b] = SQRT_HALF * (U[a, i] * V[b, j] + U[a, j] * V[b, i])
        A[k, k] = mu + lam * (s[i] * s[j]) ** 2
        A[i, j] = lam * s[i] * s[j] * s[k] ** 2 - c * s[k]
        A[j, i] = A[i, j]
    scalings, rows = symmetric_eigensystem(A)
    for m in ti.static(range(3)):
        values[6 + m] = scalings[m]
        for a, b in ti.static(ti.ndrange(3, 3)):
            vectors[6 + m, 3 * a + b] = (
                U[a, 0] * rows[m, 0] * V[b, 0] + U[a, 1] * rows[m, 1] * V[b, 1] + U[a, 2] * rows[m, 2] * V[b, 2]
            )
    return values, vectors


def youngs_modulus_key(default=MISSING, si=None):
    """The field of a form's Young's modulus, key E (default: none, the key is required; si: the SI value a
    default None stands for, units.si_default)."""
    return key(default, "Young's modulus of the stable neo-Hookean material, > 0", unit=PRESSURE, si=si, name="E")


@DEFAULT_FORM.register
@dataclass(frozen=True)
class Material(MaterialForm):
    """Isotropic material of the stable neo-Hookean law: Young's modulus E > 0 (None: 1e4 Pa in the scene's
    units, set by the Scene), Poisson's ratio -1 < nu < 0.5."""

    youngs_modulus: float | None = youngs_modulus_key(si=DEFAULT_YOUNGS_MODULUS)
    poisson_ratio: float = poisson_ratio_key(0.45)
    name = StableNeoHookean.name
    summary = "the stable neo-Hookean one of E and nu (no law or preset)"

    def __post_init__(self):
        require(
            self.youngs_modulus is None or require_finite("E", self.youngs_modulus) > 0,
            f"E = {self.youngs_modulus!r} must be > 0",
        )
        nu = require_finite("nu", self.poisson_ratio)
        require(-1 < nu < 0.5, f"nu = {self.poisson_ratio!r} must lie in (-1, 0.5)")

    @classmethod
    def form_keys(cls, values: dict) -> dict:
        """E and nu, with the values a scene file that gives neither writes (unitless)."""
        return {"E": DEFAULT_YOUNGS_MODULUS, "nu": cls.poisson_ratio}

    @classmethod
    def refusal(cls, extra: list[str], values: dict) -> str:
        laws = " or ".join(selector_names("law"))
        return f"{', '.join(extra)} need law = {laws} (E and nu alone: stable neo-Hookean)"

    def law_parameters(self, units) -> tuple[type[Law], np.ndarray]:
        """The law and its parameter vector (E and nu are in the scene's units already)."""
        return StableNeoHookean, StableNeoHookean.parameters(self.youngs_modulus, self.poisson_ratio)[0]
