"""The bending angle is the whole turn from rest, never its remainder within one turn (fem/tip.py), in the history,
the summary, the extremes, the printed lines and the plot; pneuma-reach --output reports only values it reached, of
columns that measure the state, and keeps the column out of the file system's way.

The finger: a strip 11.5 long, 22 rectangular chambers in a row above a stiffer bottom layer, driven from rest in 12
increments, the 14 nearer the clamp to 2.65 times their area and the 8 nearer the tip to 5.8 times: it curls clockwise
through more than a whole turn, each step by less than 60 degrees, as a spiral whose tip part curls tighter and so
passes inside the first loop (a finger curled evenly meets itself at a whole turn: every equilibrium is checked for
the body's surface through itself, simulate.state_fault, and such a state is none). That it does is read off the node
positions independently of fem/tip.py: the direction of the body's bottom edge, followed segment by segment from the
clamp to the tip (np.unwrap), turns through the same angle.
"""

import json

import numpy as np
import pytest

import taichi_pneuma as tp
from taichi_pneuma.apps import inflate, reach
from taichi_pneuma.control import outputs
from taichi_pneuma.fem.tip import continued, tip_measures, tip_twist_of
from taichi_pneuma.solve.records import SOLVER_COLUMNS

CHAMBERS, LENGTH, HEIGHT = 22, 11.5, 0.8
QUIET = ["--no-video", "--quiet"]


def finger_toml(increments: int = 12, ratios: tuple[float, float] = (2.65, 5.8), tip_chambers: int = 8) -> str:
    """The finger of the module docstring: chamber i spans x in [-L/2 + 0.3 + 0.5 i, -L/2 + 0.7 + 0.5 i], y in
    [-0.18, 0.32], driven to ratios[0] times its area, the last tip_chambers to ratios[1]; the bottom 0.15 five times
    stiffer; clamped on the left."""
    left = -LENGTH / 2
    chambers = "".join(
        f'\n[[chambers]]\nname = "c{i}"\nshape = "polygon"\ncontrol = "area"\n'
        f"points = [[{a}, -0.18], [{a + 0.4}, -0.18], [{a + 0.4}, 0.32], [{a}, 0.32]]\n"
        f"keyframes = [[0, 1.0], [{increments}, {ratios[i >= CHAMBERS - tip_chambers]}]]\n"
        for i in range(CHAMBERS)
        for a in [round(left + 0.3 + 0.5 * i, 6)]
    )
    return (
        'name = "curling_finger"\n[body]\nshape = "rectangle"\ncenter = [0.0, 0.0]\n'
        f"size = [{LENGTH}, {HEIGHT}]\n[mesh]\nmax_area = 0.04\n"
        f"[material]\nE = 1e4\nnu = 0.45\nregions = [{{ box = [{left}, -0.4, {-left}, -0.25], E = 5e4 }}]\n"
        f'[clamp]\nside = "left"\n{chambers}\n[schedule]\nincrements = {increments}\n'
    )


@pytest.fixture(scope="module")
def finger_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("finger") / "curling_finger.toml"
    path.write_text(finger_toml())
    return path


@pytest.fixture(scope="module")
def curled(finger_file):
    return tp.simulate(tp.load_scene(finger_file), tol=1e-4)


def bottom_edge_turn(rest: np.ndarray, positions: np.ndarray) -> float:
    """The angle (degrees) through which the body's bottom edge (the nodes at y = -H/2, in order along x) turns
    from its rest direction +x at the clamp to its last segment at the tip: the segments' directions unwrapped."""
    bottom = np.flatnonzero(np.isclose(rest[:, 1], -HEIGHT / 2))
    segments = np.diff(positions[bottom[np.argsort(rest[bottom, 0])]], axis=0)
    return float(np.degrees(np.unwrap(np.arctan2(segments[:, 1], segments[:, 0])))[-1])


