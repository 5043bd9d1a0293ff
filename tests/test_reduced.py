"""The reduced-order model (taichi_pneuma/reduce/): POD basis, ECSW sampling, reduced Newton, indicator, store.

On a coarse reference beam (about 230 vertices) whose area ramp runs from 1 to 2.5 in 7 increments, trained on the
ramp and 6 Latin hypercube points."""

import numpy as np
import pytest
from fd import check_reduced_derivatives

import taichi_pneuma as tp
from taichi_pneuma.errors import PneumaInputError
from taichi_pneuma.reduce.model import ReducedModel, every_piece
from taichi_pneuma.reduce.pod import pod_basis
from taichi_pneuma.reduce.solve import equilibrium, indicator
from taichi_pneuma.reduce.store import load_reduced, save_reduced
from taichi_pneuma.reduce.train import ECSW_TOL, train
from taichi_pneuma.solve.newton import NewtonOptions, NewtonSolver
from taichi_pneuma.solve.simulate import settle

COARSE = {
    "mesh.max_area": 0.01,
    "chambers[0].points": 32,
    "schedule.increments": 7,
    "chambers[0].keyframes": [[0, 1.0], [7, 2.5]],
}
TIGHT = NewtonOptions(tol=1e-9)
HELD_OUT = (1.37, 2.21)  # area ratios inside the training range, none of them trained on


def coarse_scene(**changes):
    return tp.load_scene("reference_beam").with_values({**COARSE, **changes})


@pytest.fixture(scope="module")
def trained():
    built = coarse_scene().build()
    return train(built, modes=8, samples=6, options=TIGHT)


def full_equilibrium(built, ratio: float) -> np.ndarray:
    """The full model's equilibrium (n d,) at area ratio `ratio`, from rest, to the tolerance 1e-9."""
    rest = built.scene.schedule.rest_commands
    built.set_commands(rest)
    u, *_ = settle(built, NewtonSolver(built.model, TIGHT), rest, np.zeros_like(built.mesh.vertices), np.array([ratio]))
    return u.ravel()


def test_all_modes_and_all_elements_reproduce_the_full_model(trained):
    built = trained.model.built
    n = built.model.n_dofs
    whole = ReducedModel(built, np.eye(n), every_piece(built))
    rest = built.scene.schedule.rest_commands
    solved = equilibrium(whole, np.array([2.0]), (rest, np.zeros(n)), tol=1e-9)
    u = full_equilibrium(built, 2.0)
    assert solved.converged
    assert np.linalg.norm(solved.q - u) <= 1e-8 * np.linalg.norm(u)


def test_the_error_at_held_out_commands_falls_as_modes_are_added(trained):
    built, snapshots = trained.model.built, trained.snapshots
    errors = []
    for modes in (2, 4, 8):
        basis, _, _ = pod_basis(snapshots.displacements, modes=modes)
        model = ReducedModel(built, basis, every_piece(built), (snapshots.commands, snapshots.displacements @ basis))
        error = 0.0
        for ratio in HELD_OUT:
            reduced = equilibrium(model, np.array([ratio]), tol=1e-9)
            u = full_equilibrium(built, ratio)
            error = max(error, float(np.linalg.norm(basis @ reduced.q - u) / np.linalg.norm(u)))
        errors.append(error)
    assert errors[0] > errors[1] > errors[2]
    assert errors[2] < 1e-4


def test_ecsw_reproduces_the_projected_snapshot_forces_with_fewer_elements(trained):
    model, snapshots = trained.model, trained.snapshots
    built = model.built
    assert 0 < len(model.elements) < built.mesh.n_elements
    assert np.all(model.samples["elastic"][1] > 0)
    fits = []
    for u in snapshots.displacements:
        built.model.set_displacements(u)
        sampled = model.sampled["elastic"]
        sampled.set_displacements(u)
        fits.append((model.basis.T @ built.elastic.gradient().ravel(), sampled.gradient()))
    largest = max(np.linalg.norm(full) for full, _ in fits)
    errors = [
        np.sum((sampled - full) ** 2) / np.sum(full**2)
        for full, sampled in fits
        if np.linalg.norm(full) > 1e-12 * largest
    ]
    assert len(errors) == len(fits) - 1  # all but the rest state, which has no force to fit
    assert trained.sampling["elastic"].error <= ECSW_TOL
    assert np.sqrt(np.mean(errors)) <= ECSW_TOL * (1 + 1e-6)


