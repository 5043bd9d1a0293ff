"""The chambers and quadratic terms of a reduced model, exact in its coordinates (taichi_pneuma/reduce/exact.py),
against the full terms evaluated at u = V q, on an arbitrary orthonormal basis: a quadratic 3D box with a closed
cavity (its volume a cubic in u), each chamber kind, and the quarter shell whose cavity is closed by symmetry
planes (an open wall); and the elastic term restricted to sampled elements (Elasticity.restricted), with one
pressure per element too."""

import numpy as np
import pytest
from fd import check_reduced_derivatives
from solid_meshes import box_with_cavity, scene_of, shell_octant

from taichi_pneuma.materials import IsochoricMaterial, IsochoricPolynomial
from taichi_pneuma.reduce.exact import ReducedChamber, projected
from taichi_pneuma.reduce.model import ReducedModel, every_piece
from taichi_pneuma.scene.build import Material
from taichi_pneuma.scene.schedule import ChamberSchedule
from taichi_pneuma.terms import VOLUMETRIC
from taichi_pneuma.terms.chambers.syringe import Syringe
from taichi_pneuma.terms.model import EnergyModel

MODES = 6
COMMANDS = {"pressure": 800.0, "area": 1.4, "closed_gas": 0.3, "syringe": 0.2}


def random_basis(n: int, seed: int = 0) -> np.ndarray:
    return np.linalg.qr(np.random.default_rng(seed).standard_normal((n, MODES)))[0]


def coordinates(built, basis, fraction: float, seed: int = 1) -> np.ndarray:
    """q whose largest nodal displacement V q is `fraction` of the body's size."""
    q = np.random.default_rng(seed).standard_normal(basis.shape[1])
    size = float(np.ptp(built.mesh.vertices, axis=0).max())
    return q * fraction * size / np.abs(basis @ q).max()


def full_parts(chamber, basis):
    """The full chamber term at the model's state, projected: energy, V^T g, V^T H V (rank-one part included),
    V^T (-dr/dc)."""
    g = basis.T @ chamber.gradient().ravel()
    H = projected(basis, *chamber.hessian_pattern(), chamber.hessian_values())
    for dofs, a, c in chamber.low_rank():
        b = basis[dofs].T @ a
        H += c * np.outer(b, b)
    return chamber.energy(), g, H, basis[chamber.dofs].T @ chamber.command_force()


@pytest.fixture(scope="module")
def box():
    return box_with_cavity(order=2)


@pytest.mark.parametrize("kind", sorted(COMMANDS))
def test_a_reduced_chamber_is_the_full_one_at_v_q(box, kind):
    control = Syringe(syringe_volume=0.5, dead_volume=0.1) if kind == "syringe" else kind
    built = scene_of(box, [ChamberSchedule(control, ((1, COMMANDS[kind]),))], 1, Material(1e4, 0.45)).build()
    built.set_commands(np.array([COMMANDS[kind]]))
    basis = random_basis(built.model.n_dofs)
    chamber = built.chambers[0]
    reduced = ReducedChamber(chamber, basis)
    for fraction in (0.0, 0.03, 0.1):
        q = coordinates(built, basis, fraction)
        built.model.set_displacements((basis @ q).reshape(-1, 3))
        reduced.set_coordinates(q)
        energy, g, H, c = full_parts(chamber, basis)
        assert reduced.area == pytest.approx(chamber.area(), rel=1e-11)
        assert reduced.energy() == pytest.approx(energy, rel=1e-10, abs=1e-10 * abs(chamber.pressure()))
        assert np.linalg.norm(reduced.gradient() - g) <= 1e-9 * np.linalg.norm(g) + 1e-12
        assert np.linalg.norm(reduced.hessian(False) - H) <= 1e-9 * np.linalg.norm(H)
        assert np.linalg.norm(reduced.command_force() - c) <= 1e-9 * np.linalg.norm(c)


def test_the_gas_step_bound_is_the_full_ones(box):
    built = scene_of(box, [ChamberSchedule("closed_gas", ((1, 0.0),))], 1, Material(1e4, 0.45)).build()
    basis = random_basis(built.model.n_dofs, 3)
    reduced = ReducedChamber(built.chambers[0], basis)
    q = coordinates(built, basis, 0.05, 4)
    built.model.set_displacements((basis @ q).reshape(-1, 3))
    reduced.set_coordinates(q)
    chamber = built.chambers[0]
    shrink = -basis[chamber.dofs].T @ chamber.area_and_gradient()[1].ravel()  # along -dA/dq: the cavity shrinks
    shrink *= float(np.ptp(built.mesh.vertices, axis=0).max()) / np.abs(basis @ shrink).max()
    full = built.chambers[0].max_step((basis @ shrink).reshape(-1, 3))
    assert np.isfinite(full)
    assert reduced.max_step(shrink) == pytest.approx(full, rel=1e-8)


