"""Material laws: each registered law's stress and stress derivative by finite differences, its energy,
gradient and Hessian through the elastic term on every element family (triangles and tetrahedra, linear
and quadratic), the plane-strain embedding, and the generic (Jacobi) eigensystem against the analytic one
(in 2D and 3D)."""

import numpy as np
import pytest
from fd import dense_hessian, fd_gradient, fd_hessian
from solid_meshes import shell_octant

from taichi_pneuma.backend import ti
from taichi_pneuma.materials import LAWS, Law, StableNeoHookean, lame_parameters
from taichi_pneuma.materials.law import element_parameters, stress_eigensystem
from taichi_pneuma.scene.build import reference_scene
from taichi_pneuma.solve.newton import NewtonSolver
from taichi_pneuma.terms import Clamp, Elasticity
from taichi_pneuma.terms.chambers import AreaControl
from taichi_pneuma.terms.model import EnergyModel

Arrays1, Arrays2, Arrays3 = (ti.types.ndarray(dtype=ti.f64, ndim=n) for n in (1, 2, 3))
MU, LAM = lame_parameters(1e4, 0.45)


@LAWS.register
class SaintVenantKirchhoff(Law):
    """psi = mu |E|^2 + lam/2 (tr E)^2, E = (F^T F - I) / 2 (the worked example of docs/extending.md)."""

    name, parameter_names = "saint_venant_kirchhoff", ("mu", "lam")
    parameters, modulus = StableNeoHookean.parameters, StableNeoHookean.modulus

    @staticmethod
    @ti.func
    def energy(F, p):
        E = 0.5 * (F.transpose() @ F - ti.Matrix.identity(ti.f64, 3))
        return p[0] * (E * E).sum() + 0.5 * p[1] * E.trace() ** 2

    @staticmethod
    @ti.func
    def stress(F, p):  # P = F S, S = 2 mu E + lam tr(E) I
        I = ti.Matrix.identity(ti.f64, 3)
        E = 0.5 * (F.transpose() @ F - I)
        return F @ (2.0 * p[0] * E + p[1] * E.trace() * I)

    @staticmethod
    @ti.func
    def stress_derivative(F, p):  # dP_ij/dF_kl = d_ik S_lj + mu (F_il F_kj + (F F^T)_ik d_jl) + lam F_ij F_kl
        I = ti.Matrix.identity(ti.f64, 3)
        E = 0.5 * (F.transpose() @ F - I)
        S, B = 2.0 * p[0] * E + p[1] * E.trace() * I, F @ F.transpose()
        M = ti.Matrix.zero(ti.f64, 9, 9)
        for i, j, k, l in ti.ndrange(3, 3, 3, 3):
            M[3 * i + j, 3 * k + l] = (
                I[i, k] * S[l, j] + p[0] * (F[i, l] * F[k, j] + B[i, k] * I[j, l]) + p[1] * F[i, j] * F[k, l]
            )
        return M


class JacobiNeoHookean(StableNeoHookean):
    """Stable neo-Hookean without its analytic eigensystem, said not isotropic: its Hessian takes the generic Jacobi
    path."""

    analytic_dims = ()
    isotropic = False


class SvdNeoHookean(StableNeoHookean):
    """Stable neo-Hookean without its analytic eigensystem: in 3D its Hessian takes the isotropic laws' SVD path."""

    analytic_dims = ()


@ti.func
def load(F: ti.template(), i):
    F3 = ti.Matrix.zero(ti.f64, 3, 3)
    for a, b in ti.static(ti.ndrange(3, 3)):
        F3[a, b] = F[i, a, b]
    return F3


@ti.kernel
def evaluate(law: ti.template(), F: Arrays3, parameters: Arrays2, psi: Arrays1, P: Arrays3, M: Arrays3):
    """psi, P (3 x 3) and d2psi/dF2 (9 x 9) of the law at each F (N, 3, 3)."""
    for i in range(F.shape[0]):
        F3, p = load(F, i), element_parameters(law, parameters, i)
        psi[i] = law.energy(F3, p)
        stress, derivative = law.stress(F3, p), law.stress_derivative(F3, p)
        for a, b in ti.static(ti.ndrange(3, 3)):
            P[i, a, b] = stress[a, b]
        for a, b in ti.ndrange(9, 9):
            M[i, a, b] = derivative[a, b]


