"""Neo-Hookean, Mooney-Rivlin and Yeoh on the isochoric invariants (materials/isochoric.py) against closed forms:
linearised at F = I each is linear elasticity with its shear modulus 2 (C10 + C01) and bulk modulus K; at
nu -> 1/2 uniaxial tension of a homogeneous 3D body, of a plane-strain one, and of a meshed plane-strain strip
(the elastic term, P1 and P2) follows the incompressible material's nominal stress-stretch curve."""

import numpy as np
import pytest
from scipy.optimize import brentq
from test_materials import evaluate

from taichi_pneuma import runtime
from taichi_pneuma.fem.planar import Geometry
from taichi_pneuma.fem.shapes import Rectangle
from taichi_pneuma.fem.supports import PointSet
from taichi_pneuma.materials import IsochoricMaterial, IsochoricPolynomial
from taichi_pneuma.terms import Elasticity
from taichi_pneuma.terms.model import EnergyModel

# One material of each form (kPa, of Ecoflex-like magnitude)
FORMS = {
    "neo_hookean": IsochoricMaterial("neo_hookean", 12.0, poisson_ratio=0.49999),
    "mooney_rivlin": IsochoricMaterial("mooney_rivlin", 10.0, C01=3.0, poisson_ratio=0.49999),
    "yeoh": IsochoricMaterial("yeoh", 8.0, C20=0.4, C30=0.01, poisson_ratio=0.49999),
}
STRETCHES = np.linspace(1.05, 3.0, 8)


def at(material, F):
    """(psi, P, M) of the isochoric law with the material's parameters at each F (N, 3, 3)."""
    n = len(F)
    psi, P, M = np.empty(n), np.empty((n, 3, 3)), np.empty((n, 9, 9))
    evaluate(IsochoricPolynomial, np.ascontiguousarray(F, dtype=np.float64), np.tile(material.row(), (n, 1)), psi, P, M)
    return psi, P, M


def w_derivatives(m, I1):
    """dW/dI1 and dW/dI2 of the material's W at first invariant I1 (its own formula, written out again here)."""
    a = I1 - 3.0
    return m.C10 + 2 * m.C20 * a + 3 * m.C30 * a**2, m.C01


def uniaxial_3d(m, lam):
    """Incompressible uniaxial tension: P = 2 (lam - lam^-2) (W1 + W2 / lam), I1 = lam^2 + 2 / lam."""
    w1, w2 = w_derivatives(m, lam**2 + 2 / lam)
    return 2 * (lam - lam**-2) * (w1 + w2 / lam)


def uniaxial_plane_strain(m, lam):
    """Incompressible uniaxial tension in plane strain (stretches lam, 1/lam, 1):
    P = 2 (lam - lam^-3) (W1 + W2), I1 = I2 = lam^2 + lam^-2 + 1."""
    w1, w2 = w_derivatives(m, lam**2 + lam**-2 + 1)
    return 2 * (lam - lam**-3) * (w1 + w2)


@pytest.mark.parametrize("form", FORMS)
def test_small_strain_limit_is_linear_elasticity_with_the_laws_moduli(form):
    """d2psi/dF2 at F = I applied to a displacement gradient H gives mu (H + H^T) + (K - 2 mu / 3) tr(H) I,
    with mu = 2 (C10 + C01) and K the bulk modulus (from nu = 0.49999 here), in 3D and in plane strain."""
    material = FORMS[form]
    mu, K = 2 * (material.C10 + material.C01), material.bulk
    assert K == pytest.approx(2 * mu * 1.49999 / (3 * (1 - 2 * 0.49999)), rel=1e-12)
    M = at(material, np.eye(3)[None])[2][0]
    rng = np.random.default_rng(1)
    for dim in (3, 2):
        H = np.zeros((3, 3))
        H[:dim, :dim] = rng.standard_normal((dim, dim))
        linear = mu * (H + H.T) + (K - 2 * mu / 3) * np.trace(H) * np.eye(3)
        assert (M @ H.ravel()).reshape(3, 3) == pytest.approx(linear, abs=1e-10 * K)


