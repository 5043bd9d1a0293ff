"""A reduced model's training snapshots solved on workers (reduce/snapshots.py with study/executors.py): the
hypercube points solved in a process pool or as Ray tasks are the equilibria solved here, to the Newton tolerance;
pneuma-reduce --workers and --ray train the same model as without.

On a coarse reference beam (374 vertices; its schedule 1 .. 2.5 in 35 increments) and 6 hypercube points."""

import json
import subprocess
import sys

import numpy as np
import pytest

import taichi_pneuma as tp
from taichi_pneuma.reduce.snapshots import PointsTask, solve_points, solve_snapshots
from taichi_pneuma.solve.newton import NewtonOptions
from taichi_pneuma.study import LocalPool

COARSE = {"mesh.max_area": 0.01}
SAMPLES = 6
TIGHT = NewtonOptions(tol=1e-9)


@pytest.fixture(scope="module")
def built():
    tp.init("cpu")
    return tp.load_scene("reference_beam").with_values(COARSE).build()


def by_commands(snapshots) -> dict:
    return {tuple(np.round(c, 12)): u for c, u in zip(snapshots.commands, snapshots.displacements)}


def test_points_solved_in_a_process_pool_are_those_solved_here(built):
    here = by_commands(solve_snapshots(built, SAMPLES, 0, TIGHT))
    with LocalPool(2) as pool:
        there = by_commands(solve_snapshots(built, SAMPLES, 0, TIGHT, pool))
    assert sorted(here) == sorted(there) and len(here) == 36 + SAMPLES
    scale = max(np.abs(u).max() for u in here.values())
    assert max(np.abs(here[c] - there[c]).max() for c in here) <= 1e-7 * scale


def test_a_chunk_that_cannot_run_is_one_error_not_an_exception(built):
    wrong = np.zeros((1, built.model.n_dofs + 2))  # states of another mesh
    row = solve_points(PointsTask(built.scene.to_toml(), np.ones((1, 1)), wrong, np.full((1, 1), 1.5), None))
    assert row["commands"] is None and row["failed"] == 1
    assert (
        row["error"]
        == f"PneumaInputError: the worker's mesh has {built.model.n_dofs} DOFs, the scene's {wrong.shape[1]}"
    )


@pytest.mark.slow
def test_pneuma_reduce_on_a_local_ray_trains_the_model_trained_here(tmp_path):
    pytest.importorskip("ray")
    flags = ["--samples", str(SAMPLES), "--modes", "8", "--set", "mesh.max_area=0.01", "--tol", "1e-9"]
    records = {}
    for name, extra in (("here", []), ("ray", ["--ray", "--workers", "2"])):
        out = tmp_path / name
        proc = subprocess.run(
            [sys.executable, "-m", "taichi_pneuma.apps.reduce", *flags, *extra, "--out", str(out)],
            capture_output=True,
            text=True,
            timeout=300,
        )
        assert proc.returncode == 0, proc.stderr
        records[name] = json.loads(next(out.glob("*_reduced.json")).read_text())
    assert "hypercube points solved in ray (" in proc.stdout
    assert records["ray"]["training_executor"]["ray_cpus"] == 2
    here, ray = records["here"]["held_out"], records["ray"]["held_out"]
    assert [h["commands"] for h in here] == [r["commands"] for r in ray]
    for h, r in zip(here, ray):
        assert r["tip_error_percent"] == pytest.approx(h["tip_error_percent"], rel=1e-3, abs=1e-6)
