"""Checks during a run that stop or flag it, and a summary that keeps the run's extremes (issue 28): chamber walls
through themselves, chambers of no positive rest measure, a material law that gives energy by deforming, a run
past the largest principal stretch the scene allows, and a schedule that goes out and back."""

import dataclasses
import json
import math
import subprocess
import sys

import numpy as np
import pytest
from solid_meshes import box_with_cavity, scene_of

from taichi_pneuma.apps.inflate import main
from taichi_pneuma.control.inverse import Reacher
from taichi_pneuma.errors import PneumaInputError
from taichi_pneuma.materials import IsochoricMaterial
from taichi_pneuma.scene.build import reference_scene
from taichi_pneuma.scene.schedule import ChamberSchedule
from taichi_pneuma.solve.simulate import NoEquilibrium, RampFailed, run_schedule, state_fault
from taichi_pneuma.terms.chambers import AreaControl

RING = """name = "ring"
[body]
shape = "polygon"
points = {points}
[mesh]
max_area = 0.02
[material]
E = 1e4
nu = 0.45
[clamp]
box = [-0.3, -2.1, 0.3, -1.9]
[[chambers]]
name = "main"
shape = "ellipse"
center = [0.0, 0.0]
semi_axes = [1.0, 1.0]
points = 48
control = "pressure"
keyframes = [[6, 2500.0]]
[schedule]
increments = 6
"""


def crosses(points: np.ndarray) -> bool:
    """Whether any two non-adjacent edges of the closed polygon through points cross (a plain double loop)."""
    n = len(points)
    edges = [(points[i], points[(i + 1) % n]) for i in range(n)]

    def side(p, q, r):
        return (q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0])

    for i in range(n):
        for j in range(i + 2, n - (i == 0)):
            (a, b), (c, d) = edges[i], edges[j]
            if side(a, b, c) * side(a, b, d) < 0 and side(c, d, a) * side(c, d, b) < 0:
                return True
    return False


def stderr_lines(capsys) -> list[str]:
    return [line for line in capsys.readouterr().err.splitlines() if line.strip()]


@pytest.mark.parametrize("growth", ["0.05", "1e-320"])
def test_a_chamber_closed_past_what_the_body_allows_stops_where_its_wall_crosses_itself(tmp_path, growth):
    """Closing the chamber to 0.05 of its area (or to nothing) folds its wall through itself: the run stops there
    with one line naming the step and the chamber, exit 1, and the steps before it (simple walls) are kept.
    (Run in a process of its own: in this one, Taichi's CPU flags read the subnormal 1e-320 as 0.)"""
    out = tmp_path / "out"
    run = subprocess.run(
        [
            sys.executable,
            "-m",
            "taichi_pneuma.apps.inflate",
            "--growth",
            growth,
            "--steps",
            "6",
            "--max-area",
            "0.005",
            "--no-video",
            "--quiet",
            "--out",
            str(out),
        ],
        capture_output=True,
        text=True,
    )
    assert run.returncode == 1
    errors = [line for line in run.stderr.splitlines() if line.strip() and not line.startswith("[Taichi]")]
    assert len(errors) == 1 and errors[0].startswith("error: step ")
    assert "chamber 'main' wall crosses itself" in errors[0]
    failed = int(errors[0].split()[2].rstrip(":"))
    states = np.load(next(out.glob("inflate_cy+0.15_growth*_steps6_max_area0.005_states.npz")))
    assert 2 <= failed <= 5 and states["positions"].shape[0] == failed  # steps 0 .. failed - 1
    loop = states["chamber_loop_0"]
    assert not any(crosses(positions[loop]) for positions in states["positions"])


def test_inverse_control_refuses_a_pose_whose_wall_crosses_itself_and_keeps_the_last_one(taichi_cpu):
    """Reach settles each trial pose with simulate.settle, which checks the state as the ramp does: a chamber
    closed to 0.05 of its area is no equilibrium, and the pose (and the model) stay at the last good one."""
    built = reference_scene(steps=2, max_area=0.005).build()
    rest = built.scene.schedule.rest_commands  # the chamber's rest area
    reacher = Reacher(built, bounds=(0.01 * rest, 4.0 * rest), start=rest)
    before = reacher.pose
    with pytest.raises(NoEquilibrium, match="chamber 'main' wall crosses itself"):
        reacher.settle(0.05 * rest)
    assert reacher.pose is before and np.array_equal(built.model.config.u, before.u)
    loop = built.chambers[0].loop_vertices
    assert not crosses(built.mesh.vertices[loop] + before.u[loop])


