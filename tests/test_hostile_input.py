"""Untrusted input, round two (issue 21): size guards that thin geometry and self-contact cannot fool,
parsers with depth and length limits, result files that follow no link and no other run, failures and
signals that end in one line and lose no finished work, bounded counts and files, safe CSV columns.
One section per kind; docs/untrusted_input.md lists every example with its outcome."""

import csv
import dataclasses
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

import taichi_pneuma as tp
from taichi_pneuma.apps import inflate, sweep
from taichi_pneuma.errors import PneumaInputError
from taichi_pneuma.fem.planar import Geometry
from taichi_pneuma.fem.shapes import Ellipse, Polygon
from taichi_pneuma.limits import Budget
from taichi_pneuma.scene.dotted_edits import parse_assignment, parse_key
from taichi_pneuma.scene.scenefile import load_scene
from taichi_pneuma.scene.targets import read_targets_csv
from taichi_pneuma.study import Sweep, parse_vary, plan, run_task, study_figure

SCENES = Path(__file__).resolve().parent.parent / "taichi_pneuma" / "scenes"
CHEAP = (
    (SCENES / "reference_beam.toml")
    .read_text()
    .replace("max_area = 0.0012", "max_area = 0.02")
    .replace("[35, 3.5]", "[2, 1.3]")
    .replace("increments = 35", "increments = 2")
)
QUICK = ["--no-video", "--quiet"]
RESULTS = {
    "reference_beam.pvd",
    "reference_beam_history.csv",
    "reference_beam_states.npz",
    "reference_beam_summary.json",
    "reference_beam_scene.toml",
}
STRIP = [[-1, -0.5], [1, -0.5], [1, -5e-5], [100, -5e-5], [100, 5e-5], [1, 5e-5], [1, 0.5], [-1, 0.5]]
ENV = {**os.environ, "PYTHONUNBUFFERED": "1"}
SIGNAL_NAMES = {signal.SIGINT: "Ctrl-C", signal.SIGTERM: "SIGTERM", signal.SIGHUP: "SIGHUP"}


def scene_file(tmp_path, text=CHEAP, *replacements, name="scene.toml") -> Path:
    for old, new in replacements:
        assert old in text
        text = text.replace(old, new)
    path = tmp_path / name
    path.write_text(text)
    return path


def error_line(capsys) -> str:
    lines = [line for line in capsys.readouterr().err.splitlines() if line.strip()]
    assert len(lines) == 1 and lines[0].startswith("error: "), lines
    return lines[0]


def run_inflate(tmp_path, scene: Path, *flags, out="out") -> int:
    return inflate.main(["--scene", str(scene), "--out", str(tmp_path / out), *QUICK, *flags])


class Inline:
    """A study executor running the tasks in this process, one after the other (no worker start-up)."""

    def describe(self) -> dict:
        return {"executor": "inline"}

    def run(self, tasks):
        for i, task in enumerate(tasks):
            yield i, run_task(task)


# --- 1. size guards ---------------------------------------------------------------------------------


def test_a_thin_strip_is_stopped_by_the_triangle_budget_not_meshed_for_minutes(tmp_path, capsys):
    """The estimate sees area and outline (about 256 triangles); quality meshing fills the 1e-4 wide,
    99 long strip with ~745,000 triangles (before: 73 s, then out of memory). Triangle now stops at its
    cap of added points."""
    body = f'[body]\nshape = "polygon"\npoints = {STRIP}'
    path = scene_file(
        tmp_path,
        CHEAP,
        ('[body]\nshape = "rectangle"\ncenter = [0.0, 0.0]\nsize = [3.5, 0.8]', body),
        ("semi_axes = [0.85, 0.22]", "semi_axes = [0.3, 0.1]"),
        ("center = [0.0, 0.15]", "center = [0.0, 0.2]"),
    )
    start = time.perf_counter()
    assert run_inflate(tmp_path, path, "--max-triangles", "20000") == 2
    assert time.perf_counter() - start < 10.0
    line = error_line(capsys)
    assert "the mesh needs more than 20000 triangles: Triangle stopped at its cap" in line
    assert "(--max-triangles raises it)" in line