@ti.kernel
def eigensystems(
    law: ti.template(), d: ti.template(), F: Arrays3, parameters: Arrays2, values: Arrays2, vectors: Arrays3
):
    """stress_eigensystem of the law on the leading d x d block at each F (N, 3, 3)."""
    for i in range(F.shape[0]):
        lambdas, V = stress_eigensystem(law, load(F, i), element_parameters(law, parameters, i), d)
        for a in range(d * d):
            values[i, a] = lambdas[a]
            for b in range(d * d):
                vectors[i, a, b] = V[a, b]


# Parameters exercising every term of a law where those of the reference material's moduli would not
SAMPLE_PARAMETERS = {"isochoric_polynomial": [1e3, 400.0, 300.0, 50.0, 2e4]}  # C10, C01, C20, C30, K
# Laws singular at det F = 0 (the isochoric invariants): finite differences near it measure the singularity,
# so their elastic term is tested in a state with det F > 0.2 everywhere
BARRIER_LAWS = {"isochoric_polynomial"}


def law_parameters(law, n):
    """n parameter vectors of the law: its sample ones, else those of the reference material's moduli."""
    sample = SAMPLE_PARAMETERS.get(law.name)
    return law.parameters(np.full(n, 1e4), np.full(n, 0.45)) if sample is None else np.tile(sample, (n, 1))


def at(law, F):
    """(psi, P, M) of the law at each F (N, 3, 3), with law_parameters."""
    n = len(F)
    psi, P, M = np.empty(n), np.empty((n, 3, 3)), np.empty((n, 9, 9))
    evaluate(law, np.ascontiguousarray(F), law_parameters(law, n), psi, P, M)
    return psi, P, M


def random_F(count, dim=3, scale=0.3, seed=0):
    """Deformation gradients near I (dim = 2: embedded with F_33 = 1), about one in ten inverted."""
    rng = np.random.default_rng(seed)
    F = np.tile(np.eye(3), (count, 1, 1))
    F[:, :dim, :dim] += scale * rng.standard_normal((count, dim, dim))
    return F


