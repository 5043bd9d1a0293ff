"""The apps and the API on a 3D body: the tip Jacobian with its z row against finite differences of re-solves,
inverse control reaching an (x, y, z) target (API and `reach --tip X Y Z`), a sweep of a mesh-file scene, and
simulate / fields / save of a mesh-file scene. All on a small structured box (tests/solid_meshes.py) with two
cavities side by side in z, so that inflating one more than the other bends the tip sideways (z) as well as
down (y)."""

import csv
import json

import numpy as np
import pytest
from solid_meshes import box_with_cavities, scene_of
from test_sensitivity import TIGHT, relative_error

import taichi_pneuma as tp
from taichi_pneuma.apps.reach import main as reach_main
from taichi_pneuma.control.inverse import Reacher, ReachOptions
from taichi_pneuma.errors import PneumaInputError
from taichi_pneuma.fem.meshfile import write_mesh
from taichi_pneuma.fem.tip import tip_outputs
from taichi_pneuma.scene.build import Material
from taichi_pneuma.scene.schedule import ChamberSchedule
from taichi_pneuma.scene.targets import Target, read_targets_csv
from taichi_pneuma.solve.newton import NewtonSolver
from taichi_pneuma.solve.sensitivity import sensitivity
from taichi_pneuma.solve.simulate import settle
from taichi_pneuma.study import RunOptions, Sweep, check_axes, parse_vary, run_task

CAVITIES = {"back": ((-0.75, 0.0, -0.24), (0.75, 0.2, -0.08)), "front": ((-0.75, 0.0, 0.08), (0.75, 0.2, 0.24))}
PRESSURE = 2000.0  # up to E / 5: tip deflections of a few percent of the box's height


@pytest.fixture(scope="module")
def twin():
    """The box with two cavities (804 linear tetrahedra), each under pressure control 0 .. PRESSURE."""
    return box_with_cavities(CAVITIES, 5)


def twin_scene(mesh):
    schedules = [ChamberSchedule("pressure", ((0, 0.0), (2, PRESSURE))) for _ in CAVITIES]
    return scene_of(mesh, schedules, 2, Material(1e4, 0.45))


def test_3d_tip_jacobian_matches_finite_differences_of_resolves(twin):
    built = twin_scene(twin).build()
    solver = NewtonSolver(built.model, TIGHT)
    commands = np.array([0.8 * PRESSURE, 0.3 * PRESSURE])
    u = settle(built, solver, np.zeros(2), np.zeros_like(twin.vertices), commands)[0]
    s = sensitivity(built, commands, u)
    h = 0.1
    fd = np.column_stack(
        [
            (
                tip_outputs(twin, settle(built, solver, commands, u, commands + h * e)[0])
                - tip_outputs(twin, settle(built, solver, commands, u, commands - h * e)[0])
            )
            / (2 * h)
            for e in np.eye(2)
        ]
    )
    assert s.tip.shape == (4, 2)
    assert np.all(np.abs(fd).max(axis=1) > 1e-3 * np.abs(fd).max())  # every output moves, dz included
    assert np.sign(fd[3, 0]) == -np.sign(fd[3, 1])  # the back cavity pushes the tip to +z, the front one to -z
    assert relative_error(s.tip, fd).max() <= 1e-5


def test_reach_finds_an_xyz_target_on_a_3d_body(twin):
    """The target is the tip of a forward solve at commands the reach does not know; it starts from the box
    centre of the commands, and must put the tip within 1e-5 of the body length of it, by the commands."""
    reacher = Reacher(twin_scene(twin).build(), options=ReachOptions(tol=1e-5))
    wanted = np.array([0.9 * PRESSURE, 0.2 * PRESSURE])
    goal = reacher.settle(wanted).tip.copy()
    assert goal.shape == (3,) and abs(goal[2]) > 1e-3  # a target off the x-y plane
    reacher.settle(np.full(2, PRESSURE / 2))
    result = reacher.reach(Target(tuple(goal)))
    assert result.reached and result.error <= 1e-5 * reacher.length
    assert result.pose.commands == pytest.approx(wanted, rel=1e-3)
    assert result.summary_line().startswith("reached: tip (") and result.summary_line().count(",") >= 3
    with pytest.raises(PneumaInputError, match="a 2D scene's tip is"):
        Reacher(tp.reference_scene(max_area=0.05, chamber_points=16).build()).reach(Target((1.0, 0.0, 0.0)))


def mesh_file_scene(tmp_path, mesh) -> str:
    """A scene file naming the mesh written as gmsh 2.2 beside it: both cavities pressure-controlled."""
    write_mesh(tmp_path / "twin.msh", mesh, tuple(CAVITIES))
    chambers = "".join(
        f'''
[[chambers]]
name = "{name}"
shape = "mesh_surface"
group = "{name}"
control = "pressure"
keyframes = [[0, 0.0], [2, {PRESSURE}]]
'''
        for name in CAVITIES
    )
    path = tmp_path / "twin.toml"
    path.write_text(
        f'name = "twin"\n[body]\nshape = "mesh"\nfile = "twin.msh"\n[material]\nE = 1e4\nnu = 0.45\n'
        f'[clamp]\nside = "left"\n[schedule]\nincrements = 2\n{chambers}'
    )
    return str(path)