def test_the_budget_leaves_meshes_under_it_unchanged_and_is_what_a_mesher_asks():
    """The cap (Triangle's S switch) stops nothing a budget allows: the same mesh as without one. A mesher
    (2D or 3D) asks its budget's element_cap(weight) and reports through its check_mesh."""
    geometry = Geometry(Polygon(tuple(map(tuple, STRIP))), (("c", Ellipse((0.0, 0.2), (0.3, 0.1), 32)),), 0.02)
    small = Geometry(geometry.body, geometry.chambers, 0.02, order=2)
    assert Budget().element_cap() is None
    budget = Budget(1000)
    assert budget.element_cap() == 1000 and budget.element_cap(4) == 250
    with pytest.raises(PneumaInputError, match="Triangle stopped at its cap of 1000 added points"):
        geometry.mesh(budget)
    with pytest.raises(PneumaInputError, match="stopped at its cap of 250 added points"):
        small.mesh(budget)  # quadratic triangles count 4 times
    reference = tp.reference_scene(max_area=0.02).geometry
    free = reference.mesh()
    capped = reference.mesh(Budget(2 * free.n_triangles))
    assert np.array_equal(capped.vertices, free.vertices) and np.array_equal(capped.triangles, free.triangles)
    with pytest.raises(PneumaInputError, match="the mesh has"):
        reference.mesh(Budget(free.n_triangles - 1))


def test_self_contact_pairs_count_in_the_estimate_and_are_checked_before_they_are_allocated(tmp_path, capsys):
    """A wall of k nodes has k (k - 2) point-edge pairs, about 2.5 kB each (before: a 1990-point wall
    was estimated at 0.025 GB and tried to allocate > 1 GiB)."""
    path = scene_file(tmp_path, CHEAP + "\n[effects.self_contact]\n", ("points = 128", "points = 300"))
    assert run_inflate(tmp_path, path, "--max-triangles", "20000") == 2
    line = error_line(capsys)
    assert "and 89400 self-contact pairs (walls of 300 nodes)" in line and "the limit is 20000 triangles" in line
    assert not (tmp_path / "out").exists()
    from taichi_pneuma.terms.effects import SelfContact

    scene = tp.reference_scene(max_area=0.02, chamber_points=100)  # 363 triangles, a wall of 100 nodes
    with pytest.raises(PneumaInputError, match="self-contact would hold 9800 point-edge pairs"):
        dataclasses.replace(scene, effects=(SelfContact(),)).build(Budget(1000))


# --- 2. parsers with depth and length limits -------------------------------------------------------


@pytest.mark.parametrize(
    "text, words",
    [
        ("a" + ".a" * 499_000 + " = 1\n", "a dotted key of more than 16 parts"),  # 998 kB: before, minutes
        ("[" + ".".join(["x"] * 3000) + "]\n", "a dotted key of more than 16 parts"),  # before: RecursionError
        ("a = " + "{a = " * 3000 + "1" + "}" * 3000, "nested too deeply"),
        ("a = " + "[" * 20 + "]" * 20, "nested too deeply \\(at most 16 levels\\)"),
    ],
    ids=["499000-part key", "3000-part header", "deep inline tables", "20 deep arrays"],
)
def test_deep_or_long_keys_in_a_scene_file_are_refused_at_once(tmp_path, text, words):
    path = tmp_path / "deep.toml"
    path.write_text(text)
    start = time.perf_counter()
    with pytest.raises(PneumaInputError, match=words):
        load_scene(path)
    assert time.perf_counter() - start < 2.0


@pytest.mark.parametrize(
    "assignment, words",
    [
        ("name=" + "[" * 3000 + "]" * 3000, "nested too deeply"),
        (".".join(["a"] * 20_000) + "=1", "has more than 16 parts"),
        ("chambers[0].name=ab\udcff", "is not valid UTF-8"),  # a byte the terminal could not decode
        ("name=" + "x" * 100_001, "the value has 100001 characters"),
    ],
    ids=["3000-deep value", "20000-part key", "undecodable byte", "long value"],
)
def test_deep_long_or_undecodable_set_values_are_one_error_line(tmp_path, capsys, assignment, words):
    """Before: RecursionError tracebacks; the undecodable byte crashed the CSV/VTU writer after the run."""
    assert run_inflate(tmp_path, scene_file(tmp_path), "--set", assignment) == 2
    assert words in error_line(capsys)
    assert not (tmp_path / "out").exists()