def lateral_stretch(material, lam, free):
    """The stretch of the free directions (indices) of F = diag(lam, t, t or 1) that zeroes their stress."""

    def stress(t):
        F = np.diag([lam, t, t if len(free) == 2 else 1.0])
        return at(material, F[None])[1][0, free[0], free[0]]

    return brentq(stress, 0.2, 1.5, xtol=1e-15)


@pytest.mark.parametrize("form", FORMS)
def test_uniaxial_tension_near_incompressibility_follows_the_closed_form(form):
    """A homogeneous 3D body stretched by lam with zero lateral stress (lateral stretch solved for), and a
    plane-strain one (F33 = 1), at nu = 0.49999: P11 equals the incompressible closed form within 1e-3, and
    the volume change J - 1 is below 1e-3."""
    material = FORMS[form]
    for lam in STRETCHES:
        t = lateral_stretch(material, lam, (1, 2))
        P = at(material, np.diag([lam, t, t])[None])[1][0]
        assert abs(P[2, 2]) < 1e-9 * material.C10 and abs(lam * t * t - 1) < 1e-3
        assert P[0, 0] == pytest.approx(uniaxial_3d(material, lam), rel=1e-3)
        t = lateral_stretch(material, lam, (1,))
        assert abs(lam * t - 1) < 1e-3
        assert at(material, np.diag([lam, t, 1.0])[None])[1][0, 0, 0] == pytest.approx(
            uniaxial_plane_strain(material, lam), rel=1e-3
        )


def strip_reaction(material, order, lam, length=4.0, height=1.0):
    """Pull a meshed plane-strain strip [0, length] x [0, height] to stretch lam: the ends' x-displacements
    prescribed (0 and (lam - 1) length), every other degree of freedom free but one y at the left end, solved by
    Newton on the elastic term. Returns the force per unit depth on the right end (sum of dE/dx_x there)."""
    runtime.ensure_initialised()
    mesh = Geometry(Rectangle((length / 2, height / 2), (length, height)), (), 0.08, PointSet("left"), order).mesh()
    X = mesh.vertices
    model = EnergyModel(X, force_floor=1e-9, energy_resolution=1e-12)
    term = model.add(
        Elasticity(model.config, mesh.triangles, IsochoricPolynomial, np.tile(material.row(), (mesh.n_triangles, 1)))
    )
    left, right = np.isclose(X[:, 0], 0.0), np.isclose(X[:, 0], length)
    fixed = np.zeros(X.shape, dtype=bool)
    fixed[left | right, 0] = True
    fixed[np.flatnonzero(left)[0], 1] = True
    u = np.zeros_like(X)
    u[:, 0], u[:, 1] = (lam - 1) * X[:, 0], (1 / lam - 1) * X[:, 1]  # start from the incompressible homogeneous state
    rows, cols = term.hessian_pattern()
    free = ~fixed.ravel()
    for _ in range(30):
        model.set_displacements(u)
        g = term.gradient().ravel()
        if np.linalg.norm(g[free]) < 1e-10 * material.bulk:
            break
        H = np.zeros((u.size, u.size))
        np.add.at(H, (rows, cols), term.hessian_values(psd_only=True))
        step = np.zeros(u.size)
        step[free] = np.linalg.solve(H[np.ix_(free, free)], -g[free])
        u = u + step.reshape(u.shape)
    assert np.linalg.norm(g[free]) < 1e-10 * material.bulk
    return term.gradient()[right, 0].sum()


@pytest.mark.parametrize("order", [1, 2])
@pytest.mark.parametrize("form", FORMS)
def test_a_meshed_plane_strain_strip_follows_the_closed_form(form, order):
    """The strip's end force per unit depth over its rest height is the plane-strain closed form's nominal
    stress within 1e-3, up to a stretch of 2.5."""
    material = FORMS[form]
    for lam in (1.2, 1.8, 2.5):
        assert strip_reaction(material, order, lam) / 1.0 == pytest.approx(
            uniaxial_plane_strain(material, lam), rel=1e-3
        )
