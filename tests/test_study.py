"""Design studies (study.py, apps/sweep.py): the planned runs, the acceptance sweep over the chamber
height through the process pool and through a local Ray, failing runs recorded, resumed studies."""

import csv
import json
import subprocess
import sys
import tomllib

import numpy as np
import pytest

import taichi_pneuma as tp
from taichi_pneuma import backend
from taichi_pneuma.apps.sweep import main
from taichi_pneuma.scene.scenefile import read_scene
from taichi_pneuma.study import RunOptions, Task, check_axes, parse_vary, plan, run_task, study_figure

CY = "chambers[0].center[1]"
COARSE = ["--steps", "11", "--max-area", "0.01"]  # 380 vertices, 10 increments: ~0.1 s a ramp
# a worker's run and the same run here agree to round-off (parallel sums in a thread-dependent order), and at worst
# to the Newton tolerance (1e-6) should they stop after different iteration counts
SAME = 1e-6


def read_rows(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def by_height(rows):
    return {float(r[CY]): r for r in rows}


def errors_only(capsys):
    err = capsys.readouterr().err
    return [line for line in err.splitlines() if line.strip()], err


# --- planning ------------------------------------------------------------------------------------


def test_ranges_and_lists_give_the_grid_of_every_combination():
    base = tp.reference_scene()
    axes = check_axes(
        base,
        [parse_vary("cy=-0.15:0.15:3"), parse_vary("material.E=1e4,2e4"), parse_vary("schedule.increments=10:40:4")],
    )
    assert axes[0].grid() == [-0.15, 0.0, 0.15]
    assert axes[2].grid() == [10, 20, 30, 40] and all(type(v) is int for v in axes[2].grid())
    runs = plan(axes)
    assert len(runs) == 3 * 2 * 4
    assert len({tuple(r.values()) for r in runs}) == 24
    assert {r[CY] for r in runs} == {-0.15, 0.0, 0.15} and {r["material.E"] for r in runs} == {1e4, 2e4}
    # integer ends of a float key still give floats (0.5 is not rounded away)
    assert check_axes(base, [parse_vary("cy=0:1:3")])[0].grid() == [0.0, 0.5, 1.0]


def test_latin_hypercube_puts_one_sample_in_every_stratum_of_every_range():
    base = tp.reference_scene()
    axes = check_axes(
        base, [parse_vary("cy=-0.2:0.2"), parse_vary("material.E=5e3:2e4:7"), parse_vary("schedule.increments=5:14")]
    )
    runs = plan(axes, samples=10, seed=3)
    assert len(runs) == 10
    cy = np.array([r[CY] for r in runs])
    e = np.array([r["material.E"] for r in runs])
    assert np.all((-0.2 <= cy) & (cy < 0.2)) and np.all((5e3 <= e) & (e < 2e4))
    for values, low, high in ((cy, -0.2, 0.2), (e, 5e3, 2e4)):  # Latin: each tenth of the range once
        assert sorted(np.floor((values - low) / (high - low) * 10).astype(int)) == list(range(10))
    increments = [r["schedule.increments"] for r in runs]  # 10 integers 5..14, each stratum one integer
    assert sorted(increments) == list(range(5, 15)) and all(type(v) is int for v in increments)
    assert plan(axes, samples=10, seed=3) == runs and plan(axes, samples=10, seed=4) != runs


def test_a_task_never_raises_and_names_what_went_wrong():
    base = (
        tp.reference_scene()
        .with_values({"mesh.max_area": 0.05, "schedule.increments": 2, "chambers[0].keyframes": [[2, 1.5]]})
        .to_toml()
    )
    ok = run_task(Task(base, {"material.E": 2e4}))
    assert ok["error"] is None and ok["converged"] and ok["increments"] == 2
    assert ok["main.area_ratio"] == pytest.approx(1.5, rel=0.02) and ok["main.peak_pressure"] > 0
    outside = run_task(Task(base, {CY: 0.3}))
    assert "not inside the body" in outside["error"] and "tip_dy" not in outside
    broken = run_task(Task("name = ", {CY: 0.1}))
    assert broken["error"].startswith("TOMLDecodeError:") and "\n" not in broken["error"]
    too_big = run_task(Task(base, {"mesh.max_area": 1e-6}, RunOptions(max_triangles=1000)))
    assert "the limit is 1000 triangles" in too_big["error"]


def test_the_plot_shows_the_rows_tip_deflections():
    rows = [{CY: cy, "E": e, "tip_dy": cy * e, "tip_dx": 0.1, "error": None} for cy in (-0.1, 0.1, 0.2) for e in (1, 2)]
    rows[-1] = {CY: 0.2, "E": 2, "error": "no equilibrium"}
    one = study_figure([r for r in rows if r["E"] == 1], [CY]).axes[0]
    x, y = one.lines[0].get_data()
    assert list(x) == [-0.1, 0.1, 0.2] and list(y) == [-0.1, 0.1, 0.2]
    heat = study_figure(rows, [CY, "E"])
    mesh = heat.axes[0].collections[0].get_array()
    assert mesh.shape == (2, 3)  # rows E = 1, 2; columns cy
    assert np.allclose(mesh[0], [-0.1, 0.1, 0.2]) and np.allclose(mesh[1, :2], [-0.2, 0.2])
    assert mesh.mask[1, 2]  # the failed run has no colour, and is marked
    assert list(zip(*heat.axes[0].lines[-1].get_data())) == [(0.2, 2)]
    assert list(heat.axes[0].get_xticks()) == [-0.1, 0.1, 0.2] and list(heat.axes[0].get_yticks()) == [1, 2]
    assert [t.get_text() for t in heat.axes[0].get_xticklabels()] == ["-0.1", "0.1", "0.2"]  # on the grid's values


# --- bad input -----------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "flags, words",
    [
        (["--vary", "material.foo=1,2"], "unknown key 'material.foo'"),
        (["--vary", "cy=0.1:0.2:0"], "count '0' must be an integer"),
        (["--vary", "cy=0.1:0.2:x"], "count 'x'"),
        (["--vary", "cy=0.1:0.2"], "needs a count"),
        (["--vary", "cy=0:nan:3"], "must be a finite number"),
        (["--vary", "material.E=soft,hard"], "'soft' is not a number"),
        (["--vary", "cy=0.1,0.1"], "listed twice"),
        (["--vary", "cy"], "must look like KEY="),
        (["--vary", "cy=0.1", "--vary", "chambers[0].center[1]=0.2"], "varied twice"),
        (["--vary", "cy=0.1", "--workers", "0"], "--workers 0"),
        (["--vary", "cy=0:0.1:400", "--vary", "E=1:2:400"], "160000 runs; the limit is 100000"),
        (["--vary", "cy=0:0.1", "--samples", "0"], "--samples 0"),
        (["--vary", "cy=0.1", "--name", "../x"], "cannot name the result files"),
        (["--vary", "cy=0.1", "--nu", "0.5"], "nu = 0.5"),
    ],
)
def test_bad_input_is_one_error_line_and_exit_2_with_nothing_written(tmp_path, capsys, flags, words):
    out = tmp_path / "out"
    assert main([*flags, "--out", str(out)]) == 2
    lines, err = errors_only(capsys)
    assert len(lines) == 1 and lines[0].startswith("error:") and words in lines[0], err
    assert not out.exists() or not any(out.iterdir())
    assert [p.name for p in tmp_path.iterdir()] in ([], ["out"])