def test_keys_and_values_read_the_same_within_the_limits():
    assert parse_key("chambers[0].keyframes[1][0]") == ["chambers", 0, "keyframes", 1, 0]
    assert parse_assignment("body.points=[[0, 0], [1, 0], [1, 1]]") == ("body.points", [[0, 0], [1, 0], [1, 1]])
    assert parse_assignment("name=café") == ("name", "café")
    with pytest.raises(PneumaInputError, match="more than 16 parts"):
        tp.reference_scene().with_value(".".join(["a"] * 20_000), 1)


# --- 3. result files: no link followed, no other run interleaved -----------------------------------


def test_links_planted_in_out_are_replaced_or_refused_never_followed(tmp_path):
    """Before: a link at the predictable temporary name made the run overwrite the file it points to."""
    victim = tmp_path / "victim.txt"
    victim.write_text("precious")
    out = tmp_path / "out"
    out.mkdir()
    for name in (
        ".reference_beam_history.csv.partial.csv",
        ".reference_beam_summary.json.partial.json",
        "reference_beam_summary.json",
        ".reference_beam.pvd.partial.pvd",
    ):
        (out / name).symlink_to(victim)
    assert run_inflate(tmp_path, scene_file(tmp_path)) == 0
    assert victim.read_text() == "precious"
    assert not (out / "reference_beam_summary.json").is_symlink()
    assert json.loads((out / "reference_beam_summary.json").read_text())["steps"] == 3


def test_a_link_at_the_vtk_folder_is_refused_and_its_target_untouched(tmp_path, capsys):
    """Before: the run deleted and wrote VTU files in the directory the link pointed to."""
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    (elsewhere / "reference_beam_0000.vtu").write_text("someone's")
    (tmp_path / "out").mkdir()
    (tmp_path / "out" / "reference_beam_vtk").symlink_to(elsewhere, target_is_directory=True)
    assert run_inflate(tmp_path, scene_file(tmp_path)) == 2
    assert "reference_beam_vtk' is a link, not a folder" in error_line(capsys)
    assert os.listdir(elsewhere) == ["reference_beam_0000.vtu"]
    assert (elsewhere / "reference_beam_0000.vtu").read_text() == "someone's"


def hold_lock(path: Path) -> subprocess.Popen:
    """Another process holding path's flock (as a run of the same stem does) until it is killed."""
    holder = (
        "import fcntl, os, sys, time; fd = os.open(sys.argv[1], os.O_RDWR | os.O_CREAT); "
        "fcntl.flock(fd, fcntl.LOCK_EX); print('held', flush=True); time.sleep(60)"
    )
    proc = subprocess.Popen([sys.executable, "-c", holder, str(path)], stdout=subprocess.PIPE, text=True)
    assert proc.stdout.readline().strip() == "held"
    return proc


def test_a_second_run_of_a_stem_is_one_error_naming_it(tmp_path, capsys):
    """Before: interleaved VTU files (a PVD listing 49 missing and 16 foreign steps), a false 'No such
    file or directory', two sweeps accepted under one name."""
    out = tmp_path / "out"
    out.mkdir()
    holder = hold_lock(out / ".reference_beam.lock")
    try:
        assert run_inflate(tmp_path, scene_file(tmp_path)) == 2
        line = error_line(capsys)
        assert "another run is writing the results named 'reference_beam'" in line and "it holds" in line
        assert sweep.main(["--vary", "cy=0,0.1", "--out", str(out), "--name", "reference_beam", "--quiet"]) == 2
        assert "another run is writing the results named 'reference_beam'" in error_line(capsys)
        assert sorted(os.listdir(out)) == [".reference_beam.lock"]
    finally:
        holder.kill()
        holder.wait()
    assert run_inflate(tmp_path, scene_file(tmp_path)) == 0
    assert set(os.listdir(out)) == RESULTS | {"reference_beam_vtk"}  # the lock file is gone with its run
    from taichi_pneuma.io.output import lock_stem

    with lock_stem(out, "x"), lock_stem(out, "x"):  # re-entrant in one process
        assert (out / ".x.lock").exists()
    assert not (out / ".x.lock").exists()


