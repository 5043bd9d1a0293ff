"""Untrusted scene files and runaway inputs: no result file outside --out, a run too big is refused
before any work (naming the estimate, the limit and the flag), and Ctrl-C during a ramp keeps the
steps done and exits 130."""

import json
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from taichi_pneuma import limits
from taichi_pneuma.apps.inflate import main
from taichi_pneuma.errors import PneumaInputError
from taichi_pneuma.fem import sizing, triangulation
from taichi_pneuma.fem.shapes import MAX_WALL_POINTS
from taichi_pneuma.io.output import check_stem, save_text
from taichi_pneuma.scene.scenefile import MAX_SCENE_BYTES, load_scene

SCENES = Path(__file__).resolve().parent.parent / "taichi_pneuma" / "scenes"
# the reference scene file made cheap: a coarse mesh, 2 increments
CHEAP = (
    (SCENES / "reference_beam.toml")
    .read_text()
    .replace("max_area = 0.0012", "max_area = 0.02")
    .replace("[35, 3.5]", "[2, 1.3]")
    .replace("increments = 35", "increments = 2")
)
CHAMBER = CHEAP[CHEAP.index("[[chambers]]") : CHEAP.index("[schedule]")]
QUICK = ["--no-video", "--quiet"]


def reference_with(tmp_path, *replacements, file_name="scene.toml") -> Path:
    """The cheap reference scene file with (old, new) text replacements, written under tmp_path/scenes."""
    text = CHEAP
    for old, new in replacements:
        assert old in text
        text = text.replace(old, new)
    path = tmp_path / "scenes" / file_name
    path.parent.mkdir(exist_ok=True)
    path.write_text(text)
    return path


def files_under(directory: Path) -> set[str]:
    return {str(p.relative_to(directory)) for p in directory.rglob("*") if p.is_file()}


def error_line(capsys) -> str:
    lines = [line for line in capsys.readouterr().err.splitlines() if line.strip()]
    assert len(lines) == 1 and lines[0].startswith("error: "), lines
    return lines[0]


@pytest.mark.parametrize(
    "name", ["../escaped", "../../etc/evil", "/tmp/evil", "sub/dir", ".hidden", "..", "", "x" * 101, "tab\tname"]
)
def test_a_scene_name_that_is_no_plain_file_name_is_refused_and_nothing_is_written(tmp_path, capsys, name):
    path = reference_with(tmp_path, ('name = "reference_beam"', f"name = {json.dumps(name)}"))
    assert main(["--scene", str(path), "--out", str(tmp_path / "out"), *QUICK]) == 2
    line = error_line(capsys)
    assert f"name = {name!r} cannot name the result files" in line and "letters, digits and _ + - ." in line
    assert files_under(tmp_path) == {"scenes/scene.toml"}


@pytest.mark.parametrize("name", ["reference_beam", "inflate_cy+0.15", "v1.2-final", "A"])
def test_plain_file_names_are_accepted(name):
    assert check_stem(name) == name


def test_without_a_name_the_file_name_is_reduced_to_a_plain_one_and_everything_lands_in_out(tmp_path, capsys):
    path = reference_with(tmp_path, ('name = "reference_beam"\n', ""), file_name="..my beam (v2).toml")
    out = tmp_path / "out"
    assert main(["--scene", str(path), "--out", str(out), *QUICK]) == 0
    steps = json.loads((out / "my_beam__v2__summary.json").read_text())["steps"]
    assert files_under(tmp_path) == {"scenes/..my beam (v2).toml", "out/my_beam__v2_.pvd"} | {
        f"out/my_beam__v2__{suffix}" for suffix in ("history.csv", "states.npz", "summary.json", "scene.toml")
    } | {f"out/my_beam__v2__vtk/my_beam__v2__{i:04d}.vtu" for i in range(steps)}


def test_a_file_that_cannot_be_written_is_one_error_naming_it(tmp_path):
    (tmp_path / "taken").mkdir()  # a directory where the file should go: the rename fails
    with pytest.raises(PneumaInputError, match=r"cannot write '.*taken'"):
        save_text(tmp_path / "taken", "text")
    assert files_under(tmp_path) == set()


@pytest.mark.parametrize(
    "content, message",
    [
        (b'name = "x"\n' + b"#" * MAX_SCENE_BYTES, f"larger than {MAX_SCENE_BYTES} bytes"),
        (b'name = "caf\xe9"\n', "not UTF-8"),
        (b"a = " + b"[" * 5000 + b"]" * 5000, "nested too deeply"),
    ],
)
def test_oversized_binary_or_deeply_nested_files_are_refused(tmp_path, content, message):
    path = tmp_path / "bad.toml"
    path.write_bytes(content)
    with pytest.raises(PneumaInputError, match=message):
        load_scene(path)