def test_reach_app_takes_tip_x_y_z_on_a_3d_scene(tmp_path, twin, capsys):
    scene = mesh_file_scene(tmp_path, twin)
    built = tp.load_scene(scene).build()
    reacher = Reacher(built)
    goal = reacher.settle(np.array([0.3 * PRESSURE, PRESSURE])).tip
    code = reach_main(
        ["--scene", scene, "--tip", *map(str, goal), "--no-video", "--out", str(tmp_path / "out"), "--quiet"]
    )
    out = capsys.readouterr().out
    assert code == 0 and "reached: tip (" in out
    summary = json.loads((tmp_path / "out" / "reach_twin_summary.json").read_text())
    assert summary["tetrahedra"] == twin.n_elements and len(summary["tip"]) == 3
    assert summary["tip_error"] <= 1e-3 * summary["body_length"]
    with open(tmp_path / "out" / "reach_twin_history.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert float(rows[-1]["tip_z"]) == pytest.approx(summary["tip"][2], abs=1e-12)
    assert float(rows[-1]["target_z"]) == pytest.approx(goal[2], abs=1e-12)
    assert float(rows[-1]["tip_dz"]) == pytest.approx(
        summary["tip"][2] - twin.vertices[built.mesh.tip, 2].mean(), abs=1e-12
    )
    assert reach_main(["--scene", scene, "--tip", "1", "2", "3", "4", "--no-video", "--out", str(tmp_path)]) == 2
    assert "--tip takes X Y or X Y Z, not 4 numbers" in capsys.readouterr().err
    assert reach_main(["--scene", scene, "--tip", "1", "2", "3", "--interactive", "--out", str(tmp_path)]) == 2
    assert "--interactive reach works on 2D scenes" in capsys.readouterr().err


def test_targets_with_z_from_a_csv_file_and_a_scene_file(tmp_path):
    path = tmp_path / "targets.csv"
    path.write_text("x,y,z,wz\n1.7,-0.1,0.05,2\n1.7,-0.2,,\n")
    assert read_targets_csv(path) == [Target((1.7, -0.1, 0.05), weight_z=2.0), Target((1.7, -0.2))]
    scene = tp.reference_scene().with_value("targets", [{"tip": [1.7, -0.1, 0.05], "weight_z": 0.5}])
    assert scene.targets == (Target((1.7, -0.1, 0.05), weight_z=0.5),)
    (tmp_path / "s.toml").write_text(scene.to_toml())
    assert tp.load_scene(tmp_path / "s.toml").targets == scene.targets
    with pytest.raises(PneumaInputError, match=r"target tip = \[1.0, 2.0, 3.0, 4.0\] must be \[x, y\] or \[x, y, z\]"):
        Target((1.0, 2.0, 3.0, 4.0))
    with pytest.raises(PneumaInputError, match="target weight_z = -1.0 must be >= 0"):
        Target((1.0, 2.0, 3.0), weight_z=-1.0)


class InProcess:
    """A study executor that runs each task here, one after the other (the process pool's interface)."""

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return False

    def describe(self):
        return {"executor": "in process"}

    def run(self, tasks):
        return ((i, run_task(task)) for i, task in enumerate(tasks))


def test_sweep_runs_a_3d_mesh_file_scene(tmp_path, twin):
    """Two runs over the front cavity's peak pressure: each row has the 3D tip dz; the back cavity alone bends the
    tip to +z, and adding the front one takes it back towards -z."""
    base = tp.load_scene(mesh_file_scene(tmp_path, twin))
    axes = check_axes(base, [parse_vary(f"chambers[1].keyframes[1][1]=0,{PRESSURE}")])
    sweep = Sweep(base, axes, tmp_path / "study", options=RunOptions(tol=1e-8))
    report = sweep.run(InProcess())
    rows = sorted(report.rows, key=lambda r: r["chambers[1].keyframes[1][1]"])
    assert [r["error"] for r in rows] == [None, None] and "tip_dz" in sweep.columns
    assert rows[0]["tip_dz"] > 0 and rows[1]["tip_dz"] < rows[0]["tip_dz"] - 0.005  # measured 0.0087 and -0.0035
    with open(sweep.csv, newline="") as f:
        assert [
            float(r["tip_dz"]) for r in sorted(csv.DictReader(f), key=lambda r: float(r[axes[0].key]))
        ] == pytest.approx([r["tip_dz"] for r in rows], rel=1e-12)


def test_simulate_fields_and_save_of_a_3d_mesh_file_scene(tmp_path, twin):
    result = tp.simulate(tp.load_scene(mesh_file_scene(tmp_path, twin)))
    assert result.converged and result.mesh.dim == 3
    fields = result.fields()
    assert fields["stress"].shape == (twin.n_elements, 3, 3) and np.all(fields["det_F"] > 0)
    written = {p.name for p in result.save(tmp_path / "out")}
    assert {"twin_history.csv", "twin_states.npz", "twin.pvd", "twin_summary.json"} <= written
    states = np.load(tmp_path / "out" / "twin_states.npz")
    assert states["positions"].shape == (3, twin.n_vertices, 3) and "tetrahedra" in states
    summary = json.loads((tmp_path / "out" / "twin_summary.json").read_text())
    assert summary["tetrahedra"] == twin.n_elements and summary["tip_dz"] == pytest.approx(result.steps[-1].tip[2])