@pytest.mark.slow
def test_two_different_sweeps_under_one_name_one_is_refused(tmp_path):
    """Two processes at once: whichever comes second is refused, by the lock or (if the first has ended)
    as another study; the survivor's rows are all there."""
    out = tmp_path / "out"
    command = [
        sys.executable,
        "-m",
        "taichi_pneuma.apps.sweep",
        "--steps",
        "3",
        "--max-area",
        "0.02",
        "--workers",
        "1",
        "--out",
        str(out),
        "--quiet",
    ]
    procs = [
        subprocess.Popen([*command, "--vary", vary], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=ENV)
        for vary in ("cy=-0.1,0.1", "E=1e4,2e4")
    ]
    outcomes = [(p.wait(timeout=300), p.stderr.read()) for p in procs]
    assert sorted(code for code, _ in outcomes) == [0, 2], outcomes
    refused = next(err for code, err in outcomes if code == 2)
    assert "another run is writing the results named 'sweep'" in refused or "holds another study" in refused
    with open(out / "sweep.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 2 and all(row["error"] == "" and row["tip_dy"] for row in rows)


# --- 4. failures that became tracebacks -------------------------------------------------------------


def test_a_ramp_that_fails_at_step_0_is_one_line_and_saves_nothing(tmp_path, capsys):
    """Before: IndexError/KeyError in save_history (no step done)."""
    path = scene_file(tmp_path, (SCENES / "finger_on_ground.toml").read_text(), ("max_area = 0.004", "max_area = 0.02"))
    assert run_inflate(tmp_path, path, "--max-iterations", "1") == 1
    assert error_line(capsys).startswith("error: step 0: no equilibrium")
    assert not any(p.is_file() for p in (tmp_path / "out").rglob("*"))


def test_a_huge_time_step_is_the_quasistatic_limit_not_an_overflow(tmp_path, capsys):
    """Before: OverflowError in masses / dt**2."""
    assert (
        run_inflate(
            tmp_path, scene_file(tmp_path), "--set", "effects.dynamics.density=1", "--set", "effects.dynamics.dt=1e300"
        )
        == 0
    )
    (path,) = (tmp_path / "out").glob("reference_beam_*_summary.json")  # named by the scene's hash
    dynamic = json.loads(path.read_text())["tip_deflection"]
    assert run_inflate(tmp_path, scene_file(tmp_path), out="static") == 0
    static = json.loads((tmp_path / "static" / "reference_beam_summary.json").read_text())["tip_deflection"]
    assert dynamic == pytest.approx(static, rel=1e-6)


def test_a_file_at_the_vtk_folder_is_refused_before_solving_and_a_folder_at_a_partial_name_is_no_obstacle(
    tmp_path, capsys
):
    """Before: FileExistsError / IsADirectoryError after the run, its results not saved."""
    out = tmp_path / "out"
    out.mkdir()
    (out / "reference_beam_vtk").write_text("not a folder")
    assert run_inflate(tmp_path, scene_file(tmp_path)) == 2
    assert "reference_beam_vtk' is a file, not a folder" in error_line(capsys)
    (out / "reference_beam_vtk").unlink()
    (out / ".reference_beam_history.csv.partial.csv").mkdir()  # the old temporary name, taken by a folder
    assert run_inflate(tmp_path, scene_file(tmp_path)) == 0
    assert RESULTS <= set(os.listdir(out))


def test_damaged_study_files_are_one_error_or_a_rerun_never_a_traceback(tmp_path):
    """Before: a 131,073-character CSV field (csv.Error), a JSON that is [] or null (AttributeError), deep
    JSON (RecursionError) crashed every rerun; a non-numeric tip_dy crashed the progress line and plot."""
    base, axes = tp.reference_scene(max_area=0.02, steps=3), [parse_vary("cy=-0.1,0.1")]
    out = tmp_path / "study"
    Sweep(base, axes, out).run(Inline())
    csv_text, json_text = (out / "sweep.csv").read_text(), (out / "sweep.json").read_text()
    for damage in ("[]", "null", "[" * 100_000):
        (out / "sweep.json").write_text(damage)
        with pytest.raises(PneumaInputError, match="holds another study .*damaged"):
            Sweep(base, axes, out)
    (out / "sweep.json").write_text(json_text)
    (out / "sweep.csv").write_text(csv_text + '0.5,"' + "x" * 140_000 + '"\n')
    with pytest.raises(PneumaInputError, match="holds another study .*damaged"):
        Sweep(base, axes, out)
    lines = csv_text.splitlines(keepends=True)
    header = lines[0].rstrip("\r\n").split(",")
    tampered = lines[1].rstrip("\r\n").split(",")
    tampered[header.index("tip_dy")] = "abc"
    (out / "sweep.csv").write_text(lines[0] + ",".join(tampered) + "\r\n" + lines[2])
    again = Sweep(base, axes, out)
    assert len(again.todo) == 1  # the tampered row's run runs again
    report = again.run(Inline())
    assert report.ran == 1 and all(isinstance(row["tip_dy"], float) for row in report.rows)
    with pytest.raises(PneumaInputError, match="a value of more than 10000 characters"):
        parse_vary("name=" + "x" * 20_000)


@pytest.mark.filterwarnings("ignore:constrained_layout not applied")  # 1e100-wide tick labels
@pytest.mark.parametrize(
    "keys, values",
    [
        (["k"], [(1.0, 1e308), (2.0, -1e308)]),
        (["k"], [(1e308, 1.0)]),
        (["k", "j"], [((-1e308, 1.0), 1.0), ((1e308, 2.0), 2.0)]),
        (["k", "j"], [((-1.0, 1.0), -1e308), ((1.0, 2.0), 1e308)]),
        (["k"], [(1e-300, 1e-300), (2e-300, -1e-300)]),
    ],
)
def test_the_study_plot_draws_extreme_values(keys, values):
    """Before: LinAlgError, 'Axis limits cannot be NaN or Inf', 'arange: cannot compute length' after the CSV."""
    rows = [
        {**dict(zip(keys, k if isinstance(k, tuple) else (k,))), "tip_dy": tip, "tip_dx": 0.0, "error": None}
        for k, tip in values
    ]
    import io

    study_figure(rows, keys).savefig(io.BytesIO(), format="png", dpi=50)


def test_arch_gpu_without_a_gpu_that_runs_64_bit_kernels_is_one_error_line(tmp_path):
    """Before: a RuntimeError traceback from the Vulkan code generator (no 64-bit atan2); where Taichi finds no
    Vulkan driver at all, a segfault (exit -11), which the probe process now turns into the error line."""
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "taichi_pneuma.apps.inflate",
            "--arch",
            "gpu",
            "--steps",
            "2",
            "--max-area",
            "0.02",
            *QUICK,
            "--out",
            str(tmp_path / "out"),
        ],
        capture_output=True,
        text=True,
        env=ENV,
        timeout=120,
        check=False,
    )
    if "Starting on arch=cuda" in proc.stdout + proc.stderr:
        pytest.skip("this machine has CUDA: --arch gpu runs")
    assert proc.returncode == 2 and "Traceback" not in proc.stderr, proc.stderr
    assert (
        "which cannot run this program's 64-bit kernels; use cpu, or cuda" in proc.stderr
        or "starting it here crashed a test process (signal SIGSEGV" in proc.stderr
    ), proc.stderr


