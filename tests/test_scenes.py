"""Scene files: the shipped scenes run from the command line and do what they say; pressure control
agrees with area control and stops clearly past its limit point; self-contact keeps a collapsing
chamber simple; malformed files give one clear error naming the key or value."""

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest

from taichi_pneuma.apps.inflate import main
from taichi_pneuma.errors import PneumaInputError
from taichi_pneuma.fem.polygons import polygon_self_intersects
from taichi_pneuma.scene.build import ChamberControl, reference_scene
from taichi_pneuma.scene.scenefile import load_scene
from taichi_pneuma.scene.schedule import ChamberSchedule
from taichi_pneuma.solve.simulate import RampFailed, run_schedule
from taichi_pneuma.terms.effects import SelfContact

SCENES = Path(__file__).resolve().parent.parent / "taichi_pneuma" / "scenes"
LENGTH = 3.5


def run_scene_cli(name, tmp_path):
    """Run a shipped scene through the command line; return its summary, history and states."""
    out = tmp_path / "out"
    assert main(["--scene", str(SCENES / f"{name}.toml"), "--out", str(out), "--quiet"]) == 0
    summary = json.loads((out / f"{name}_summary.json").read_text())
    history = np.genfromtxt(out / f"{name}_history.csv", delimiter=",", names=True, deletechars="")
    return summary, history, np.load(out / f"{name}_states.npz")


def test_reference_file_is_the_spec_scene():
    """So its run is the reference ramp, whose figures test_reference.py checks."""
    assert dataclasses.replace(load_scene(SCENES / "reference_beam.toml"), name="x") == dataclasses.replace(
        reference_scene(cy=0.15), name="x"
    )


def test_bidirectional_tip_goes_down_back_then_up(tmp_path):
    summary, history, states = run_scene_cli("bidirectional", tmp_path)
    tip = history["tip_dy"]
    assert tip[8] < -0.1  # top chamber inflated: curls down
    assert abs(tip[16]) < 1e-3  # back at rest
    assert tip[24] > 0.1  # bottom chamber inflated: curls up
    assert states["area"].shape == (25, 2) and states["pressure"][8, 0] > 0


def test_pneunet_finger_curls_past_45_degrees_and_uncurls(tmp_path):
    summary, history, _ = run_scene_cli("pneunet_finger", tmp_path)
    assert len(summary["chambers"]) >= 5
    rotation = history["tip_rotation"]
    assert history["c1.pressure"][10] == pytest.approx(900.0)
    assert rotation[10] < -45.0  # curls down, clockwise
    assert abs(rotation[-1]) < 0.1  # deflated: back to straight


def test_finger_on_ground_stays_above_it_and_lifts(tmp_path):
    summary, history, states = run_scene_cli("finger_on_ground", tmp_path)
    ground = float(states["ground_height"])
    assert states["positions"][..., 1].min() > ground
    assert history["tip_dy"][0] < 0  # sags under its own weight onto the ground
    assert history["tip_dy"][-1] > 0.5  # lifts its tip as the chambers inflate
    assert np.all(history["ground.fy"] > 0) and summary["contact"]["ground"][1] > 0
    assert states["contact_forces"].shape == states["positions"].shape


def coarse_reference(**kwargs):
    return reference_scene(cy=0.15, max_area=0.01, chamber_points=64, **kwargs)


@pytest.mark.slow
def test_self_contact_keeps_a_chamber_deflated_to_0p2_simple():
    scene = dataclasses.replace(coarse_reference(growth=0.2, steps=9), effects=(SelfContact(),))
    built = scene.build()
    result = run_schedule(built)
    assert result.steps[-1].chambers["main"].command == pytest.approx(0.2)
    loop = built.mesh.chambers[0]
    assert not any(polygon_self_intersects(state[loop]) for state in result.positions)
    assert built.effects["self_contact"][0].min_distance() > 0
    assert result.steps[-1].contact["self_contact"][2] > 0  # the walls do touch


def pressure_version(scene, pressure):
    return dataclasses.replace(
        scene, controls=(ChamberControl(ChamberSchedule("pressure", ((0, 0.0), (scene.increments, pressure)))),)
    )


def test_pressure_control_to_the_reached_pressure_gives_the_same_shape():
    area_scene = coarse_reference(growth=3.5, steps=11)
    area_result = run_schedule(area_scene.build())
    pressure = area_result.steps[-1].chambers["main"].pressure
    pressure_result = run_schedule(pressure_version(area_scene, pressure).build())
    assert np.abs(pressure_result.positions[-1] - area_result.positions[-1]).max() < 1e-3 * LENGTH


@pytest.mark.slow
def test_pressure_past_the_limit_point_stops_naming_the_pressure():
    built = pressure_version(coarse_reference(steps=5), 3000.0).build()
    with pytest.raises(
        RampFailed,
        match=r"step 1: no equilibrium at pressure [0-9.]+ \(last equilibrium at pressure "
        r"[0-9.]+\) after 4 cuts",
    ) as failure:
        run_schedule(built, max_cuts=4)
    assert len(failure.value.result.steps) == 1


BAD = {
    "unknown key": ('name = "main"', 'name = "main"\ncentre = [0.0, 0.0]', "unknown key 'chambers[0].centre'"),
    "chamber outside the body": (
        "center = [0.0, 0.15]",
        "center = [0.0, 0.35]",
        "chamber 'main' is not inside the body",
    ),
    "negative pressure": (
        'control = "area"\nstiffness = 1e5\nkeyframes = [[0, 1.0], [35, 3.5]]',
        'control = "pressure"\nkeyframes = [[0, 0.0], [35, -50.0]]',
        "chambers[0]: keyframes pressure -50.0 is negative",
    ),
    "not a number": ("E = 1e4", 'E = "soft"', "material.E = 'soft' must be a number"),
    "bad effect": ("[schedule]", "[effects.magnetism]\nstrength = 1\n[schedule]", "unknown key 'effects.magnetism'"),
}


@pytest.mark.parametrize("case", list(BAD))
def test_malformed_scene_files_name_the_key(tmp_path, case):
    old, new, message = BAD[case]
    text = (SCENES / "reference_beam.toml").read_text()
    assert old in text
    text = text.replace(old, new)
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(PneumaInputError) as error:
        load_scene(path)
    assert message in str(error.value) and str(error.value).startswith(str(path))


def test_overlapping_chambers_are_refused(tmp_path):
    text = (SCENES / "bidirectional.toml").read_text().replace("center = [0.0, -0.2]", "center = [0.1, 0.1]")
    path = tmp_path / "overlap.toml"
    path.write_text(text)
    with pytest.raises(PneumaInputError, match="chambers 'top' and 'bottom' overlap"):
        load_scene(path)


def test_cli_bad_scene_file_is_one_line_exit_2(tmp_path, capsys):
    path = tmp_path / "bad.toml"
    path.write_text((SCENES / "reference_beam.toml").read_text().replace("nu = 0.45", "nu = 0.5"))
    assert main(["--scene", str(path), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "material: nu = 0.5 must lie in (-1, 0.5)" in err[0]
