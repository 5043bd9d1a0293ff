"""Hyper-reduction of the fibres and the sheets (terms/base.py Term.restricted, reduce/ecsw.py per piecewise term):
on a quadratic box with a cavity, a crossed pair of stiff cords round it and a wrinkling sheet on its bottom face,
the cords restricted to segments and the sheet to cells are the weighted sums of those pieces; the reduced model of
the scene evaluates no term on the full field, is the projected full model with every piece at weight 1, and its
gradient and Hessian are those of its energy; ECSW fits each term's projected snapshot forces on its own."""

import numpy as np
import pytest
import scipy.sparse as sp
from solid_meshes import box_with_cavity, scene_of

from taichi_pneuma import runtime
from taichi_pneuma.errors import PneumaInputError
from taichi_pneuma.fem.fiber_paths import Crossed
from taichi_pneuma.reduce.ecsw import piecewise_terms, sample_terms
from taichi_pneuma.reduce.exact import projected
from taichi_pneuma.reduce.model import ReducedModel, every_piece
from taichi_pneuma.reduce.train import ECSW_TOL, train
from taichi_pneuma.scene.build import Material
from taichi_pneuma.scene.schedule import ChamberSchedule
from taichi_pneuma.solve.newton import NewtonOptions
from taichi_pneuma.terms.base import block_pattern
from taichi_pneuma.terms.fibers import Fiber
from taichi_pneuma.terms.sheets import Layer

MODES = 6


@pytest.fixture(scope="module")
def built():
    runtime.ensure_initialised()
    crossed = Fiber(Crossed((-1.7, -0.2, 0.0), 0.15, 2.0, "x", angle=40.0), 3e6, area=1e-4)
    sheet = Layer("sheet", 1e6, 0.3, 0.01, side="bottom")
    return scene_of(
        box_with_cavity(2), [ChamberSchedule("pressure", ((2, 1000.0),))], 2, Material(1e4, 0.3),
        fibers=(crossed,), layers=(sheet,),
    ).build()  # fmt: skip


def stretched(built, seed: int) -> np.ndarray:
    """Displacements (n, d): the body stretched 5 % along x and y, plus a random 1 % of its size."""
    X = built.mesh.vertices
    noise = np.random.default_rng(seed).standard_normal(X.shape)
    return 0.05 * X * np.array([1.0, 1.0, 0.0]) + 0.01 * float(np.ptp(X, axis=0).max()) * noise


def at_state(term, u):
    term.config.u[:] = u[term.vertices]
    return term


def dense(term, n: int) -> np.ndarray:
    return sp.coo_matrix((term.hessian_values(), term.hessian_pattern()), shape=(n, n)).toarray()


@pytest.mark.parametrize("name", ["fibers", "membrane"])
def test_a_restricted_term_is_the_weighted_sum_of_its_pieces(built, name):
    """All pieces at weight 1: the full term's energy, gradient and Hessian; weighted: the weighted sum of the
    one-piece terms; apart: each piece's own forces, summing to the full gradient; the Hessian one dense block per
    piece on its nodes."""
    term = piecewise_terms(built.model.terms)[name]
    u = stretched(built, 1)
    built.model.set_displacements(u)
    P, d = term.n_pieces, 3
    whole = at_state(term.restricted(np.arange(P), np.ones(P)), u)
    g = term.gradient()
    assert whole.energy() == pytest.approx(term.energy(), rel=1e-12)
    assert term.energy() > 0  # stretched: the cords taut, the sheet in tension somewhere
    assert np.allclose(whole.gradient(), g[whole.vertices], rtol=0, atol=1e-12 * np.abs(g).max())
    dofs = (d * whole.vertices[:, None] + np.arange(d)).ravel()
    full_H = dense(term, built.model.n_dofs)[np.ix_(dofs, dofs)]
    assert np.allclose(dense(whole, len(dofs)), full_H, rtol=0, atol=1e-12 * np.abs(full_H).max())
    rows, cols = block_pattern(whole.piece_nodes(), d)
    assert np.array_equal(whole.hessian_pattern()[0], rows) and np.array_equal(whole.hessian_pattern()[1], cols)

    rng = np.random.default_rng(2)
    some = np.sort(rng.choice(P, min(P, 12), replace=False))
    weights = 0.5 + rng.random(len(some))
    singles = [at_state(term.restricted(np.array([p]), np.ones(1)), u) for p in some]
    weighted = at_state(term.restricted(some, weights), u)
    assert weighted.energy() == pytest.approx(weights @ [s.energy() for s in singles], rel=1e-12)
    summed = np.zeros_like(u)
    for w, single in zip(weights, singles, strict=True):
        np.add.at(summed, single.vertices, w * single.gradient())
    local = np.zeros_like(u)
    np.add.at(local, weighted.vertices, weighted.gradient())
    assert np.allclose(local, summed, rtol=0, atol=1e-12 * np.abs(summed).max())

    apart = at_state(term.restricted(np.arange(P), np.ones(P), apart=True), u)
    assert len(np.unique(apart.vertices)) < len(apart.vertices) == apart.piece_nodes().size  # nodes copied
    summed = np.zeros_like(u)
    np.add.at(summed, apart.vertices, apart.gradient())
    assert np.allclose(summed, g, rtol=0, atol=1e-12 * np.abs(g).max())