def test_the_reduced_gradient_and_hessian_are_those_of_the_reduced_energy(trained):
    model = trained.model
    model.built.set_commands(np.array([2.0]))
    q = model.training[1][5]
    direction = np.random.default_rng(1).standard_normal(model.n_modes)
    direction *= 1e-3 * np.linalg.norm(q) / np.linalg.norm(direction)
    h = 1e-3

    check_reduced_derivatives(model, q, direction, h)


def test_the_indicator_flags_commands_outside_the_training_range(trained):
    model = trained.model
    inside = equilibrium(model, np.array([2.2]))
    outside = equilibrium(model, np.array([3.0]))
    assert indicator(model, np.array([2.2]), inside.q).inside
    flagged = indicator(model, np.array([3.0]), outside.q)
    assert not flagged.inside
    assert flagged.outside == [(0, 3.0, 1.0, 2.5)]


def test_a_changed_scene_refuses_an_old_reduced_model(trained, tmp_path):
    path = tmp_path / "beam.npz"
    save_reduced(path, trained.model, trained.singular_values)
    loaded = load_reduced(path, trained.model.built)
    assert np.array_equal(loaded.basis, trained.model.basis)
    for saved, read in zip(trained.model.samples["elastic"], loaded.samples["elastic"], strict=True):
        assert np.array_equal(saved, read)
    with np.load(path) as data:  # the first format: the elastic term's elements and weights, no label
        first = {name: data[name] for name in ("basis", "commands", "coordinates", "singular_values", "scene_sha256")}
        first["elements"], first["weights"] = data["pieces_elastic"], data["weights_elastic"]
    np.savez(tmp_path / "first.npz", **first)
    old = load_reduced(tmp_path / "first.npz", trained.model.built)
    assert np.array_equal(old.elements, trained.model.elements) and not old.whole
    changed = coarse_scene(**{"material.E": 2e4}).build()
    with pytest.raises(PneumaInputError, match="was trained for another scene"):
        load_reduced(path, changed)


def test_pneuma_reduce_trains_validates_and_saves(tmp_path, capsys):
    from taichi_pneuma.apps.reduce import main

    sets = [f"--set={key}={value}" for key, value in COARSE.items()]
    assert main(["--scene", "reference_beam", *sets, "--modes", "4", "--samples", "3", "--held-out", "2",
                 "--out", str(tmp_path)]) == 0  # fmt: skip
    printed = capsys.readouterr().out
    assert "basis: 4 modes keep" in printed and "time per equilibrium" in printed
    (saved,) = tmp_path.glob("*_reduced.npz")
    built = coarse_scene().build()
    assert load_reduced(saved, built).n_modes == 4


def test_pneuma_reduce_refuses_bad_flags_in_one_line(tmp_path, capsys):
    from taichi_pneuma.apps.reduce import main

    assert main(["--scene", "reference_beam", "--modes", "0", "--out", str(tmp_path)]) == 2
    assert capsys.readouterr().err == "error: --modes = 0 must be >= 1\n"
    assert not any(tmp_path.iterdir())


def test_elasticity_that_couples_the_elements_is_refused_before_any_solve(monkeypatch):
    import taichi_pneuma.reduce.train as training

    monkeypatch.setattr(training, "solve_snapshots", lambda *args: pytest.fail("solved before refusing"))
    nodal = {"mesh.volumetric": "nodal", "material.law": "neo_hookean", "material.C10": 1700.0, "material.K": 3e4}
    with pytest.raises(PneumaInputError, match="volumetric = 'nodal' couples the elements"):
        training.train(coarse_scene(**nodal).build(), modes=2)
