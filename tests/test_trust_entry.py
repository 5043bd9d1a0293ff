"""Issue 28, the entry points: a finished run survives a signal, a signal during cut-backs ends the run at once,
small mesh files cannot claim large memory, and every bad input at every entry point (command lines,
environment variables, the Python API) is one `error:` line (PneumaInputError), never a traceback."""

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from solid_meshes import extruded_beam, lzma_vtu, moved_up

ENV = {**os.environ, "PYTHONUNBUFFERED": "1"}
STEM = "inflate_cy+0.15_steps4_max_area0.02"
CHEAP = ["--steps", "4", "--max-area", "0.02"]


def app(name: str, *args: str, env: dict | None = None, timeout: float = 120) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", f"taichi_pneuma.apps.{name}", *args],
        capture_output=True,
        text=True,
        env=env or ENV,
        timeout=timeout,
        check=False,
    )


def one_error_line(done: subprocess.CompletedProcess, *needles: str) -> str:
    """The run's one `error:` line (exit 2, no traceback), which names each of needles."""
    errors = [line for line in done.stderr.splitlines() if line.startswith("error:")]
    assert done.returncode == 2 and "Traceback" not in done.stderr and len(errors) == 1, done.stderr
    assert all(needle in errors[0] for needle in needles), errors[0]
    return errors[0]


# --- 1. signals -----------------------------------------------------------------------------------------


def signalled_when(line_seen: str, signum: int, out: Path, *flags: str, delay: float = 0.0):
    """Run pneuma-inflate, send signum `delay` s after it prints a line containing line_seen; (exit code, stderr,
    seconds from the signal to the exit). A run still alive 20 s after the signal is killed (exit None)."""
    proc = subprocess.Popen(
        [sys.executable, "-m", "taichi_pneuma.apps.inflate", *CHEAP, "--out", str(out), *flags],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=ENV,
    )
    for line in proc.stdout:
        if line_seen in line:
            time.sleep(delay)
            proc.send_signal(signum)
            break
    sent = time.perf_counter()
    try:
        _, stderr = proc.communicate(timeout=20)
    except subprocess.TimeoutExpired:
        proc.kill()
        _, stderr = proc.communicate()
        return None, stderr, time.perf_counter() - sent
    return proc.returncode, stderr, time.perf_counter() - sent


@pytest.mark.parametrize(
    "signum, delay",
    [(signal.SIGINT, 0.0), (signal.SIGTERM, 0.0), (signal.SIGTERM, 0.1)],
    ids=["SIGINT", "SIGTERM", "SIGTERM-0.1s-later"],
)
def test_a_signal_once_the_last_increment_is_solved_waits_for_every_result_file(tmp_path, signum, delay):
    """The signal comes as the last step's line is printed (the run is finished, no file written yet). Before:
    only the PVD and the VTU files were left."""
    out = tmp_path / "out"
    code, stderr, _ = signalled_when("step   3/3", signum, out, "--size", "128x64", delay=delay)
    # 128 + signal once the files are written (0 only where the run ended before the signal came)
    assert code in (0, 128 + signum) and "Traceback" not in stderr, stderr
    assert [line for line in stderr.splitlines() if line.startswith("error:")] == [
        f"error: interrupted ({'Ctrl-C' if signum == signal.SIGINT else 'SIGTERM'})"
    ][: code != 0]
    summary = json.loads((out / f"{STEM}_summary.json").read_text())
    assert summary["steps"] == 4 and summary["interrupted"] is False and summary["video_frames"] == 4
    rows = (out / f"{STEM}_history.csv").read_text().splitlines()
    assert [row.split(",")[0] for row in rows[1:]] == ["0", "1", "2", "3"]
    assert np.load(out / f"{STEM}_states.npz")["positions"].shape[0] == 4
    for name in (f"{STEM}.mp4", f"{STEM}.png", f"{STEM}_plot.png", f"{STEM}_scene.toml", f"{STEM}.pvd"):
        assert (out / name).stat().st_size > 0, name
    assert len(list((out / f"{STEM}_vtk").glob("*.vtu"))) == 4
    assert not list(out.rglob("*.partial"))