def test_restricted_cords_keep_their_branches(built):
    """The restricted cords start on their own branches and choose them as the full term does: taut or slack at
    u + dx, the same segments changing, the same Hessian."""
    term = piecewise_terms(built.model.terms)["fibers"]
    u = stretched(built, 3)
    built.model.set_displacements(u)
    P = term.n_pieces
    restricted = at_state(term.restricted(np.arange(P), np.ones(P)), u)
    dx = -1.2 * u  # past the rest state: the stretched cords go slack
    changed = term.choose_branches(dx)
    assert changed > 0
    assert restricted.choose_branches(dx[restricted.vertices]) == changed
    dofs = (3 * restricted.vertices[:, None] + np.arange(3)).ravel()
    expected = dense(term, built.model.n_dofs)[np.ix_(dofs, dofs)]
    assert np.allclose(dense(restricted, len(dofs)), expected, rtol=0, atol=1e-12 * np.abs(expected).max() + 1e-300)
    term.choose_branches(None)


def test_the_reduced_model_with_every_piece_is_the_projected_full_model(built):
    """Every piecewise term sampled whole at weight 1, on a random orthonormal basis: no term on the full field,
    g_r = V^T g(V q), H_r = V^T H(V q) V, and central differences of E_r and g_r give g_r and H_r."""
    built.set_commands(np.array([600.0]))
    basis = np.linalg.qr(np.random.default_rng(4).standard_normal((built.model.n_dofs, MODES)))[0]
    model = ReducedModel(built, basis, every_piece(built))
    assert not model.whole and set(model.sampled) == {"elastic", "fibers", "membrane"}
    q = basis.T @ stretched(built, 5).ravel()
    model.set_coordinates(q)
    built.model.set_displacements(basis @ q)
    g_full, _ = built.model.gradient()
    H_full = projected(basis, *built.model.hessian_pattern(), built.model.hessian_values())
    g, _ = model.gradient()
    H = model.hessian()
    assert model.energy() == pytest.approx(built.model.energy(), rel=1e-11)
    assert np.linalg.norm(g - basis.T @ g_full) <= 1e-10 * np.linalg.norm(g)
    assert np.linalg.norm(H - H_full) <= 1e-10 * np.linalg.norm(H)

    direction = np.random.default_rng(6).standard_normal(MODES)
    h = 1e-5 * np.linalg.norm(q) / np.linalg.norm(direction)

    def at(x):
        model.set_coordinates(x)
        return model.energy(), model.gradient()[0]

    (e_plus, g_plus), (e_minus, g_minus) = at(q + h * direction), at(q - h * direction)
    assert (e_plus - e_minus) / (2 * h) == pytest.approx(g @ direction, rel=1e-6)
    assert np.linalg.norm((g_plus - g_minus) / (2 * h) - H @ direction) <= 1e-6 * np.linalg.norm(H @ direction)


def test_a_term_with_no_force_in_any_snapshot_gets_no_pieces(built):
    """Snapshots of the body shrunk uniformly: every cord is slack and the wrinkling sheet slack, exactly no force,
    the rubber compressed: ECSW gives the cords and the sheet no pieces, and a reduced model leaves them out (not
    evaluated whole)."""
    basis = np.linalg.qr(np.random.default_rng(7).standard_normal((built.model.n_dofs, MODES)))[0]
    shrunk = np.stack([-s * built.mesh.vertices.ravel() for s in (0.02, 0.05)])
    sampling = sample_terms(built.model.terms, basis, shrunk, ECSW_TOL)
    assert len(sampling["elastic"].pieces) > 0
    for name in ("fibers", "membrane"):
        assert len(sampling[name].pieces) == 0 and sampling[name].error == 0.0
    model = ReducedModel(built, basis, {label: (s.pieces, s.weights) for label, s in sampling.items()})
    assert set(model.sampled) == {"elastic"} and not model.whole


def test_pieces_of_another_term_or_past_a_terms_count_are_refused_in_one_line(built):
    basis = np.eye(built.model.n_dofs)[:, :MODES]
    fibers = piecewise_terms(built.model.terms)["fibers"]
    for samples in ({"fibres": (np.array([0]), np.ones(1))}, {"fibers": (np.array([fibers.n_pieces]), np.ones(1))}):
        with pytest.raises(PneumaInputError, match=r"^the sampled pieces of 'fib(er|re)s' do not fit this scene \("):
            ReducedModel(built, basis, samples)


@pytest.fixture(scope="module")
def trained(built):
    return train(built, modes=4, samples=3, options=NewtonOptions(tol=1e-9))


def test_ecsw_fits_each_terms_projected_forces_with_fewer_pieces(trained):
    """Each piecewise term has its own fit: fewer pieces than it has, positive weights, and its sampled projected
    force matches V^T f(u_s) over the loaded snapshots to the tolerance (root mean square of the relative errors)."""
    model, snapshots = trained.model, trained.snapshots
    built = model.built
    terms = piecewise_terms(built.model.terms)
    assert set(trained.sampling) == set(model.sampled) == {"elastic", "fibers", "membrane"} and not model.whole
    for label, sampled in model.sampled.items():
        pieces, weights = model.samples[label]
        assert 0 < len(pieces) < terms[label].n_pieces and np.all(weights > 0)
        assert trained.sampling[label].error <= ECSW_TOL
        fits = []
        for u in snapshots.displacements:
            built.model.set_displacements(u)
            sampled.set_displacements(u)
            fits.append((model.basis.T @ terms[label].gradient().ravel(), sampled.gradient()))
        largest = max(np.linalg.norm(full) for full, _ in fits)
        errors = [np.sum((s - f) ** 2) / np.sum(f**2) for f, s in fits if np.linalg.norm(f) > 1e-12 * largest]
        assert np.sqrt(np.mean(errors)) <= ECSW_TOL * (1 + 1e-6)