@pytest.mark.parametrize("law", LAWS.values(), ids=LAWS.keys())
def test_stress_and_stress_derivative_match_finite_differences(law):
    F, h = random_F(30), 1e-6
    _, P, M = at(law, F)
    P_fd, M_fd = np.empty_like(P), np.empty_like(M)
    for c in range(9):
        step = np.zeros(9)
        step[c] = h
        (psi_plus, P_plus, _), (psi_minus, P_minus, _) = (at(law, F + s * step.reshape(3, 3)) for s in (1, -1))
        P_fd[:, c // 3, c % 3] = (psi_plus - psi_minus) / (2 * h)
        M_fd[:, :, c] = (P_plus - P_minus).reshape(-1, 9) / (2 * h)
    assert np.abs(P - P_fd).max() < 1e-7 * np.abs(P).max()
    assert np.abs(M - M_fd).max() < 1e-7 * np.abs(M).max()
    assert np.allclose(M, M.transpose(0, 2, 1), atol=1e-12 * np.abs(M).max())


@pytest.mark.parametrize("law", LAWS.values(), ids=LAWS.keys())
def test_every_law_is_stress_free_at_rest(law):
    psi, P, _ = at(law, np.eye(3)[None])
    assert psi[0] == 0 and np.abs(P).max() < 1e-12 * MU


def test_stable_neo_hookean_linearises_to_lame_constants_mu_and_lam_minus_mu():
    """At F = I, d2psi/dF2 is the linear elasticity tensor (lam - mu) d_ij d_kl + mu (d_ik d_jl + d_il d_jk):
    that of Saint Venant-Kirchhoff with Lame constants (mu, lam - mu)."""
    d = np.eye(3)
    linear = (
        (LAM - MU) * np.einsum("ij,kl->ijkl", d, d)
        + MU * (np.einsum("ik,jl->ijkl", d, d) + np.einsum("il,jk->ijkl", d, d))
    ).reshape(9, 9)
    assert at(StableNeoHookean, np.eye(3)[None])[2][0] == pytest.approx(linear, abs=1e-9 * MU)
    svk = np.empty((1, 9, 9))
    evaluate(
        SaintVenantKirchhoff, np.eye(3)[None].copy(), np.array([[MU, LAM - MU]]), np.empty(1), np.empty((1, 3, 3)), svk
    )
    assert svk[0] == pytest.approx(linear, abs=1e-9 * MU)


def test_plane_strain_energy_is_the_3d_law_at_unit_thickness_stretch():
    """psi(F) of the stable neo-Hookean 2D law, mu (1 - J) + lam/2 (1 - J)^2 + mu/2 (|F|^2 - 2), at
    F = [[F2, 0], [0, 1]]."""
    F = random_F(20, dim=2)
    F2 = F[:, :2, :2]
    J = np.linalg.det(F2)
    expected = MU * (1 - J) + LAM / 2 * (1 - J) ** 2 + MU / 2 * (np.sum(F2**2, axis=(1, 2)) - 2)
    assert at(StableNeoHookean, F)[0] == pytest.approx(expected, rel=1e-12, abs=1e-12 * MU)


@pytest.mark.parametrize("d", [2, 3])
def test_generic_and_analytic_eigensystems_reconstruct_the_stress_derivative(d):
    """Jacobi's eigenpairs and the analytic ones: orthonormal, V^T diag(lambda) V = d2psi/dF2 (its d x d block),
    eigenvalues those of NumPy's eigh, also at repeated singular values (F = I, a uniaxial stretch) and at
    inverted F."""
    F = random_F(40, dim=d, seed=d)
    F[:3, :d, :d] = [np.eye(d), np.diag([1.3] + [0.9] * (d - 1)), -np.eye(d)[::-1]]
    n, k = len(F), d * d
    parameters = StableNeoHookean.parameters(np.full(n, 1e4), np.full(n, 0.45))
    block = np.ix_(*[[3 * i + j for i in range(d) for j in range(d)]] * 2)
    M = at(StableNeoHookean, F)[2][:, block[0], block[1]]
    scale = np.abs(M).max()
    for law in (JacobiNeoHookean, SvdNeoHookean, StableNeoHookean):
        values, vectors = np.empty((n, k)), np.empty((n, k, k))
        eigensystems(law, d, F, parameters, values, vectors)
        assert np.allclose(vectors @ vectors.transpose(0, 2, 1), np.eye(k), atol=1e-12)
        assert np.abs(np.einsum("nki,nk,nkj->nij", vectors, values, vectors) - M).max() < 1e-10 * scale
        assert np.abs(np.sort(values, axis=1) - np.linalg.eigvalsh(M)).max() < 1e-10 * scale
    assert (values < 0).any(axis=1).mean() > 0.3  # the projection has work to do


def test_the_svd_eigensystem_of_the_isochoric_law_reconstructs_its_stress_derivative():
    """The isochoric polynomial law (every coefficient) through the isotropic laws' SVD path, against NumPy's eigh
    of its d2psi/dF2: orthonormal vectors, V^T diag(lambda) V = M, the same eigenvalues, also at repeated singular
    values (F = I, a uniaxial stretch, an equibiaxial one) where the twists and flips are degenerate."""
    law = LAWS["isochoric_polynomial"]
    F = random_F(60, seed=5)
    F = F[np.linalg.det(F) > 0.2]
    F[:3] = [np.eye(3), np.diag([1.3, 0.9, 0.9]), np.diag([1.2, 1.2, 0.7])]
    n = len(F)
    M = at(law, F)[2]
    scale = np.abs(M).max()
    values, vectors = np.empty((n, 9)), np.empty((n, 9, 9))
    eigensystems(law, 3, F, law_parameters(law, n), values, vectors)
    assert np.allclose(vectors @ vectors.transpose(0, 2, 1), np.eye(9), atol=1e-12)
    assert np.abs(np.einsum("nki,nk,nkj->nij", vectors, values, vectors) - M).max() < 1e-10 * scale
    assert np.abs(np.sort(values, axis=1) - np.linalg.eigvalsh(M)).max() < 1e-10 * scale
    assert (values < 0).any(axis=1).mean() > 0.1  # the projection has work to do


def coarse_body(order, dim=2):
    """A coarse body in a random, partly compressed state: the beam with its chamber commanded to 1.5x (2D), or
    an octant of a spherical shell (3D)."""
    if dim == 3:
        mesh = shell_octant(2, 1, order)
    else:
        scene = reference_scene(
            cy=0.15, chamber_points=16 if order == 2 else 32, max_area=0.05 if order == 2 else 0.02, order=order
        )
        mesh = scene.build().mesh
    return mesh, 0.02 * np.random.default_rng(order).standard_normal(mesh.vertices.shape)


def elastic_model(mesh, law):
    model = EnergyModel(mesh.vertices, force_floor=1.0, energy_resolution=1e-12)
    return model, model.add(Elasticity(model.config, mesh.elements, law, law_parameters(law, mesh.n_elements)))


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("order", [1, 2])
@pytest.mark.parametrize("law", [*LAWS.values(), JacobiNeoHookean], ids=[*LAWS.keys(), "jacobi_neo_hookean"])
def test_elastic_term_energy_gradient_and_hessian_match_finite_differences(law, order, dim):
    mesh, u = coarse_body(order, dim)
    model, term = elastic_model(mesh, law)
    model.set_displacements(u)
    while law.name in BARRIER_LAWS and term.min_determinant() < 0.2:
        u = 0.5 * u
        model.set_displacements(u)
    g = term.gradient().ravel()
    assert np.linalg.norm(g - fd_gradient(model, term, u)) < 1e-6 * np.linalg.norm(g)
    hessian = dense_hessian(model.n_dofs, [term], psd_only=False)
    assert np.linalg.norm(hessian - fd_hessian(model, [term], u)) < 1e-6 * np.linalg.norm(hessian)
    projected = dense_hessian(model.n_dofs, [term], psd_only=True)
    assert np.linalg.eigvalsh(projected).min() > -1e-9 * np.abs(projected).max()


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("order", [1, 2])
def test_generic_path_gives_the_analytic_hessian(order, dim):
    mesh, u = coarse_body(order, dim)
    model, analytic = elastic_model(mesh, StableNeoHookean)
    model.set_displacements(u)
    for generic in (JacobiNeoHookean, SvdNeoHookean):
        generic_model, term = elastic_model(mesh, generic)
        generic_model.set_displacements(u)
        for psd_only in (True, False):
            expected = analytic.hessian_values(psd_only)
            assert np.abs(term.hessian_values(psd_only) - expected).max() < 1e-10 * np.abs(expected).max()


def test_a_new_law_drives_a_solve():
    """The worked example: the beam of Saint Venant-Kirchhoff material (Lame constants mu, lam - mu, so that it
    linearises to the neo-Hookean beam) inflates to equilibrium, and under a small inflation (0.1 %) it bends as
    the neo-Hookean beam does."""
    built = reference_scene(cy=0.15, chamber_points=32, max_area=0.02).build()
    mesh, tips = built.mesh, []
    for law, (mu, lam) in ((StableNeoHookean, (MU, LAM)), (SaintVenantKirchhoff, (MU, LAM - MU))):
        model = EnergyModel(mesh.vertices, force_floor=1e-6 * (MU + LAM), energy_resolution=1e-12 * (MU + LAM))
        model.add(Elasticity(model.config, mesh.triangles, law, np.tile([mu, lam], (mesh.n_triangles, 1))))
        chamber = model.add(AreaControl(1e5).term(model.config, mesh.chambers[0], "main", 1))
        model.add(Clamp(model.config, mesh.pinned, 1e9))
        chamber.set_command(1.001)
        u, record = NewtonSolver(model).solve(np.zeros_like(mesh.vertices))
        assert record.converged
        tips.append(u[mesh.tip, 1].mean())
    assert tips[1] == pytest.approx(tips[0], rel=3e-3)  # (the gap is of the order of the strain: 1.2 % at 1.01)