def test_a_signal_while_an_increment_cuts_back_ends_the_run_within_a_second(tmp_path):
    """One Newton iteration per try and 100000 cuts allowed: step 1 creeps by ever smaller cuts. Before: the
    first SIGTERM was noted and waited for the increment's end, minutes away."""
    out = tmp_path / "out"
    code, stderr, seconds = signalled_when(
        "step   0/3", signal.SIGTERM, out, "--max-iterations", "1", "--max-cuts", "100000", "--no-video", delay=1.0
    )
    assert code == 143 and seconds < 2.0 and "Traceback" not in stderr, (code, seconds, stderr)
    errors = [line for line in stderr.splitlines() if line.startswith("error:")]
    assert errors == ["error: interrupted during step 1 of 3 (SIGTERM)"]
    summary = json.loads((out / f"{STEM}_summary.json").read_text())
    assert summary["interrupted"] is True and summary["steps"] == 1


# --- 2. memory from small files ---------------------------------------------------------------------------


def scene_of_mesh(directory: Path, mesh: Path) -> Path:
    scene = directory / "scene.toml"
    scene.write_text(
        f'name = "small_file"\n[body]\nshape = "mesh"\nfile = "{mesh.name}"\n[clamp]\nside = "left"\n'
        '[[chambers]]\nname = "main"\nshape = "mesh_surface"\ngroup = "chamber"\ncontrol = "volume"\n'
        "keyframes = [[0, 1.0], [2, 1.5]]\n[schedule]\nincrements = 2\n"
    )
    return scene


MEASURE = """import resource, subprocess, sys
done = subprocess.run(sys.argv[2:], stdout=subprocess.DEVNULL)
open(sys.argv[1], "w").write(str(resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss * 1024))
sys.exit(done.returncode)
"""


def measured(command: list, folder: Path) -> tuple[subprocess.CompletedProcess, int]:
    """Run command (its stdout dropped) and return it with its peak resident memory in bytes, counted by a small
    Python process that starts it: on Linux a process started straight from this one (a test worker of a GB or
    more) inherits its high-water mark through fork and exec, so only a grandchild's peak is its own."""
    peak = folder / "peak.txt"
    done = subprocess.run(
        [sys.executable, "-c", MEASURE, str(peak), *command], capture_output=True, text=True, env=ENV, timeout=300
    )
    return done, int(peak.read_text())


def test_a_small_mesh_file_that_claims_gigabytes_is_refused_at_low_memory(tmp_path):
    """Before: 5.3 GB resident (meshio decompressed every block, then failed on the array's size)."""
    mesh = lzma_vtu(tmp_path / "mesh.vtu")
    assert mesh.stat().st_size < 600_000
    done, peak = measured(
        [
            sys.executable,
            "-m",
            "taichi_pneuma.apps.inflate",
            "--scene",
            str(scene_of_mesh(tmp_path, mesh)),
            "--no-video",
            "--out",
            str(tmp_path / "out"),
        ],
        tmp_path,
    )
    one_error_line(done, str(mesh), "bytes of memory")
    assert peak < 800e6  # the reader's bound is 256 MB above the process's size


# --- 3. one line for every bad input, at every entry point ----------------------------------------------


@pytest.mark.parametrize(
    "command, needles",
    [
        (["inflate", "--scene", "{tmp}"], ["is not a regular file"]),
        (["inflate", "--scene", "x" * 5000], ["(5000 characters) cannot be read (File name too long)"]),
        (["reach", "--targets", "{tmp}"], ["targets file", "is not a regular file"]),
    ],
    ids=["scene-folder", "scene-5000-characters", "targets-folder"],
)
def test_a_path_that_is_a_folder_or_too_long_is_one_error_line(tmp_path, command, needles):
    """Before: IsADirectoryError and OSError (File name too long) tracebacks, exit 1."""
    done = app(*[part.replace("{tmp}", str(tmp_path)) for part in command], "--out", str(tmp_path / "out"))
    line = one_error_line(done, *needles)
    assert len(line) < 400


@pytest.mark.parametrize("variable", ["PNEUMA_BACKEND", "PNEUMA_TRIANGLE"])
@pytest.mark.parametrize(
    "name, args",
    [
        ("inflate", CHEAP + ["--no-video"]),
        ("steer", CHEAP + ["--no-video"]),
        ("reach", ["--tip", "3", "0"]),
        ("sweep", ["--vary", "cy=0,0.1", "--workers", "1", *CHEAP]),
        ("bench", ["--sections", "startup"]),
    ],
)
def test_an_environment_variable_naming_no_backend_is_one_error_line_at_every_command(tmp_path, variable, name, args):
    """Before: an ImportError traceback (exit 1), and the sweep recorded the error in every row and exited 0."""
    done = app(name, *args, "--out", str(tmp_path / "out"), env={**ENV, variable: "garbage"})
    one_error_line(done, f"{variable}='garbage' is not one of")
    assert not (tmp_path / "out").exists() or not list((tmp_path / "out").glob("*.csv"))