def test_the_finger_curls_past_a_whole_turn_and_the_history_says_so(curled):
    rotation = curled.history["tip_rotation"]
    mesh = curled.mesh
    rest = mesh.vertices[mesh.tip]
    for step, positions in enumerate(curled.positions):
        # the tip edge's least-squares rotation from its points alone, in (-180, 180]
        r, c = rest - rest.mean(axis=0), positions[mesh.tip] - positions[mesh.tip].mean(axis=0)
        raw = np.degrees(np.arctan2(np.sum(r[:, 0] * c[:, 1] - r[:, 1] * c[:, 0]), np.sum(r * c)))
        assert abs((rotation[step] - raw + 180.0) % 360.0 - 180.0) < 1e-6  # the same angle, up to whole turns
        body = bottom_edge_turn(mesh.vertices, positions)  # the body's own turn, no history involved
        assert abs(rotation[step] - body) <= 0.05 * abs(body) + 1.0, (step, rotation[step], body)
    assert np.all(np.diff(rotation) < 0) and np.all(np.diff(rotation) > -60)  # a steady clockwise curl
    # past a whole turn, the count of turns read off the body: its bottom edge within 5 % of it at every step above
    assert rotation[-1] < -360
    assert curled.tip_rotation == rotation[-1]


def test_the_summary_and_its_extremes_keep_the_whole_turn(curled):
    summary = curled.summary()
    rotation = curled.history["tip_rotation"]
    assert summary["tip_rotation_deg"] == rotation[-1] < -360
    extremes = summary["extremes"]["tip_rotation"]
    assert extremes["min"] == rotation[-1] and extremes["min_step"] == len(rotation) - 1
    assert extremes["max"] == 0.0 and extremes["max_step"] == 0  # rest: it never turned counter-clockwise


def test_the_plot_draws_the_whole_turn(curled):
    figure = curled.plot()
    (axes,) = [a for a in figure.axes if a.get_title().startswith("bending angle")]
    (line,) = axes.get_lines()
    drawn = np.asarray(line.get_ydata(), dtype=float)
    assert drawn.min() < -360 and np.all(np.diff(drawn) < 0)


def test_inflate_prints_and_writes_the_whole_turn(finger_file, tmp_path, capsys):
    assert inflate.main(["--scene", str(finger_file), "--out", str(tmp_path), *QUIET]) == 0
    printed = capsys.readouterr().out
    summary = json.loads((tmp_path / "curling_finger_summary.json").read_text())
    history = np.genfromtxt(tmp_path / "curling_finger_history.csv", delimiter=",", names=True, deletechars="")
    final = history["tip_rotation"][-1]
    assert final < -360 and np.all(np.diff(history["tip_rotation"]) < 0)
    assert summary["tip_rotation_deg"] == pytest.approx(final, abs=1e-9)
    assert summary["extremes"]["tip_rotation"]["min"] == pytest.approx(final, abs=1e-9)
    assert f"tip rotation {final:+.1f} deg" in printed
    assert f"rotation {final:+.1f} (step 12) to +0.0 (step 0) deg" in printed


def test_reach_output_does_not_claim_an_angle_the_finger_never_turns_to(finger_file, tmp_path, capsys):
    """The finger only curls clockwise: +150 degrees is never crossed (0141107 said `reached: tip_rotation = 180`,
    the root finder landing on the wrap)."""
    command = ["--scene", str(finger_file), "--output", "tip_rotation", "--value", "150", "--out", str(tmp_path)]
    assert reach.main([*command, *QUIET]) == 1
    captured = capsys.readouterr()
    assert "reached:" not in captured.out
    (line,) = [text for text in captured.err.splitlines() if text.startswith("unreachable:")]
    assert line.startswith("unreachable: tip_rotation = 150 is not crossed by the schedule; closest 0 at step 0")
    (path,) = tmp_path.glob("*_summary.json")
    assert not json.loads(path.read_text())["found"]


def test_reach_output_finds_an_angle_past_a_whole_turn(finger_file):
    """-370 degrees, past a whole turn: a fresh ramp to the commands found curls the body's bottom edge that far."""
    scene = tp.load_scene(finger_file)
    result = outputs.reach_output(scene.build(), "tip_rotation", -370.0)
    assert result.found and result.value == pytest.approx(-370.0, abs=1e-3) and 11 < result.step < 12
    again = tp.simulate(
        scene.with_values(
            {
                **{f"chambers[{i}].keyframes": [[6, float(c)]] for i, c in enumerate(result.commands)},
                "schedule.increments": 6,
            }
        )
    )
    assert again.tip_rotation == pytest.approx(-370.0, abs=0.1)
    assert abs(bottom_edge_turn(again.mesh.vertices, again.positions[-1]) + 370.0) <= 0.05 * 370.0 + 1.0