# --- running studies -----------------------------------------------------------------------------


def coarse_rows(heights) -> dict:
    """The rows of COARSE reference ramps at these chamber heights, each run here in this process (run_task)."""
    base = tp.reference_scene(steps=11, max_area=0.01).to_toml()
    return {cy: run_task(Task(base, {CY: cy})) for cy in heights}


def test_cy_sweep_on_the_process_pool_gives_the_rows_of_single_runs_records_a_failure_and_resumes(tmp_path, capsys):
    """The pool's rows are those of the same runs made one by one in this process (the reference figures
    themselves: test_reference.py)."""
    out = tmp_path / "study"
    argv = ["--vary", "cy=-0.15,0,0.15,0.35", *COARSE, "--workers", "2", "--out", str(out), "--quiet"]
    assert main(argv) == 0
    rows = by_height(read_rows(out / "sweep.csv"))
    single = coarse_rows((-0.15, 0.0, 0.15))
    for cy, alone in single.items():
        assert alone["error"] is None and alone["increments"] == 10
        assert rows[cy]["converged"] == "true" and rows[cy]["error"] == "" and rows[cy]["increments"] == "10"
        for column in ("tip_dy", "tip_dx", "main.area_ratio", "main.peak_pressure"):
            assert float(rows[cy][column]) == pytest.approx(alone[column], rel=SAME, abs=SAME), (cy, column)
    assert float(rows[0.15]["tip_dy"]) < -0.1 < 0.1 < float(rows[-0.15]["tip_dy"])  # curls away from the chamber
    assert float(rows[0.15]["main.area_ratio"]) == pytest.approx(3.5, abs=0.02)
    assert "not inside the body" in rows[0.35]["error"] and rows[0.35]["tip_dy"] == ""  # recorded, not fatal
    record = json.loads((out / "sweep.json").read_text())
    assert record["status"] == "done" and record["result"]["ran"] == 4 and record["result"]["failed"] == 1
    assert record["executor"] == {"executor": "process pool", "workers": 2}
    assert {backend.NAME, "numpy", "scipy", "taichi-pneuma"} <= set(record["versions"])
    assert record["grid"]["axes"][0]["values"] == [-0.15, 0.0, 0.15, 0.35]
    assert read_scene(tomllib.loads(record["base_scene"]), "x") == tp.reference_scene(0.15, steps=11, max_area=0.01)
    assert (out / "sweep.png").stat().st_size > 10_000
    assert sorted(p.name for p in out.iterdir()) == ["sweep.csv", "sweep.json", "sweep.png"]

    # the same command again: nothing runs, nothing changes
    text = (out / "sweep.csv").read_text()
    capsys.readouterr()
    assert main(argv) == 0
    assert "4 done before, 0 to run" in capsys.readouterr().out
    assert (out / "sweep.csv").read_text() == text
    assert json.loads((out / "sweep.json").read_text())["result"]["ran"] == 0

    # a study cut short (the cy = 0.15 row missing, a half-written last line): only that run is run again
    lines = text.splitlines(keepends=True)
    kept = [line for line in lines if not line.startswith("0.15,")]
    (out / "sweep.csv").write_text("".join(kept) + "0.15,0.05,-0.2")
    assert main(argv) == 0
    assert json.loads((out / "sweep.json").read_text())["result"]["ran"] == 1
    again = read_rows(out / "sweep.csv")
    assert [r[CY] for r in again] == ["-0.15", "0.0", "0.15", "0.35"]
    assert float(by_height(again)[0.15]["tip_dy"]) == pytest.approx(single[0.15]["tip_dy"], rel=SAME)
    assert [r["seconds"] for r in again if r[CY] != "0.15"] == [r["seconds"] for r in read_rows_text(kept)]

    # another base scene under the same name is refused, the rows kept
    assert main([*argv, "--E", "2e4"]) == 2
    assert "holds another study" in capsys.readouterr().err
    assert len(read_rows(out / "sweep.csv")) == 4