def test_an_open_wall_closed_by_symmetry_planes_is_exact_too():
    built = scene_of(
        shell_octant(3, 2, order=2), [ChamberSchedule("pressure", ((1, 50.0),))], 1, Material(1e3, 0.45)
    ).build()
    built.set_commands(np.array([50.0]))
    basis = random_basis(built.model.n_dofs, 5)
    reduced = ReducedChamber(built.chambers[0], basis)
    q = coordinates(built, basis, 0.05, 6)
    built.model.set_displacements((basis @ q).reshape(-1, 3))
    reduced.set_coordinates(q)
    energy, g, H, _ = full_parts(built.chambers[0], basis)
    assert reduced.energy() == pytest.approx(energy, rel=1e-10)
    assert np.linalg.norm(reduced.gradient() - g) <= 1e-9 * np.linalg.norm(g)
    assert np.linalg.norm(reduced.hessian(False) - H) <= 1e-9 * np.linalg.norm(H)


def test_the_reduced_models_energy_gradient_and_hessian_agree_with_finite_differences(box):
    """A 3D model on every element, its chamber (a gas) and clamp exact in q: central differences of E_r and g_r."""
    built = scene_of(box, [ChamberSchedule("closed_gas", ((1, 0.3),))], 1, Material(1e4, 0.45)).build()
    built.set_commands(np.array([0.3]))
    basis = random_basis(built.model.n_dofs, 7)
    model = ReducedModel(built, basis, every_piece(built))
    assert not model.whole  # the chamber and the clamp are exact: no term evaluated on the full field
    q = coordinates(built, basis, 0.02, 8)
    direction = np.random.default_rng(9).standard_normal(MODES)
    h = 1e-4 * np.linalg.norm(q) / np.linalg.norm(direction)

    check_reduced_derivatives(model, q, direction, h)


@pytest.mark.parametrize("volumetric", ["element", "mixed"])
def test_the_restricted_elastic_term_is_the_weighted_sum_of_its_elements(volumetric):
    """Elasticity.restricted, what ECSW samples and the reduced model evaluates: on a quadratic shell of a
    nearly incompressible Yeoh rubber (with one pressure per element too), the term on all elements is the full
    term, weighted it is the weighted sum of the one-element terms, and its elements apart give each element's own
    forces, which sum to the full gradient."""
    mesh = shell_octant(2, 1, 2)
    m = mesh.n_elements
    parameters = np.tile(IsochoricMaterial("yeoh", 1.0, C20=0.2, poisson_ratio=0.49).row(), (m, 1))
    model = EnergyModel(mesh.vertices, 1.0, 1e-12)
    term = model.add(VOLUMETRIC[volumetric](model.config, mesh.elements, IsochoricPolynomial, parameters))
    rng = np.random.default_rng(2)
    model.set_displacements(0.03 * rng.standard_normal(mesh.vertices.shape))

    def at_state(restricted):
        restricted.config.u[:] = model.config.u[restricted.vertices]
        return restricted

    whole = at_state(term.restricted(np.arange(m), np.ones(m)))
    assert whole.energy() == pytest.approx(term.energy(), rel=1e-12)
    assert np.allclose(
        whole.gradient(), term.gradient()[whole.vertices], rtol=0, atol=1e-12 * np.abs(term.gradient()).max()
    )
    weights = 0.5 + rng.random(m)
    singles = [at_state(term.restricted(np.array([e]), np.ones(1))).energy() for e in range(m)]
    assert at_state(term.restricted(np.arange(m), weights)).energy() == pytest.approx(weights @ singles, rel=1e-12)
    apart = at_state(term.restricted(np.arange(m), np.ones(m), apart=True))
    summed = np.zeros_like(model.config.u)
    np.add.at(summed, apart.vertices, apart.gradient())
    assert np.allclose(summed, term.gradient(), rtol=0, atol=1e-12 * np.abs(term.gradient()).max())