@pytest.mark.parametrize("column", SOLVER_COLUMNS)
def test_reach_output_refuses_the_solvers_columns_in_one_line(column, tmp_path, capsys):
    command = ["--max-area", "0.02", "--steps", "4", "--output", column, "--value", "3.5", "--out", str(tmp_path)]
    assert reach.main([*command, *QUIET]) == 2
    captured = capsys.readouterr()
    (line,) = captured.err.strip().splitlines()
    assert line.startswith(f"error: output {column!r} is not a measure of this scene's state")
    allowed = line.split(": one of ")[1].split(", ")
    assert "tip_rotation" in allowed and "main.pressure" in allowed
    assert not set(SOLVER_COLUMNS) & set(allowed) and "reached" not in captured.out


def test_a_column_that_jumps_over_the_value_inside_a_step_is_not_reached(monkeypatch):
    """Newton's iteration count, let through as a target, is an integer: brentq lands on one of its jumps, and the
    value found there (a whole number) is not the 3.5 wanted (0141107 said `reached: iterations = 3`)."""
    monkeypatch.setattr(outputs, "SOLVER_COLUMNS", ())
    scene = tp.reference_scene(max_area=0.02, chamber_points=32, steps=4)
    result = outputs.reach_output(scene.build(), "iterations", 3.5)
    assert result.evaluations and not result.found
    assert result.value == round(result.value) and abs(result.value - 3.5) >= 0.5
    assert result.summary_line().startswith("unreachable: iterations = 3.5 is not taken inside step 1 of the schedule")


def test_a_column_never_enters_a_file_name_unreduced(tmp_path, capsys):
    """A chamber's name goes into its columns; the summary of a reach for one stays inside --out, even where --out
    holds a folder named as the column's first part (0141107 wrote a/b/escaped.area_ratio1.5_summary.json)."""
    scene = tp.reference_scene(max_area=0.02, chamber_points=32, steps=4)
    text = scene.to_toml().replace('name = "main"', 'name = "x/../../escaped"')
    (tmp_path / "odd.toml").write_text(text)
    out = tmp_path / "a" / "b" / "out"
    (out / f"{scene.name}_output_x").mkdir(parents=True)
    column = "x/../../escaped.area_ratio"
    command = ["--scene", str(tmp_path / "odd.toml"), "--output", column, "--value", "1.5", "--out", str(out)]
    assert reach.main(command) == 0
    written = list(tmp_path.rglob("*.json"))
    assert written and all(out in p.parents for p in written), written
    assert "reached: x/../../escaped.area_ratio = 1.5" in capsys.readouterr().out


def test_an_angle_is_continued_from_the_state_before():
    """A rigid rotation of the tip's points by 0, 40, ..., 400 degrees, each continued from the last, reads as the
    whole turn; alone, each reads as its remainder in (-180, 180] (the twist about x likewise, in 3D)."""
    mesh2 = type("Mesh", (), {"dim": 2, "tip": np.arange(4), "vertices": np.array([[1.0, y] for y in range(4)])})
    points = np.array([[1.0, y, 0.5 * y] for y in range(4)])
    mesh3 = type("Mesh", (), {"dim": 3, "tip": np.arange(4), "vertices": points})
    rotation = twist = 0.0
    for degrees in range(0, 401, 40):
        a = np.radians(degrees)
        turn = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
        u2 = mesh2.vertices @ turn.T - mesh2.vertices
        rotation = tip_measures(mesh2, u2, rotation)[1]
        assert rotation == pytest.approx(degrees, abs=1e-9)
        assert tip_measures(mesh2, u2)[1] == pytest.approx((degrees + 180) % 360 - 180, abs=1e-9)
        moved = points.copy()
        moved[:, 1:] = points[:, 1:] @ turn.T
        twist = tip_twist_of(mesh3, moved - points, twist)
        assert twist == pytest.approx(degrees, abs=1e-9)
    assert continued(170.0, -170.0) == pytest.approx(-190.0) and continued(-100.0, 300.0) == pytest.approx(260.0)