API_BACKEND = """
import taichi_pneuma as tp
try:
    tp.simulate(tp.reference_scene(max_area=0.05, steps=2))
except tp.PneumaInputError as exc:
    print("refused:", exc)
"""


def test_the_api_under_an_environment_variable_naming_no_backend_raises_the_input_error():
    """Before: an ImportError that is no PneumaInputError, unlike every other bad input through the API."""
    done = subprocess.run(
        [sys.executable, "-c", API_BACKEND],
        capture_output=True,
        text=True,
        timeout=120,
        env={**ENV, "PNEUMA_BACKEND": "garbage"},
        check=False,
    )
    assert done.returncode == 0 and "refused: PNEUMA_BACKEND='garbage' is not one of" in done.stdout, done.stderr


def test_an_arch_whose_driver_crashes_the_process_is_one_error_line(tmp_path):
    """--arch opengl here has no driver: Taichi segfaults while starting it (before: exit -11, no line). Where
    a driver exists it starts, and the arch is refused for its 32-bit floats, or (CUDA) runs."""
    done = app("inflate", "--arch", "opengl", *CHEAP, "--no-video", "--out", str(tmp_path / "out"))
    if done.returncode == 0:
        pytest.skip("this machine runs --arch opengl")
    line = one_error_line(done, "arch = 'opengl'")
    assert "use cpu, or cuda" in line or "is not one this backend has" in line, line  # Quadrants has no opengl


def test_an_arch_taichi_would_quietly_run_on_the_cpu_is_one_error_line(tmp_path):
    """Before: --arch cuda on a machine without CUDA ran on the CPU, with only Taichi's warning."""
    done = app("inflate", "--arch", "cuda", *CHEAP, "--no-video", "--out", str(tmp_path / "out"))
    if "Starting on arch=cuda" in done.stdout + done.stderr:
        pytest.skip("this machine runs --arch cuda")
    one_error_line(done, "arch = 'cuda' is not available here", "use cpu")


# --- 4. the Python API ------------------------------------------------------------------------------------


def test_the_api_refuses_what_the_commands_refuse(tmp_path):
    """Before: 10**400 increments ran without end, a 100000x100000 video tried to allocate 149 GiB, and
    load_scene(a folder) raised IsADirectoryError."""
    import taichi_pneuma as tp

    scene = tp.reference_scene(max_area=0.05, steps=3)
    with pytest.raises(tp.PneumaInputError, match="increments; the limit is 2000 .simulate's max_increments"):
        tp.simulate(scene.with_value("schedule.increments", 10**400))
    with pytest.raises(tp.PneumaInputError, match=r"size 100000x100000 is 10000000000 pixels per frame"):
        tp.simulate(scene).video(tmp_path / "big.mp4", size="100000x100000")
    assert not list(tmp_path.iterdir())
    with pytest.raises(tp.PneumaInputError, match="is not a regular file"):
        tp.load_scene(tmp_path)


SPARSE_READ = """
import sys
import numpy as np
from taichi_pneuma.fem.meshfile import read_mesh
dense, sparse = read_mesh(sys.argv[1]), read_mesh(sys.argv[2])
assert np.array_equal(sparse.points, dense.points)
assert all(np.array_equal(a.data, b.data) and a.type == b.type for a, b in zip(sparse.cells, dense.cells))
assert sparse.field_data.keys() == dense.field_data.keys()
"""


def test_a_gmsh_file_numbering_its_nodes_from_4e9_reads_as_the_dense_one_at_low_memory(tmp_path):
    """Every node number of a gmsh 2.2 file (the reference beam in 3D, written by write_mesh) moved up by 4e9.
    Before: meshio maps node numbers through an array as long as the largest (one node numbered 4e8 took
    1.66 GB; past 2**31 it overflows)."""
    from taichi_pneuma.fem.meshfile import write_mesh

    dense = write_mesh(tmp_path / "dense.msh", extruded_beam(0.05)[0], ("main",))
    sparse = tmp_path / "sparse.msh"
    sparse.write_text(moved_up(dense.read_text(), 4_000_000_000))
    done, peak = measured([sys.executable, "-c", SPARSE_READ, str(dense), str(sparse)], tmp_path)
    assert done.returncode == 0, done.stderr
    assert peak < 600e6