def interrupted_early(command: list[str], delay: float, **kwargs) -> subprocess.CompletedProcess:
    proc = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=ENV, **kwargs)
    time.sleep(delay)
    group = kwargs.get("start_new_session")
    os.killpg(proc.pid, signal.SIGINT) if group else proc.send_signal(signal.SIGINT)
    try:
        stdout, stderr = proc.communicate(timeout=120)
    except subprocess.TimeoutExpired:  # a hang: end it, and the test fails
        os.killpg(proc.pid, signal.SIGKILL) if group else proc.kill()
        raise
    return subprocess.CompletedProcess(command, proc.returncode, stdout, stderr)


@pytest.mark.parametrize("app", ["inflate", "bench"])
def test_ctrl_c_while_loading_or_in_bench_is_one_line_and_130(tmp_path, app):
    """Ctrl-C 0.4 s after the start (the modules are loading), or once bench has begun its section.
    Before: a KeyboardInterrupt traceback of the imports, or of the benchmark."""
    command = [sys.executable, "-m", f"taichi_pneuma.apps.{app}", "--out", str(tmp_path / "out")]
    if app == "bench":
        proc = subprocess.Popen(
            [*command, "--sections", "breakdown"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=ENV
        )
        for line in proc.stdout:
            if line.startswith("## breakdown"):
                proc.send_signal(signal.SIGINT)
                break
        _, stderr = proc.communicate(timeout=120)
        done = subprocess.CompletedProcess(command, proc.returncode, "", stderr)
    else:
        done = interrupted_early([*command, *QUICK], 0.4)
    assert done.returncode == 130 and "Traceback" not in done.stderr, done.stderr
    assert [line for line in done.stderr.splitlines() if line.startswith("error:")] == ["error: interrupted (Ctrl-C)"]


# --- 5. signals ---------------------------------------------------------------------------------------


def signalled_at_step_3(app: str, steps: int, out: Path, signum: int) -> tuple[int, str]:
    """Run an app's ramps of `steps` commanded areas, send it signum once step 3 is reported; (exit code, stderr)."""
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            f"taichi_pneuma.apps.{app}",
            "--steps",
            str(steps),
            "--max-area",
            "0.02",
            "--no-video",
            "--out",
            str(out),
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=ENV,
    )
    for line in proc.stdout:
        if f"step   3/{steps - 1}" in line:
            proc.send_signal(signum)
            break
    _, stderr = proc.communicate(timeout=120)
    return proc.returncode, stderr