def test_a_chamber_wall_mirrored_through_its_centre_is_inside_out(taichi_cpu):
    built = reference_scene(steps=2, max_area=0.01).build()
    chamber = built.chambers[0]
    assert chamber.wall_fault() is None
    rest = built.mesh.vertices
    loop = chamber.loop_vertices
    u = np.zeros_like(rest)
    u[loop, 0] = 2 * (rest[loop, 0].mean() - rest[loop, 0])  # x -> 2 c - x: the same simple polygon, clockwise
    built.model.set_displacements(u)
    assert chamber.area() < 0 and "wall turned inside out" in chamber.wall_fault()


def test_a_3d_chamber_wall_with_a_node_dragged_across_its_neighbours_is_no_equilibrium(taichi_cpu):
    """A wall node moved within the cavity's top face (y = 0.2) past the nodes around it turns the triangles it
    drags across over; the tetrahedra under them turn inside out with them (a triangle's normal against its rest
    normal carried by its element's rotation is det F < 0: Nanson), so the state is none."""
    built = scene_of(box_with_cavity(), [ChamberSchedule("volume", ((1, 1.5),))], 1).build()
    commands = built.scene.schedule.rest_commands
    chamber = built.chambers[0]
    assert state_fault(built, commands) is None
    rest = built.mesh.vertices
    top = chamber.loop_vertices[
        np.isclose(rest[chamber.loop_vertices, 1], 0.2)
        & np.all(np.abs(rest[chamber.loop_vertices][:, [0, 2]]) < [0.5, 0.1], axis=1)
    ]
    u = np.zeros_like(rest)
    u[top[0], 0] = 1.2  # past the neighbours 0.5 away along x
    built.model.set_displacements(u)
    fault = state_fault(built, commands)
    assert fault is not None and "an element turned inside out" in fault


@pytest.mark.parametrize("degrees", [60, 120, 200, 300])
def test_a_3d_chamber_turned_with_its_body_past_a_quarter_turn_is_no_fold(taichi_cpu, degrees):
    """The box with its cavity turned rigidly about z (as a bending actuator's chamber near its tip turns past 90
    degrees): every wall triangle's normal turns with it, against its rest normal past 90 degrees, yet nothing is
    folded, inverted or crossing: the state is a physical one."""
    built = scene_of(box_with_cavity(), [ChamberSchedule("volume", ((1, 1.5),))], 1).build()
    rest = built.mesh.vertices
    t = math.radians(degrees)
    turn = np.array([[math.cos(t), -math.sin(t), 0], [math.sin(t), math.cos(t), 0], [0, 0, 1]])
    built.model.set_displacements(rest @ turn.T - rest)
    assert built.elastic.min_determinant() == pytest.approx(1.0)
    assert state_fault(built, built.scene.schedule.rest_commands) is None


def test_a_chamber_of_the_outer_surface_is_refused_for_its_negative_rest_volume(taichi_cpu):
    """The body's outer surface given as a chamber wall (facets facing into the rubber, as a mesh file's group is
    read) encloses the whole 3.5 x 0.8 x 0.8 box with the sign reversed: -2.24."""
    mesh = box_with_cavity()
    walls = {tuple(sorted(f)) for f in mesh.chambers[0]}
    outer = np.array([f for f in mesh.surface if tuple(sorted(f)) not in walls])
    flipped = dataclasses.replace(mesh, chambers=(outer[:, [0, 2, 1]],))
    with pytest.raises(PneumaInputError, match=r"chamber 'main': rest volume -2\.24 is not positive"):
        scene_of(flipped, [ChamberSchedule("volume", ((1, 1.5),))], 1).build()


def test_a_2d_chamber_wall_given_clockwise_is_refused_for_its_negative_rest_area(taichi_cpu):
    built = reference_scene(steps=2, max_area=0.01).build()
    loop = built.mesh.chambers[0]
    with pytest.raises(PneumaInputError, match=r"chamber 'main': rest area -0\.587\d* is not positive"):
        AreaControl().term(built.model.config, loop[::-1], "main", 1)


def test_a_law_that_gives_energy_by_stretching_is_named_as_the_cause_not_newton(taichi_cpu):
    """Yeoh with C20 = -800 < 0 (C10 = 1724): W = C10 a + C20 a^2 falls below its rest value 0 once a = Ibar1 - 3 >
    2.2, so no equilibrium exists past it. The coefficient is set on the built term, past any check at load."""
    scene = reference_scene(growth=3.5, steps=8, max_area=0.005)
    built = type(scene)(
        scene.geometry,
        scene.controls,
        scene.increments,
        IsochoricMaterial("neo_hookean", C10=1724.0, poisson_ratio=0.45),
        name=scene.name,
    ).build()
    built.elastic.parameters[:, 2] = -800.0
    with pytest.raises(RampFailed) as failure:
        run_schedule(built)
    message = str(failure.value)
    assert "the material law 'isochoric_polynomial' is unstable at element" in message
    assert "principal stretches" in message and "not a descent direction" not in message
    assert failure.value.result.steps  # the steps before are kept