def read_rows_text(lines):
    return list(csv.DictReader(lines))


def test_a_ramp_with_no_equilibrium_is_a_row_and_the_study_goes_on(tmp_path):
    """All the way to 3.5x in one increment needs ~20 Newton iterations, over ten increments ~9 each:
    with at most 12 and no cut-back, the first has no equilibrium and the second converges. One worker runs all
    four: it goes on after a failed run."""
    out = tmp_path / "study"
    assert (
        main(
            [
                *COARSE,
                "--max-iterations",
                "12",
                "--max-cuts",
                "0",
                "--vary",
                "chambers[0].keyframes[1][0]=1,10",
                "--vary",
                "cy=-0.1,0.1",
                "--workers",
                "1",
                "--out",
                str(out),
                "--quiet",
            ]
        )
        == 0
    )
    rows = {(int(r["chambers[0].keyframes[1][0]"]), float(r[CY])): r for r in read_rows(out / "sweep.csv")}
    assert len(rows) == 4
    for cy in (-0.1, 0.1):
        failed, done = rows[1, cy], rows[10, cy]
        assert failed["error"].startswith("step 1: no equilibrium") and failed["converged"] == "false"
        assert failed["increments"] == "0"
        assert done["error"] == "" and done["converged"] == "true" and done["increments"] == "10"
        assert np.sign(float(done["tip_dy"])) == -np.sign(cy)  # above the axis curls down


# --- Ray ------------------------------------------------------------------------------------------


def test_cy_sweep_on_a_local_ray_gives_the_rows_of_single_runs(tmp_path):
    """The command a user runs: the app starts a local Ray (2 CPUs) for the study and stops it."""
    pytest.importorskip("ray")
    out = tmp_path / "ray"
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "taichi_pneuma.apps.sweep",
            "--vary",
            "cy=-0.15,0,0.15",
            *COARSE,
            "--ray",
            "--workers",
            "2",
            "--out",
            str(out),
            "--quiet",
        ],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert proc.returncode == 0, proc.stderr
    rows = by_height(read_rows(out / "sweep.csv"))
    single = coarse_rows((-0.15, 0.0, 0.15))
    assert sorted(rows) == sorted(single)
    for cy, alone in single.items():
        assert (
            float(rows[cy]["tip_dy"]) == pytest.approx(alone["tip_dy"], rel=SAME, abs=SAME) and rows[cy]["error"] == ""
        )
    record = json.loads((out / "sweep.json").read_text())
    assert record["executor"]["executor"] == "ray" and record["executor"]["ray_cpus"] == 2
    assert record["versions"]["ray"] and record["result"]["ran"] == 3


@pytest.mark.parametrize(
    "address, words", [("127.0.0.1:1", "no Ray cluster answers there"), ("localhost", "an address is HOST:PORT")]
)
def test_a_ray_address_nothing_answers_is_refused_at_once(tmp_path, capsys, address, words):
    pytest.importorskip("ray")
    assert main(["--vary", "cy=0.1", "--ray", address, "--out", str(tmp_path / "out")]) == 2
    lines, err = errors_only(capsys)
    assert len(lines) == 1 and words in lines[0], err
    assert not (tmp_path / "out").exists()