@pytest.mark.parametrize("signum", [signal.SIGTERM, signal.SIGHUP], ids=["SIGTERM", "SIGHUP"])
def test_sigterm_and_sighup_stop_a_ramp_like_ctrl_c_and_keep_the_steps_done(tmp_path, signum):
    """Before: the process died at once; only the VTU files were left."""
    out = tmp_path / "out"
    code, stderr = signalled_at_step_3("inflate", 400, out, signum)
    name = SIGNAL_NAMES[signum]
    assert code == 128 + signum and "Traceback" not in stderr, stderr
    errors = [line for line in stderr.splitlines() if line.startswith("error:")]
    assert len(errors) == 1 and errors[0].endswith(f"of 399 ({name})")
    summary = json.loads((out / "inflate_cy+0.15_steps400_max_area0.02_summary.json").read_text())
    assert summary["interrupted"] is True and 4 <= summary["steps"] < 400
    assert len(np.load(out / "inflate_cy+0.15_steps400_max_area0.02_states.npz")["positions"]) == summary["steps"]


def test_a_signal_while_results_are_saved_waits_for_them(tmp_path, monkeypatch):
    """Before: a Ctrl-C during Result.save (after a whole ramp) left no history, npz or summary."""
    result = tp.simulate(tp.reference_scene(max_area=0.02, steps=3))
    real = np.savez  # output.save_npz writes uncompressed (faster)

    def interrupted_savez(*args, **kwargs):
        os.kill(os.getpid(), signal.SIGINT)  # arrives in the middle of the saving
        return real(*args, **kwargs)

    monkeypatch.setattr(np, "savez", interrupted_savez)
    # Python's own Ctrl-C handler before the save, as in a command's process (a test worker's may differ)
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        with pytest.raises(KeyboardInterrupt):
            result.save(tmp_path, vtk=False, plot=False)
    finally:
        signal.signal(signal.SIGINT, previous)
    assert sorted(os.listdir(tmp_path)) == [
        "reference_cy+0.15_history.csv",
        "reference_cy+0.15_scene.toml",
        "reference_cy+0.15_states.npz",
        "reference_cy+0.15_summary.json",
    ]


