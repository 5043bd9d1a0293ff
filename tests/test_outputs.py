"""Inverse control of a history column along the scene's schedule (control/outputs.py, pneuma-reach --output): the
commands it finds, ramped to by a fresh run from rest, give the wanted value."""

import json
import subprocess
import sys
import tomllib

import pytest
from test_blocked_force import actuator

import taichi_pneuma as tp
from taichi_pneuma.control.outputs import reach_output
from taichi_pneuma.errors import PneumaInputError
from taichi_pneuma.scene.scenefile import read_scene


def ramped_to(scene, commands, increments: int = 4):
    """A fresh ramp from rest to the commands (every chamber's keyframes ending there)."""
    return tp.simulate(
        scene.with_values(
            {
                **{f"chambers[{i}].keyframes": [[increments, float(c)]] for i, c in enumerate(commands)},
                "schedule.increments": increments,
            }
        )
    )


def test_the_commands_found_for_a_bending_angle_bend_a_fresh_ramp_to_it():
    scene = tp.reference_scene(max_area=0.01, chamber_points=32, steps=6)
    result = reach_output(scene.build(), "tip_rotation", -4.0)
    assert result.found and result.value == pytest.approx(-4.0, abs=1e-6)
    assert 1.0 < result.commands[0] < 3.5 and len(result.run.steps) < 6  # stopped at the crossing
    assert ramped_to(scene, result.commands).tip_rotation == pytest.approx(-4.0, rel=1e-5)


def test_the_pressure_found_for_a_blocked_force_presses_a_fresh_ramp_that_hard():
    scene = read_scene(tomllib.loads(actuator(100.0, 0.002, plate=True)), "strip")
    scene = scene.with_value("schedule.increments", 1).with_values(
        {f"chambers[{i}].keyframes": [[0, 0.0], [1, 0.002]] for i in range(len(scene.controls))}
    )
    wanted = 2e-4
    result = reach_output(scene.build(), "blocked_force", wanted)
    assert result.found and result.value == pytest.approx(wanted, rel=1e-6)
    assert ramped_to(scene, result.commands, 1).steps[-1].blocked_force == pytest.approx(wanted, rel=1e-4)


def test_a_value_the_schedule_never_reaches_is_reported_with_the_closest_step():
    scene = tp.reference_scene(max_area=0.02, chamber_points=32, steps=3)
    result = reach_output(scene.build(), "tip_rotation", 45.0)
    rotations = list(result.run.history["tip_rotation"])
    assert not result.found and len(rotations) == 3  # the whole ramp, never at 45 degrees
    assert result.value == max(rotations) and result.step == rotations.index(max(rotations))
    with pytest.raises(PneumaInputError, match="output 'tip_twist' is not a measure of this scene's state"):
        reach_output(scene.build(), "tip_twist", 1.0)


def test_reach_output_on_the_command_line(tmp_path):
    command = [sys.executable, "-m", "taichi_pneuma.apps.reach", "--max-area", "0.02", "--steps", "4"]
    done = subprocess.run(
        [*command, "--output", "tip_rotation", "--value", "-2", "--out", str(tmp_path), "--no-video"],
        capture_output=True,
        text=True,
    )
    assert done.returncode == 0, done.stderr
    assert "reached: tip_rotation = -2 at step" in done.stdout
    assert (tmp_path / "reference_cy+0.15_output_tip_rotation-2_steps4_max_area0.02_summary.json").exists()
    missing = subprocess.run([*command, "--output", "tip_rotation", "--out", str(tmp_path)], capture_output=True)
    assert missing.returncode == 2 and b"--output COLUMN and --value V go together" in missing.stderr


def test_a_ramp_that_stops_short_reports_how_far_the_column_came_and_writes_its_summary(tmp_path):
    """pneuma-reach --output prints a line per step (the column's value on it); where the ramp finds no equilibrium
    (2 Newton iterations, no cuts) before the column reaches the value, it exits 1 with one line naming the closest
    value, its step and commands and why the ramp stopped, and writes the summary saying so."""
    command = [sys.executable, "-m", "taichi_pneuma.apps.reach", "--max-area", "0.02", "--steps", "4"]
    flags = ["--output", "tip_rotation", "--value", "-20", "--max-iterations", "2", "--max-cuts", "0"]
    done = subprocess.run([*command, *flags, "--out", str(tmp_path), "--no-video"], capture_output=True, text=True)
    assert done.returncode == 1 and "Traceback" not in done.stderr
    steps = [line for line in done.stdout.splitlines() if line.lstrip().startswith("step")]
    assert steps and all("tip_rotation = " in line for line in steps)
    (line,) = [line for line in done.stderr.splitlines() if line.strip()]
    assert line.startswith("unreachable: the ramp stopped before tip_rotation reached -20; the closest it came is ")
    assert "no equilibrium" in line and ": main " in line  # why, and the commands at the closest step
    summary = json.loads(next(tmp_path.glob("*_summary.json")).read_text())
    assert summary["found"] is False and summary["all_converged"] is False and "no equilibrium" in summary["failure"]
    assert summary["step"] == len(steps) - 1 and summary["value"] == pytest.approx(
        float(steps[-1].rsplit("tip_rotation = ", 1)[1]), rel=1e-5
    )
