"""The design optimiser (study/goals.py, study/optimize.py, apps/optimize.py): expressions on a run's record, analytic
objectives with known optima (no FEM), a small 2D scene whose recorded objectives are those of the same designs run
alone, the app on the process pool and on a local Ray, resuming after a kill, and every refusal."""

import csv
import json
import os
import signal
import sqlite3
import subprocess
import sys
import textwrap
import time

import numpy as np
import pytest

import taichi_pneuma as tp
from taichi_pneuma.apps.optimize import main
from taichi_pneuma.study import LocalPool
from taichi_pneuma.study.goals import Goals, NoValue, crossing
from taichi_pneuma.study.optimize import InProcess

CY = "chambers[0].center[1]"
COARSE = ["--steps", "11", "--max-area", "0.01"]  # the reference beam in ~0.1 s a ramp (tests/test_study.py)
BEAM = tp.reference_scene(steps=11, max_area=0.01)


def record(summary=None, **history):
    return {"summary": summary or {}, "history": {k: np.asarray(v, dtype=float) for k, v in history.items()}}


def read_rows(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


# --- expressions ---------------------------------------------------------------------------------


def test_at_interpolates_where_a_column_first_reaches_a_level():
    x, y = np.array([0.0, -2.0, -6.0, -3.0, -9.0]), np.array([0.0, 10.0, 20.0, 30.0, 40.0])
    assert crossing(y, x, -4.0) == pytest.approx(15.0)  # between steps 1 and 2, halfway
    assert crossing(y, x, -2.0) == pytest.approx(10.0)  # reached exactly at step 1
    assert crossing(y, x, -7.0) == pytest.approx(30 + 10 * 4 / 6)  # first reached between steps 3 and 4
    assert crossing(y, x, -10.0) is None and crossing(y, x, 0.0) == 0.0
    goals = Goals.parse(BEAM, [("minimize", "at(main.pressure, tip_rotation, -10)")])
    with pytest.raises(NoValue, match=r"never reaches -10 \(it comes within 1\)") as short:
        goals.evaluate(record(tip_rotation=x, **{"main.pressure": y}))
    assert short.value.shortfall == pytest.approx(1.0)  # the closest approach, -9


def test_goals_read_summary_values_history_columns_and_functions():
    goals = Goals.parse(
        BEAM,
        [("minimize", "at(main.pressure, tip_rotation, -4) + 2 * abs(final(tip_dy))"), ("maximize", "max_stretch")],
        ["max(max_stretch) <= 1.5", "chambers.main.area_ratio >= 2"],
    )
    run = record(
        {"max_stretch": 1.7, "chambers": {"main": {"area_ratio": 2.5}}},
        tip_rotation=[0, -2, -6],
        tip_dy=[0, -0.1, -0.25],
        max_stretch=[1, 1.2, 1.6],
        **{"main.pressure": [0, 10, 20]},
    )
    objectives, violations = goals.evaluate(run)
    assert objectives == pytest.approx([15 + 0.5, 1.7])  # the summary's max_stretch, not the history's last
    assert violations == pytest.approx([0.1, -0.5])
    with pytest.raises(NoValue, match="never reaches -9"):
        Goals.parse(BEAM, [("minimize", "at(main.pressure, tip_rotation, -9)")]).evaluate(run)


def test_rms_measures_the_distance_from_a_target_value_or_trajectory():
    run = record(tip_dy=[0.0, -0.1, -0.3])
    assert Goals.parse(BEAM, [("minimize", "rms(tip_dy, -0.2)")]).evaluate(run)[0] == pytest.approx([0.1])
    trajectory = Goals.parse(BEAM, [("minimize", "rms(tip_dy, [-0.1, -0.2])")])
    assert trajectory.evaluate(run)[0] == pytest.approx([np.sqrt(0.01 / 2)])  # only the second step is off, by 0.1
    with pytest.raises(NoValue, match="the trajectory has 2 values, the run 3 steps after rest"):
        trajectory.evaluate(record(tip_dy=[0.0, -0.1, -0.2, -0.3]))


def bowl(task):
    """An analytic stand-in of a simulation: f = ((cy - 0.05) / 0.1)^2 + ((E - 12000) / 4000)^2 as the final
    tip_rotation, and 'max_stretch' = 1 + cy (a constraint on it bounds cy)."""
    cy, e = task.values[CY], task.values["material.E"]
    f = ((cy - 0.05) / 0.1) ** 2 + ((e - 12000.0) / 4000.0) ** 2
    run = {"summary": {"max_stretch": 1.0 + cy}, "history": {"tip_rotation": [0.0, f], "tip_dy": [0.0, cy - e / 1e5]}}
    return {"values": dict(task.values), "record": run, "files": {}, "error": None, "seconds": 0.0}


BOWL = {CY: (-0.15, 0.15), "material.E": (5000.0, 20000.0)}


@pytest.mark.parametrize("sampler, trials, within", [("tpe", 60, 0.05), ("cmaes", 60, 0.02)])
def test_an_analytic_bowl_is_minimised_near_its_known_bottom(tmp_path, sampler, trials, within):
    report = tp.optimize(
        BEAM, BOWL, minimize="tip_rotation", trials=trials, sampler=sampler, out=tmp_path, evaluate=bowl
    )
    assert len(report.rows) == trials and all(r["feasible"] for r in report.rows)
    assert report.best["objective_0"] < within**2
    assert abs(report.best[CY] - 0.05) < within * 0.1 * 1.5 and abs(report.best["material.E"] - 12000) < within * 6000
    assert report.best["objective_0"] == min(r["objective_0"] for r in report.rows)


def test_a_constraint_moves_the_optimum_to_its_boundary(tmp_path):
    """max_stretch = 1 + cy <= 1.0 allows cy <= 0 only: the constrained bottom is cy = 0, E = 12000 (f = 0.25)."""
    report = tp.optimize(
        BEAM, BOWL, minimize="tip_rotation", constraints=["max_stretch<=1.0"], trials=60, out=tmp_path, evaluate=bowl
    )
    assert report.best[CY] <= 0.0 and 0.25 <= report.best["objective_0"] < 0.35
    assert any(not r["feasible"] for r in report.rows)  # it tried the other side and counted those out
    assert all(r["feasible"] == (r["violation_0"] <= 0) for r in report.rows)


def test_a_local_refinement_reaches_the_constrained_bottom_exactly(tmp_path):
    """The constrained bowl (its bottom cy = 0, E = 12000, f = 0.25, on the constraint's boundary): 15 TPE designs
    then 15 of COBYQA land on it to 1e-5, where TPE alone with all 30 stays over 1 % off (the first test's 0.05)."""
    common = dict(minimize="tip_rotation", constraints=["max_stretch<=1.0"], trials=30, evaluate=bowl)
    refined = tp.optimize(BEAM, BOWL, refine=15, out=tmp_path / "refined", **common)
    alone = tp.optimize(BEAM, BOWL, out=tmp_path / "alone", **common)
    assert refined.best["objective_0"] == pytest.approx(0.25, abs=1e-5)
    assert -1e-5 < refined.best[CY] <= 0 and refined.best["material.E"] == pytest.approx(12000, abs=0.1)
    assert alone.best["objective_0"] > 0.25 * 1.01  # (what the refinement adds)
    assert len(refined.rows) == 30 and refined.rows[:15] == alone.rows[:15]  # the same TPE designs before it


class ThreeAtOnce(InProcess):
    """This process, asking the sampler for 3 designs a batch (as a pool of 3 workers would)."""

    def capacity(self) -> int:
        return 3


def test_the_sampler_s_batches_stop_where_the_refinement_begins(tmp_path):
    """10 trials, the last 5 refining, in batches of 3: the sampler runs exactly 5 designs (3 + 2), COBYQA the
    other 5 (the bowl is not converged in 5), each refinement design marked so in the study."""
    import optuna

    tp.optimize(
        BEAM, BOWL, minimize="tip_rotation", trials=10, refine=5, out=tmp_path, evaluate=bowl, executor=ThreeAtOnce()
    )
    trials = optuna.load_study(study_name="optimize", storage=f"sqlite:///{tmp_path / 'optimize.db'}").get_trials()
    assert [bool(t.user_attrs.get("refine")) for t in trials] == [False] * 5 + [True] * 5


def test_a_study_continued_to_more_trials_refines_afresh_from_its_best_design(tmp_path):
    """10 trials (the last 4 refining), then the same study to 16: 2 more of TPE, then a new refinement of 4 from
    the best of the 12 designs before it (the first refinement's included)."""
    import optuna

    common = dict(minimize="tip_rotation", refine=4, out=tmp_path, evaluate=bowl)
    tp.optimize(BEAM, BOWL, trials=10, **common)
    report = tp.optimize(BEAM, BOWL, trials=16, **common)
    study = optuna.load_study(study_name="optimize", storage=f"sqlite:///{tmp_path / 'optimize.db'}")
    refining = [bool(t.user_attrs.get("refine")) for t in study.get_trials()]
    assert refining == [False] * 6 + [True] * 4 + [False] * 2 + [True] * 4
    best_of_12 = min(report.rows[:12], key=lambda r: r["objective_0"])
    assert study.user_attrs["refine_16"]["start"] == {CY: best_of_12[CY], "material.E": best_of_12["material.E"]}
    assert report.best["objective_0"] <= best_of_12["objective_0"]


def test_two_objectives_give_a_pareto_front_of_designs_none_dominates(tmp_path):
    """f1 = the bowl, f2 = tip_dy = cy - E / 1e5 (maximised): the front trades the two; none of its designs is
    dominated by any evaluated design."""
    report = tp.optimize(
        BEAM, BOWL, minimize="tip_rotation", maximize="tip_dy", trials=40, sampler="nsga2", out=tmp_path, evaluate=bowl
    )
    front = report.pareto
    assert report.best is None and len(front) >= 3
    for design in front:
        assert not any(
            r["objective_0"] <= design["objective_0"]
            and r["objective_1"] >= design["objective_1"]
            and (r["objective_0"], r["objective_1"]) != (design["objective_0"], design["objective_1"])
            for r in report.rows
        )
    assert (tmp_path / "optimize_pareto.png").stat().st_size > 0 and (tmp_path / "optimize_trace.png").exists()


def ramp(task):
    """An analytic ramp: the tip turns to 100 cy degrees as the pressure goes to E / 10."""
    cy, e = task.values[CY], task.values["material.E"]
    run = {"summary": {}, "history": {"tip_rotation": [0.0, 100 * cy], "main.pressure": [0.0, e / 10]}}
    return {"values": dict(task.values), "record": run, "files": {}, "error": None, "seconds": 0.0}


def test_a_design_short_of_the_level_at_asks_for_is_infeasible_by_how_far(tmp_path):
    """at(main.pressure, tip_rotation, 5) = (E / 10) 5 / (100 cy) where 100 cy >= 5, else short by min(5, 5-100 cy)."""
    report = tp.optimize(
        BEAM, BOWL, minimize="at(main.pressure, tip_rotation, 5)", trials=30, out=tmp_path, evaluate=ramp
    )
    short = [r for r in report.rows if 100 * r[CY] < 5]
    assert short and len(short) < len(report.rows)
    for row in short:
        assert not row["feasible"] and row["objective_0"] is None
        assert f"it comes within {min(5, abs(5 - 100 * row[CY])):.4g}" in row["error"]  # (rest: 0 degrees)
    for row in report.rows:
        if row not in short:
            assert row["feasible"] and row["objective_0"] == pytest.approx(row["material.E"] / 2 / (100 * row[CY]))
    assert report.best["objective_0"] == min(r["objective_0"] for r in report.rows if r["feasible"])


def crash_above(task):
    """The bowl, but a worker process that is given cy > 0 dies."""
    if task.values[CY] > 0:
        os._exit(1)
    return bowl(task)


def test_designs_lost_with_a_crashed_worker_are_asked_again_by_the_next_run(tmp_path):
    report = tp.optimize(
        BEAM, BOWL, minimize="tip_rotation", trials=8, out=tmp_path, executor=LocalPool(2), evaluate=crash_above
    )
    assert report.lost >= 1 and len(report.rows) < 8 and all(r[CY] <= 0 for r in report.rows)
    again = tp.optimize(BEAM, BOWL, minimize="tip_rotation", trials=8, out=tmp_path, evaluate=bowl)
    assert again.lost == 0 and len(again.rows) == 8
    assert all(row in again.rows for row in report.rows)  # kept as they were
    import optuna

    lost = [
        t
        for t in optuna.load_study(study_name="optimize", storage=f"sqlite:///{tmp_path / 'optimize.db'}").trials
        if t.user_attrs.get("interrupted")
    ]
    assert len(lost) == report.lost
    for trial in lost:  # each lost design run now, once
        assert sum(r[CY] == trial.params[CY] and r["material.E"] == trial.params["material.E"] for r in again.rows) == 1


# --- FEM designs ---------------------------------------------------------------------------------


def test_a_2d_scene_records_each_design_as_the_same_design_run_alone(tmp_path):
    report = tp.optimize(
        BEAM, {CY: (-0.15, 0.15)}, maximize="tip_rotation_deg", constraints=["max_stretch<=3"], trials=4, out=tmp_path
    )
    assert len(report.rows) == 4 and all(r["error"] is None for r in report.rows)
    for row in report.rows:
        folder = tmp_path / row["folder"]
        assert sorted(p.name for p in folder.iterdir()) == ["history.csv", "plot.png", "scene.toml", "summary.json"]
        alone = tp.simulate(tp.load_scene(folder / "scene.toml"))
        assert row["objective_0"] == pytest.approx(alone.summary()["tip_rotation_deg"], rel=1e-6, abs=1e-6)
        assert alone.scene.to_toml() == BEAM.with_value(CY, row[CY]).to_toml()
    assert report.best["objective_0"] == max(r["objective_0"] for r in report.rows)


@pytest.mark.slow  # two studies, each spawning two workers: ~15 to 35 s
def test_the_app_on_the_pool_continues_a_study_to_more_trials(tmp_path, capsys):
    out = tmp_path / "out"
    flags = ["--vary", "cy=-0.15:0.15", "--minimize", "tip_dy", *COARSE, "--workers", "2", "--out", str(out)]
    assert main([*flags, "--trials", "3"]) == 0
    first = read_rows(out / "optimize.csv")
    assert main([*flags, "--trials", "5", "--quiet"]) == 0
    rows = read_rows(out / "optimize.csv")
    assert len(first) == 3 and len(rows) == 5 and rows[:3] == first
    assert len({r[CY] for r in rows}) == 5  # five designs, none asked twice
    record = json.loads((out / "optimize.json").read_text())
    assert record["executor"] == {"executor": "process pool", "workers": 2} and record["ran"] == 2
    assert record["best"]["objective_0"] == min(float(r["objective_0"]) for r in rows)
    assert "best: #" in capsys.readouterr().out


@pytest.mark.slow  # a local Ray started and stopped: ~25 to 40 s
def test_the_app_on_a_local_ray_records_the_designs_run_alone(tmp_path):
    pytest.importorskip("ray")
    out = tmp_path / "ray"
    proc = subprocess.run(
        [sys.executable, "-m", "taichi_pneuma.apps.optimize", "--vary", "cy=-0.15:0.15", "--maximize", "tip_dy"]
        + [*COARSE, "--trials", "2", "--ray", "--workers", "2", "--out", str(out), "--quiet"],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert proc.returncode == 0, proc.stderr
    record = json.loads((out / "optimize.json").read_text())
    assert record["executor"]["executor"] == "ray" and record["executor"]["ray_cpus"] == 2 and record["ran"] == 2
    for row in record["rows"]:
        alone = tp.simulate(tp.load_scene(out / row["folder"] / "scene.toml"))
        assert row["objective_0"] == pytest.approx(alone.summary()["tip_deflection"], rel=1e-6, abs=1e-9)


# --- resuming after a kill -----------------------------------------------------------------------

SCRIPT = """
import sys, time
import taichi_pneuma as tp
from taichi_pneuma.study.optimize import InProcess

def slow_bowl(task):
    time.sleep(0.4)
    x = task.values["chambers[0].center[1]"]
    run = {{"summary": {{}}, "history": {{"tip_rotation": [0.0, (x - 0.05) ** 2]}}}}
    return {{"values": dict(task.values), "record": run, "files": {{}}, "error": None, "seconds": 0.4}}

tp.optimize(tp.reference_scene(), {{"cy": (-0.15, 0.15)}}, minimize="tip_rotation", trials=10, out={out!r},
            evaluate=slow_bowl, refine={refine})
"""


def evaluated(db) -> list[tuple]:
    """The study's trials (number, state); none while Optuna has not yet made its tables."""
    with sqlite3.connect(db) as c:
        try:
            return c.execute("SELECT number, state FROM trials ORDER BY number").fetchall()
        except sqlite3.OperationalError:
            return []


def kill_midway(tmp_path, refine: int, complete: int):
    """SCRIPT's study (10 trials, the last `refine` of them refining) killed by SIGKILL into the next design's
    evaluation after `complete` designs; its out folder and script."""
    out = tmp_path / "out"
    script = tmp_path / "run.py"
    script.write_text(textwrap.dedent(SCRIPT.format(out=str(out), refine=refine)))
    proc = subprocess.Popen([sys.executable, str(script)], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline:
        time.sleep(0.1)
        if (out / "optimize.db").exists() and sum(
            s == "COMPLETE" for _, s in evaluated(out / "optimize.db")
        ) >= complete:
            break
    time.sleep(0.2)  # into the next design's evaluation
    proc.send_signal(signal.SIGKILL)
    proc.wait(timeout=30)
    return out, script


def test_a_killed_optimisation_resumes_with_no_design_lost_or_run_twice(tmp_path):
    out, script = kill_midway(tmp_path, 0, 4)
    before = {n: s for n, s in evaluated(out / "optimize.db")}
    done_before = [n for n, s in before.items() if s == "COMPLETE"]
    assert 4 <= len(done_before) < 10 and "RUNNING" in before.values()
    rows_before = {int(r["trial"]): r for r in read_rows(out / "optimize.csv")}
    again = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, timeout=120)
    assert again.returncode == 0, again.stderr
    rows = read_rows(out / "optimize.csv")
    assert len(rows) == 10 and len({r["trial"] for r in rows}) == 10
    assert all(rows_before[n] == r for r in rows if (n := int(r["trial"])) in rows_before)  # kept as they were
    import optuna

    trials = optuna.load_study(study_name="optimize", storage=f"sqlite:///{out / 'optimize.db'}").get_trials()
    killed = [t for t in trials if t.user_attrs.get("interrupted")]
    assert (
        len(killed) == 1 and killed[0].state.name == "FAIL" and str(killed[0].number) not in {r["trial"] for r in rows}
    )
    values = [float(r[CY]) for r in rows]
    assert values.count(killed[0].params[CY]) == 1  # the design it was running: asked again, evaluated once
    assert len(set(values)) == 10


def line_bowl(task):
    """SCRIPT's slow_bowl without its sleep."""
    run = {"summary": {}, "history": {"tip_rotation": [0.0, (task.values[CY] - 0.05) ** 2]}}
    return {"values": dict(task.values), "record": run, "files": {}, "error": None, "seconds": 0.0}


def test_a_refinement_killed_midway_replays_its_path_and_goes_on(tmp_path):
    """10 trials, the last 6 COBYQA's, killed after 6 designs (4 of TPE, 2 of the refinement) and run again: the
    study holds the very designs, in order, of the same study run whole (COBYQA replayed from the start stored in
    the study, the designs it had run looked up, the one in flight asked again), each evaluated once."""
    out, script = kill_midway(tmp_path, 6, 6)
    again = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, timeout=120)
    assert again.returncode == 0, again.stderr
    resumed = [float(r[CY]) for r in read_rows(out / "optimize.csv")]
    whole = tp.optimize(
        tp.reference_scene(),
        {"cy": (-0.15, 0.15)},
        minimize="tip_rotation",
        trials=10,
        refine=6,
        out=tmp_path / "whole",
        evaluate=line_bowl,
    )
    assert resumed == [r[CY] for r in whole.rows]
    explored = min(abs(r[CY] - 0.05) for r in whole.rows[:4])
    assert abs(whole.best[CY] - 0.05) < explored / 10  # the refinement went 10 times closer to the bottom


# --- refusals ------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "flags, words",
    [
        (["--vary", "material.foo=1:2", "--minimize", "tip_dy"], "unknown key 'material.foo'"),
        (["--vary", "cy=0.2:0.1", "--minimize", "tip_dy"], "must be below the high end"),
        (["--vary", "cy=0:0.2:5", "--minimize", "tip_dy"], "a range LO:HI (no count)"),
        (["--vary", "cy=0:x", "--minimize", "tip_dy"], "'x' is not a number"),
        (["--vary", "cy=0:0.2", "--minimize", "at(nosuch, tip_rotation, 6)"], "'nosuch' is not a history column"),
        (["--vary", "cy=0:0.2", "--minimize", "tip_speed"], "'tip_speed' is not a summary value or a history column"),
        (["--vary", "cy=0:0.2", "--minimize", "tip_dy +"], "does not parse as an expression"),
        (["--vary", "cy=0:0.2", "--minimize", "__import__('os')"], "the functions are abs, sqrt"),
        (["--vary", "cy=0:0.2", "--minimize", "at(main.pressure, tip_rotation)"], "at() takes 3 arguments"),
        (["--vary", "cy=0:0.2", "--minimize", "'x'"], "'x' is not a number"),
        (["--vary", "cy=0:0.2", "--minimize", "rms(tip_dy, [])"], "a list of one number or more"),
        (["--vary", "cy=0:0.2", "--minimize", "rms(tip_dy, [1, 'a'])"], "'a' is not a number"),
        (["--vary", "cy=0:0.2"], "one or two objectives"),
        (["--vary", "cy=0:0.2"] + ["--minimize", "tip_dy"] * 3, "one or two objectives"),
        (["--vary", "cy=0:0.2", "--minimize", "tip_dy", "--constraint", "max_stretch<="], "does not parse"),
        (["--vary", "cy=0:0.2", "--minimize", "tip_dy", "--constraint", "max_stretch"], "a constraint is EXPR<=VALUE"),
        (["--vary", "cy=0:0.2", "--minimize", "tip_dy", "--constraint", "1<x<2"], "a constraint is EXPR<=VALUE"),
        (["--vary", "cy=0:0.2", "--minimize", "tip_dy", "--constraint", "stretch<=2"], "'stretch' is not a summary"),
        (["--vary", "cy=0:0.2", "--minimize", "tip_dy", "--trials", "0"], "--trials 0"),
        (["--vary", "cy=0:0.2", "--minimize", "tip_dy", "--sampler", "grid"], "--sampler 'grid': one of tpe"),
        (["--vary", "cy=0:0.2", "--minimize", "tip_dy", "--maximize", "tip_dx", "--sampler", "cmaes"], "one objective"),
        (
            ["--vary", "cy=0:0.2", "--minimize", "tip_dy", "--constraint", "max_stretch<=2", "--sampler", "cmaes"],
            "takes no --constraint",
        ),
        (["--vary", "cy=0:0.2", "--minimize", "tip_dy", "--workers", "0"], "--workers 0"),
        (["--vary", "cy=0:0.2", "--minimize", "tip_dy", "--trials", "9", "--refine", "9"], "--refine 9: 0 to 8"),
        (["--vary", "cy=0:0.2", "--minimize", "tip_dy", "--refine", "-1"], "--refine -1: 0 to 29"),
        (
            ["--vary", "cy=0:0.2", "--minimize", "tip_dy", "--maximize", "tip_dx", "--refine", "5"],
            "--refine 5: a local refinement takes one objective",
        ),
        (["--vary", "cy=0,0.1", "--minimize", "tip_dy", "--refine", "5"], "a range of real numbers"),
        (["--vary", "cy=0:0.2", "--minimize", "tip_dy", "--name", "../x"], "cannot name the result files"),
    ],
)
def test_bad_input_is_one_error_line_and_exit_2_with_nothing_written(tmp_path, capsys, flags, words):
    out = tmp_path / "out"
    assert main([*flags, "--out", str(out)]) == 2
    err = capsys.readouterr().err
    lines = [line for line in err.splitlines() if line.strip()]
    assert len(lines) == 1 and lines[0].startswith("error:") and words in lines[0], err
    assert not out.exists() or not any(out.iterdir())
    assert [p.name for p in tmp_path.iterdir()] in ([], ["out"])


def test_another_study_under_the_same_name_is_refused(tmp_path, capsys):
    flags = ["--vary", "cy=-0.1:0.1", *COARSE, "--trials", "1", "--workers", "1", "--out", str(tmp_path)]
    assert main([*flags, "--minimize", "tip_dy"]) == 0
    assert main([*flags, "--maximize", "tip_dy"]) == 2
    assert "holds another study" in capsys.readouterr().err