def test_steer_saves_the_ramps_done_on_ctrl_c(tmp_path):
    """Before: nothing but the VTU files."""
    out = tmp_path / "out"
    code, stderr = signalled_at_step_3("steer", 200, out, signal.SIGINT)
    assert code == 130 and "Traceback" not in stderr, stderr
    summary = json.loads((out / "steer_steps200_max_area0.02_summary.json").read_text())
    assert summary["interrupted"] is True and list(summary["steps"]) == ["+0.15"] and summary["steps"]["+0.15"] >= 4


@pytest.mark.slow
def test_a_terminal_ctrl_c_early_in_a_sweep_ends_it_without_a_hang(tmp_path):
    """Ctrl-C to the whole process group while the workers start. Before: a traceback of the imports,
    or a hang (InvalidStateError in the executor thread) until a second Ctrl-C."""
    done = interrupted_early(
        [
            sys.executable,
            "-m",
            "taichi_pneuma.apps.sweep",
            "--vary",
            "cy=-0.1,0,0.1,0.15",
            "--steps",
            "5",
            "--max-area",
            "0.02",
            "--workers",
            "2",
            "--out",
            str(tmp_path / "out"),
            "--quiet",
        ],
        4.0,
        start_new_session=True,
    )
    assert done.returncode in (0, 130) and "Traceback" not in done.stderr, done.stderr
    errors = [line for line in done.stderr.splitlines() if line.startswith("error:")]
    assert errors == (["error: interrupted (Ctrl-C)"] if done.returncode else [])


def running(pid: int) -> bool:
    """Whether the process runs (exists and is not a zombie)."""
    try:
        return Path(f"/proc/{pid}/stat").read_text().split()[2] != "Z"
    except FileNotFoundError:
        return False


def children(pid: int) -> list[int]:
    found = []
    for entry in os.listdir("/proc"):
        try:
            status = Path(f"/proc/{entry}/status").read_text()
        except (OSError, ValueError):
            continue
        if entry.isdigit() and f"\nPPid:\t{pid}\n" in status:
            found.append(int(entry))
    return found


@pytest.mark.slow
@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
def test_sweep_workers_die_with_their_parent_killed_outright(tmp_path):
    """Before: SIGKILL (or SIGTERM) of the sweep left its workers running as orphans (~190 MB each)."""
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "taichi_pneuma.apps.sweep",
            "--vary",
            "cy=-0.1,-0.05,0,0.05,0.1,0.15",
            "--steps",
            "200",
            "--max-area",
            "0.01",
            "--workers",
            "2",
            "--out",
            str(tmp_path / "out"),
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.DEVNULL,
        text=True,
        env=ENV,
    )
    for line in proc.stdout:
        if line.startswith("study sweep:"):
            break
    workers, deadline = [], time.monotonic() + 60  # generous: a loaded machine starts the workers slowly
    while len(workers) < 2 and time.monotonic() < deadline:
        workers = [pid for pid in children(proc.pid) if "spawn_main" in Path(f"/proc/{pid}/cmdline").read_text()]
        time.sleep(0.1)
    assert len(workers) == 2
    time.sleep(1.0)  # into their runs
    proc.kill()
    proc.wait()
    try:
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline and any(map(running, workers)):
            time.sleep(0.1)
        assert not [pid for pid in workers if running(pid)]
    finally:
        for pid in workers:
            try:
                os.kill(pid, signal.SIGKILL)
            except ProcessLookupError:
                pass


def test_partial_files_of_killed_runs_are_cleaned(tmp_path):
    """Before: a .partial.vtu left by SIGKILL was never removed."""
    out = tmp_path / "out"
    (out / "reference_beam_vtk").mkdir(parents=True)
    (out / "reference_beam_vtk" / ".reference_beam_0001.vtu.partial.vtu").write_text("killed")  # the old name
    dead = out / ".reference_beam_history.csv.999999999.abcdefgh.partial"  # a process that no longer runs
    dead.mkdir()
    (dead / "reference_beam_history.csv").write_text("half")
    live = out / f".other.csv.{os.getpid()}.abcdefgh.partial"  # this one runs: kept
    live.mkdir()
    assert run_inflate(tmp_path, scene_file(tmp_path)) == 0
    assert not dead.exists() and live.exists()
    assert sorted(os.listdir(out / "reference_beam_vtk")) == [f"reference_beam_{i:04d}.vtu" for i in range(3)]