def test_a_tiny_max_area_is_refused_at_once_naming_estimate_limit_and_flag(tmp_path, capsys):
    path = reference_with(tmp_path, ("max_area = 0.02", "max_area = 1e-9"))
    start = time.perf_counter()
    assert main(["--scene", str(path), "--out", str(tmp_path / "out"), *QUICK]) == 2
    assert time.perf_counter() - start < 5.0
    line = error_line(capsys)
    assert "about 3.54e+09 triangles" in line and "max_area 1e-09" in line and "132 outline points" in line
    assert "GB" in line and f"the limit is {limits.MAX_TRIANGLES} triangles (--max-triangles raises it)" in line
    assert not (tmp_path / "out").exists()


def test_max_triangles_flag_moves_the_limit(tmp_path, capsys):
    path = reference_with(tmp_path)  # about 573 triangles estimated, 431 made
    assert main(["--scene", str(path), "--out", str(tmp_path / "a"), "--max-triangles", "500", *QUICK]) == 2
    assert "the limit is 500 triangles" in error_line(capsys)
    assert main(["--scene", str(path), "--out", str(tmp_path / "b"), "--max-triangles", "600", *QUICK]) == 0
    summary = json.loads((tmp_path / "b" / "reference_beam_summary.json").read_text())
    assert summary["triangles"] == 431 and summary["interrupted"] is False and summary["steps"] == 3


# The estimate counts gmsh's tetrahedra of the fibre-reinforced actuator's thin (2 mm) graded walls 14 % low (5788
# estimated, 6756 made), and those of gripper_3d's 2.5 mm walls around its chambers low too: a known gap of the
# estimate (it does not use the walls' thickness), which the check of gmsh's output against the budget covers; strict:
# it fails when the estimate catches up
THIN_WALLED = {"fiber_bending_3d", "fiber_bending_step", "blocked_force_3d", "gripper_3d"}
UNDERCOUNTED = pytest.mark.xfail(strict=True, reason="the estimate undercounts thin graded walls by 14 %")


@pytest.mark.parametrize(
    "scene",
    [pytest.param(p, marks=UNDERCOUNTED) if p.stem in THIN_WALLED else p for p in sorted(SCENES.glob("*.toml"))],
    ids=lambda p: p.stem,
)
def test_the_triangle_estimate_is_close_to_the_mesh_triangle_makes(scene):
    loaded = load_scene(scene)
    mesh = loaded.geometry.mesh()
    # the limit counts a quadratic triangle as 4 linear ones, a quadratic tetrahedron as 8 linear ones
    made = mesh.n_elements * ({2: 4, 3: 8}[mesh.dim] if mesh.order == 2 else 1)
    for limit, refused in ((int(0.9 * made), True), (int(1.6 * made), False)):
        try:
            sizing.check_scene(loaded, max_triangles=limit)
            assert not refused
        except PneumaInputError as exc:
            assert refused and "--max-triangles" in str(exc)


@pytest.mark.parametrize(
    "replacement, words",
    [
        (
            ("increments = 2", "increments = 1000000000"),
            "the schedule has 1000000000 increments; the limit is 2000 (--max-increments raises it)",
        ),
        (("points = 128", "points = 1000000000"), f"points = 1000000000 must be an integer in [8, {MAX_WALL_POINTS}]"),
        (
            (CHAMBER, "".join(CHAMBER.replace('"main"', f'"c{i}"') for i in range(65))),
            "65 chambers: at most 64 are allowed",
        ),
        (("[2, 1.3]", "[2, 1e300]"), "keyframes area ratio 1e+300 must lie in (0, 1000]"),
    ],
    ids=["increments", "wall points", "chambers", "area ratio"],
)
def test_absurd_sizes_are_refused_at_once(tmp_path, capsys, replacement, words):
    path = reference_with(tmp_path, replacement)
    start = time.perf_counter()
    assert main(["--scene", str(path), "--out", str(tmp_path / "out"), *QUICK]) == 2
    assert time.perf_counter() - start < 5.0
    assert words in error_line(capsys)


ELLIPSE = 'shape = "ellipse"\ncenter = [0.0, 0.15]\nsemi_axes = [0.85, 0.22]\npoints = 128'


