"""Inverse control on a reduced model, polished by the full one (control/reduced.py, pneuma-reach --reduced).

On the coarse reference beam of test_reduced.py (about 230 vertices, area ramp 1 to 2.5), trained on the ramp and 6
Latin hypercube points with 8 modes."""

import json

import numpy as np
import pytest
from test_reduced import TIGHT, coarse_scene

from taichi_pneuma.apps.reach import main
from taichi_pneuma.control.inverse import Reacher, body_length
from taichi_pneuma.control.reduced import ReducedReacher
from taichi_pneuma.reduce.solve import equilibrium, sensitivity
from taichi_pneuma.reduce.store import save_reduced
from taichi_pneuma.reduce.train import train
from taichi_pneuma.scene.targets import Target

QUIET = ["--no-video", "--quiet"]


@pytest.fixture(scope="module")
def trained():
    return train(coarse_scene().build(), modes=8, samples=6, options=TIGHT)


@pytest.fixture(scope="module")
def files(trained, tmp_path_factory):
    """(the coarse scene's TOML file, the model's .npz) as pneuma-reach reads them."""
    folder = tmp_path_factory.mktemp("reduced")
    scene, model = folder / "coarse.toml", folder / "coarse_reduced.npz"
    scene.write_text(coarse_scene().to_toml())
    save_reduced(model, trained.model, trained.singular_values)
    return str(scene), str(model)


def full_tip(built, ratio: float) -> tuple[float, float]:
    """The full model's tip point at area ratio `ratio` (at most 3.5): a target that is reachable."""
    pose = Reacher(built, (np.array([1.0]), np.array([3.5])), start=[ratio]).pose
    return float(pose.tip[0]), float(pose.tip[1])


def test_the_polished_answer_is_the_full_reachers(trained):
    built = trained.model.built
    target = Target(full_tip(built, 2.21), None, (1.0, 1.0, 1.0))
    full = Reacher(built).reach(target)
    reacher = ReducedReacher(trained.model)
    polished = reacher.reach(target)
    tol = reacher.options.tol * body_length(built)
    assert full.reached and polished.reached
    assert np.linalg.norm(polished.pose.tip - full.pose.tip) <= 2 * tol
    assert abs(polished.pose.commands[0] - full.pose.commands[0]) <= 1e-2 * (reacher.hi - reacher.lo)[0]
    phase = polished.reduced
    assert phase is not None and phase.indicator.inside and phase.result.pose.coordinates is not None
    assert polished.pose.coordinates is None  # the answer is the full model's equilibrium
    assert phase.seconds > 0 and phase.polish_seconds > 0
    assert "inside the training box" in phase.summary_line(reacher.names)


def test_the_reduced_sensitivity_is_the_derivative_of_the_reduced_equilibrium(trained):
    model = trained.model
    c, h = 2.0, 1e-3
    q = equilibrium(model, np.array([c]), tol=1e-12).q
    sens = sensitivity(model, np.array([c]), q)
    plus, minus = (equilibrium(model, np.array([c + s]), (np.array([c]), q), tol=1e-12).q for s in (h, -h))
    fd = (plus - minus) / (2 * h)
    assert np.linalg.norm(sens.coordinates[:, 0] - fd) <= 1e-4 * np.linalg.norm(fd)
    assert np.allclose(sens.displacements[..., 0], model.displacements(sens.coordinates[:, 0]))


def test_reach_with_a_reduced_model_prints_its_phase_and_records_it(files, trained, capsys, tmp_path):
    scene, model = files
    target = ["--tip", *(f"{v:.6f}" for v in full_tip(trained.model.built, 1.8))]
    assert main(["--scene", scene, *target, "--reduced", model, "--no-video", "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[-1].startswith("reached: ")
    assert any(line.strip().startswith("reduced: tip error") for line in out)
    summary = json.loads(next(tmp_path.glob("*_summary.json")).read_text())
    assert summary["reduced"]["indicator_residual"] > 0 and summary["reduced"]["outside_training"] == []


def test_a_trajectory_on_a_reduced_model_reaches_every_target(files, trained, capsys, tmp_path):
    scene, model = files
    tips = [full_tip(trained.model.built, ratio) for ratio in (1.6, 2.3)]
    (tmp_path / "targets.csv").write_text("x,y\n" + "".join(f"{x:.6f},{y:.6f}\n" for x, y in tips))
    flags = ["--targets", str(tmp_path / "targets.csv"), "--reduced", model, "--no-video", "--out", str(tmp_path)]
    assert main(["--scene", scene, *flags]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[-1].startswith("reached: all 2 targets in order")
    assert sum(line.strip().startswith("reduced: ") for line in out) == 2
    summary = json.loads(next(tmp_path.glob("*_summary.json")).read_text())
    assert all("reduced" in reach for reach in summary["reaches"])


def test_commands_outside_the_training_box_are_named_and_still_polished(files, trained, capsys, tmp_path):
    scene, model = files
    built = trained.model.built
    x, y = full_tip(built, 3.3)  # the model was trained up to 2.5
    flags = ["--tip", f"{x:.6f}", f"{y:.6f}", "--bounds", "main", "1", "3.5", "--no-video", "--out", str(tmp_path)]
    assert main(["--scene", scene, *flags, "--reduced", model]) == 0
    out = capsys.readouterr().out
    assert "chamber 'main' at 2.5" not in out and "outside its training range 1 .. 2.5 (extrapolated)" in out
    assert out.splitlines()[-1].startswith("reached: ")


def test_a_model_of_another_scene_is_refused_with_one_line(files, capsys, tmp_path):
    scene, model = files
    flags = ["--scene", scene, "--set", "E=300", "--tip", "1.9", "-0.1", "--reduced", model, "--out", str(tmp_path)]
    assert main([*flags, *QUIET]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("error: reduced model ") and "trained for another scene" in err[0]


def test_reduced_with_output_is_refused_with_one_line(files, capsys, tmp_path):
    scene, model = files
    flags = ["--scene", scene, "--output", "tip_rotation", "--value", "-3", "--reduced", model, "--out", str(tmp_path)]
    assert main([*flags, *QUIET]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == ["error: --reduced works with --tip and --targets (not --output, --design or --interactive)"]


def test_a_missing_model_file_is_one_error_line(files, capsys, tmp_path):
    scene, _ = files
    flags = ["--scene", scene, "--tip", "1.9", "-0.1", "--reduced", str(tmp_path / "none.npz"), "--out", str(tmp_path)]
    assert main([*flags, *QUIET]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("error: reduced model ") and "cannot be read" in err[0]