# --- 6. unbounded work -------------------------------------------------------------------------------


def test_too_many_targets_are_refused_at_once(tmp_path):
    """Before: 25,000 [[targets]] were accepted (two hours of reaches); /dev/zero was read until the OOM
    killer ended it at 21.8 GB."""
    path = scene_file(tmp_path, CHEAP + "".join("\n[[targets]]\ntip = [1.7, -0.1]\n" for _ in range(25_000)))
    with pytest.raises(PneumaInputError, match="25000 \\[\\[targets\\]\\]: at most 1000 are allowed"):
        load_scene(path)
    rows = tmp_path / "targets.csv"
    rows.write_text("x,y\n" + "1.7,-0.1\n" * 1001)
    with pytest.raises(PneumaInputError, match="more than 1000 targets"):
        read_targets_csv(rows)
    rows.write_text("x,y\n" + " " * 1_000_001)
    with pytest.raises(PneumaInputError, match="larger than 1000000 bytes"):
        read_targets_csv(rows)
    start = time.perf_counter()
    with pytest.raises(PneumaInputError, match="is not a regular file"):
        read_targets_csv("/dev/zero")
    assert time.perf_counter() - start < 1.0


def test_a_fifo_as_scene_or_targets_is_refused_without_waiting(tmp_path):
    """Before: `--scene FIFO` blocked for ever (no writer)."""
    fifo = tmp_path / "scene.toml"
    os.mkfifo(fifo)
    start = time.perf_counter()
    for read in (load_scene, read_targets_csv):
        with pytest.raises(PneumaInputError, match="is not a regular file"):
            read(fifo)
    assert time.perf_counter() - start < 1.0


def test_the_run_count_of_a_grid_is_counted_in_python_integers():
    """Four axes of 65,536 values: 2^64 runs, which NumPy's int64 product wrapped to 0 (then planned)."""
    axes = [parse_vary(f"chambers[0].keyframes[1][{i % 2}]=1:65536:65536") for i in range(4)]
    start = time.perf_counter()
    with pytest.raises(PneumaInputError, match=f"the grid has {2**64} runs; the limit is 100000"):
        plan(axes)
    assert time.perf_counter() - start < 5.0


# --- 7. data -------------------------------------------------------------------------------------------


def test_varying_a_chamber_name_keeps_the_study_columns_and_cells_are_formula_safe(tmp_path):
    """Before: the run's chamber columns were blank (named after the run's chamber, not the study's);
    a value starting with = went into the CSV as a formula."""
    base = tp.reference_scene(max_area=0.02, steps=3)
    report = Sweep(base, [parse_vary("chambers[0].name=other,+x")], tmp_path).run(Inline())
    with open(tmp_path / "sweep.csv", newline="") as f:
        rows = {row["chambers[0].name"]: row for row in csv.DictReader(f)}
    assert set(rows) == {"other", '"+x"'}  # a JSON string: a spreadsheet reads it as text
    assert float(rows["other"]["main.area_ratio"]) == pytest.approx(3.5, abs=0.05)
    assert "cannot start with" in rows['"+x"']["error"]  # as a chamber name it is refused (below)
    assert [row["chambers[0].name"] for row in report.rows] == ["other", "+x"]
    assert Sweep(base, [parse_vary("chambers[0].name=other,+x")], tmp_path).todo == []  # read back the same


@pytest.mark.parametrize("name", ["=1+1", "+x", "-rf", "@SUM(A1)", "\tx"])
def test_a_chamber_name_that_a_spreadsheet_would_read_as_a_formula_is_refused(tmp_path, name):
    with pytest.raises(PneumaInputError, match=r"cannot start with = \+ - @"):
        tp.reference_scene().with_value("chambers[0].name", name)
    path = scene_file(tmp_path, CHEAP, ('name = "main"', f"name = {json.dumps(name)}"))
    with pytest.raises(PneumaInputError, match=r"scene.toml: chamber name .* cannot start with"):
        load_scene(path)