@pytest.mark.parametrize(
    "replacements, words",
    [
        (
            [(ELLIPSE, 'shape = "rounded_rectangle"\ncenter = [0.0, 0.15]\nsize = [1.0, 0.3]\nradius = 1e-300')],
            "chamber 'main': two of its outline points coincide (closer than 1e-09 of its size 1)",
        ),
        (
            [("size = [3.5, 0.8]", "size = [1e17, 1e17]"), ("max_area = 0.02", "max_area = 1e33")],
            "Triangle could not mesh the geometry",
        ),
        ([("size = [3.5, 0.8]", "size = [[3.5], 0.8]")], "body: size = ([3.5], 0.8) must be a pair of numbers"),
        ([("center = [0.0, 0.15]", 'center = ["0.0", 0.15]')], "chambers[0]: center = '0.0' is not a number"),
        ([("E = 1e4", "E = 1" + "0" * 400)], "material: E = 1" + "0" * 400 + " must be a finite number"),
    ],
    ids=["coincident points", "out of precision", "ragged list", "numeric string", "huge integer"],
)
def test_what_the_fuzzer_found_is_one_error_line(tmp_path, capsys, replacements, words):
    """Before: a segfault of the whole process, Triangle's RuntimeError, ValueError, TypeError, OverflowError.
    meshpy's Triangle ends the process where it runs out of precision (docs/backends.md): that case needs `triangle`."""
    if "could not mesh" in words and triangulation.default_binding() == "meshpy":
        pytest.skip("meshpy's Triangle ends the process when it runs out of precision")
    path = reference_with(tmp_path, *replacements)
    assert main(["--scene", str(path), "--out", str(tmp_path / "out"), *QUICK]) == 2
    assert words in error_line(capsys)


def test_absurd_flags_are_refused_naming_the_flag(tmp_path, capsys):
    out = str(tmp_path / "out")
    assert main(["--steps", "100000", "--out", out, *QUICK]) == 2
    assert "99999 increments; the limit is 2000 (--max-increments raises it)" in error_line(capsys)
    assert main(["--size", "100000x100000", "--out", out, "--quiet"]) == 2
    assert (
        "--size 100000x100000 is 10000000000 pixels per frame; the limit is 8294400 (--max-frame-pixels raises it)"
    ) in error_line(capsys)
    assert main(["--max-area", "1e-7", "--max-triangles", "0", "--out", out, *QUICK]) == 2
    assert "--max-triangles = 0 must be >= 1" in error_line(capsys)
    assert not (tmp_path / "out").exists()


def test_ctrl_c_during_a_ramp_keeps_the_steps_done_and_exits_130(tmp_path):
    """A real process and a real SIGINT: sent once the third increment is reported."""
    out = tmp_path / "out"
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "taichi_pneuma.apps.inflate",
            "--steps",
            "400",
            "--max-area",
            "0.01",
            "--no-video",
            "--out",
            str(out),
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env={**os.environ, "PYTHONUNBUFFERED": "1"},
    )
    for line in proc.stdout:
        if "step   3/399" in line:
            proc.send_signal(signal.SIGINT)
            break
    stdout, stderr = proc.communicate(timeout=120)
    assert proc.returncode == 130, stderr
    errors = [line for line in stderr.splitlines() if line.startswith("error:")]
    assert len(errors) == 1 and "Traceback" not in stderr
    # "interrupted after step k" (between increments) or "during step k" (within a Newton iteration: k - 1 done)
    when, step = re.search(r"interrupted (after|during) step (\d+) of 399", errors[0]).groups()
    done = int(step) - (when == "during")
    assert 3 <= done < 399 and "saved the" in stdout
    summary = json.loads((out / "inflate_cy+0.15_steps400_max_area0.01_summary.json").read_text())
    history = np.genfromtxt(out / "inflate_cy+0.15_steps400_max_area0.01_history.csv", delimiter=",", names=True)
    states = np.load(out / "inflate_cy+0.15_steps400_max_area0.01_states.npz")
    assert summary["interrupted"] is True and summary["steps"] == done + 1
    assert len(history) == done + 1 and states["positions"].shape[0] == done + 1
    assert history["step"][-1] == done and summary["all_converged"]
    assert sorted(os.listdir(out)) == [
        "inflate_cy+0.15_steps400_max_area0.01.pvd",
        "inflate_cy+0.15_steps400_max_area0.01_history.csv",
        "inflate_cy+0.15_steps400_max_area0.01_states.npz",
        "inflate_cy+0.15_steps400_max_area0.01_summary.json",
        "inflate_cy+0.15_steps400_max_area0.01_vtk",
    ]
    assert len(os.listdir(out / "inflate_cy+0.15_steps400_max_area0.01_vtk")) == done + 1  # the VTU of every step done
    assert (out / "inflate_cy+0.15_steps400_max_area0.01.pvd").read_text().count("<DataSet ") == done + 1