def test_a_stable_law_is_never_blamed(reference_ramp):
    built, result = reference_ramp(0.15)
    assert result.converged and built.elastic.fault() is None


def ring_scene(tmp_path) -> str:
    points = [
        [round(2 * math.cos(2 * math.pi * i / 48), 6), round(2 * math.sin(2 * math.pi * i / 48), 6)] for i in range(48)
    ]
    path = tmp_path / "ring.toml"
    path.write_text(RING.format(points=points))
    return str(path)


def largest_stretch(states) -> float:
    """The largest singular value of F over every linear triangle and step, from the states file alone."""
    rest, triangles = states["rest"], states["triangles"]
    dX = np.stack([rest[triangles[:, 1]] - rest[triangles[:, 0]], rest[triangles[:, 2]] - rest[triangles[:, 0]]], -1)
    largest = 0.0
    for x in states["positions"]:
        dx = np.stack([x[triangles[:, 1]] - x[triangles[:, 0]], x[triangles[:, 2]] - x[triangles[:, 0]]], -1)
        largest = max(largest, np.linalg.svd(dx @ np.linalg.inv(dX), compute_uv=False).max())
    return largest


def test_a_ring_pressurised_past_its_limit_warns_once_and_reports_its_largest_stretch(tmp_path, capsys):
    """A ring of radii 1 and 2 (mu = 3448) holds at most about mu ln 2 = 2390 in the continuum; at 2500 the
    discrete ring still finds an 'equilibrium', its chamber 30 times its rest area. The run warns once, at the
    first step past max_stretch = 5 (the default), and the summary gives the largest stretch."""
    out = tmp_path / "out"
    assert main(["--scene", ring_scene(tmp_path), "--no-video", "--out", str(out)]) == 0
    captured = capsys.readouterr()
    warnings = [line for line in captured.err.splitlines() if line.startswith("warning:")]
    assert len(warnings) == 1 and "max_stretch = 5" in warnings[0] and warnings[0].startswith("warning: step 6:")
    summary = json.loads((out / "ring_summary.json").read_text())
    expected = largest_stretch(np.load(out / "ring_states.npz"))
    assert expected > 5 and summary["max_stretch"] == pytest.approx(expected, rel=1e-9)
    assert summary["max_stretch_step"] == 6 and summary["max_stretch_limit"] == 5
    assert f"largest principal stretch: {expected:.2f} (step 6" in captured.out


def test_the_largest_stretch_allowed_is_a_scene_key(tmp_path, capsys):
    out = tmp_path / "out"
    assert (
        main(
            [
                "--scene",
                ring_scene(tmp_path),
                "--set",
                "schedule.max_stretch=50",
                "--no-video",
                "--quiet",
                "--out",
                str(out),
            ]
        )
        == 0
    )
    assert not [line for line in capsys.readouterr().err.splitlines() if line.startswith("warning:")]
    assert json.loads((out / "ring_schedule.max_stretch50_summary.json").read_text())["max_stretch_limit"] == 50
    assert main(["--scene", ring_scene(tmp_path), "--set", "schedule.max_stretch=0.5", "--out", str(out)]) == 2
    assert "max_stretch = 0.5 must be > 1" in capsys.readouterr().err


def test_an_out_and_back_schedule_reports_the_curl_it_reached(tmp_path, capsys):
    """pneunet_finger inflates its chambers to 900 Pa by step 10, holds, and deflates to rest by step 18: the last
    step is back at rest, the 86 degree curl of step 10 is in the summary's extremes."""
    out = tmp_path / "out"
    assert main(["--scene", "pneunet_finger", "--no-video", "--quiet", "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    summary = json.loads((out / "pneunet_finger_summary.json").read_text())
    history = np.genfromtxt(out / "pneunet_finger_history.csv", delimiter=",", names=True)
    assert abs(summary["tip_rotation_deg"]) < 0.5 and abs(summary["tip_deflection"]) < 1e-3  # back at rest
    rotation, dy = summary["extremes"]["tip_rotation"], summary["extremes"]["tip_dy"]
    assert rotation["min"] < -80 and rotation["min"] == history["tip_rotation"].min()
    assert 10 <= rotation["min_step"] <= 12 and history["tip_rotation"][rotation["min_step"]] == rotation["min"]
    assert dy["min"] == history["tip_dy"].min() < -2
    assert summary["extremes"]["c3.pressure"] == {"min": 0.0, "min_step": 0, "max": 900.0, "max_step": 10}
    assert f"rotation {rotation['min']:+.1f} (step {rotation['min_step']})" in printed
    assert "c3: area 0.194 -> 0.194 (x1.00), pressure 0; over the run" in printed
