"""The public Python API: scenes round-trip through TOML, dotted keys change one value and are validated,
the README's example runs as shown, the example script runs, the plot has the history on its axes."""

import json
import re
import runpy
from pathlib import Path

import imageio_ffmpeg
import numpy as np
import pytest
from scenes import small_run

import taichi_pneuma as tp
from taichi_pneuma.render.plots import command_axis
from taichi_pneuma.scene.dotted_edits import parse_assignment
from taichi_pneuma.scene.scenefile import scene_data

ROOT = Path(__file__).resolve().parent.parent
SCENES = sorted((ROOT / "taichi_pneuma" / "scenes").glob("*.toml"))


@pytest.fixture(scope="module")
def small():
    """A short coarse reference ramp (the mesh other tests use, so Taichi's kernel cache serves it)."""
    return small_run()


@pytest.mark.parametrize("path", SCENES, ids=lambda p: p.stem)
def test_shipped_scenes_round_trip_through_toml(path, tmp_path):
    scene = tp.load_scene(path)
    written = tmp_path / "again.toml"
    written.write_text(scene.to_toml())
    again = tp.load_scene(written)
    assert again == scene
    assert again.to_toml() == scene.to_toml()


def test_round_tripped_scene_gives_the_same_mesh_and_tip_deflection(small, tmp_path):
    (tmp_path / "s.toml").write_text(small.scene.to_toml())
    again = tp.simulate(tp.load_scene(tmp_path / "s.toml"))
    assert np.array_equal(again.mesh.vertices, small.mesh.vertices)
    assert np.array_equal(again.mesh.triangles, small.mesh.triangles)
    # the same to round-off: the kernels' parallel scatter-adds sum in a thread-dependent order
    assert again.tip_deflection == pytest.approx(small.tip_deflection, rel=1e-9) and again.tip_deflection != 0


def test_with_value_changes_exactly_one_key():
    scene = tp.reference_scene(cy=0.15)
    lower = scene.with_value("chambers[0].center[1]", -0.1)
    before, after = scene_data(scene), scene_data(lower)
    assert after["chambers"][0]["center"] == [0.0, -0.1]
    after["chambers"][0]["center"][1] = 0.15
    assert after == before
    assert lower.geometry.chambers[0][1].center == (0.0, -0.1)
    assert scene.with_value("material.E", 2e4).material.youngs_modulus == 2e4
    assert scene.with_value("effects.gravity.density", 1.5).effects[0].density == 1.5  # a new effect table
    both = scene.with_values({"schedule.increments": 10, "chambers[0].keyframes": [[10, 2.0]]})
    assert both.schedule.commands(10)[0] == 2.0 and both.increments == 10


@pytest.mark.parametrize(
    "key, value, named",
    [
        ("material.nu", 0.5, "material.nu"),
        ("chambers[0].center[1]", 0.5, "chambers[0].center[1]"),  # the chamber would leave the beam
        ("chambers[2].center", [0, 0], "chambers[2].center"),
        ("material.Young", 1.0, "material.Young"),
        ("schedule.increments", 5, "schedule.increments"),  # a keyframe at step 35 lies past it
        ("mesh.max_area", "fine", "mesh.max_area"),
        ("material.E.x", 1, "material.E.x"),
        ("chambers.0", 1, "chambers.0"),
    ],
)
def test_bad_key_or_value_is_one_error_naming_the_key(key, value, named):
    with pytest.raises(tp.PneumaInputError) as error:
        tp.reference_scene().with_value(key, value)
    assert named in str(error.value)


def test_set_values_are_read_as_toml_values():
    assert parse_assignment("material.E=2e4") == ("material.E", 2e4)
    assert parse_assignment("chambers[0].center = [0, 0.1]") == ("chambers[0].center", [0, 0.1])
    assert parse_assignment("clamp.side=right") == ("clamp.side", "right")
    assert parse_assignment('name="a b"') == ("name", "a b")
    with pytest.raises(tp.PneumaInputError, match="KEY=VALUE"):
        parse_assignment("material.E")


def readme_api_example() -> str:
    text = (ROOT / "README.md").read_text()
    section = text[text.index("## Python API") :]
    return re.search(r"```python\n(.*?)```", section, re.S).group(1)


def test_readme_api_example_runs_as_shown(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    namespace = {}
    exec(readme_api_example(), namespace)
    result = namespace["result"]
    assert isinstance(result, tp.Result) and result.converged
    out = tmp_path / "out" / "api"
    stem = result.scene.name
    summary = json.loads((out / f"{stem}_summary.json").read_text())
    assert summary["tip_deflection"] == result.tip_deflection < 0  # chamber above the axis: curls down
    assert tp.load_scene(out / f"{stem}_scene.toml") == result.scene
    history = np.genfromtxt(out / f"{stem}_history.csv", delimiter=",", names=True, deletechars="")
    assert np.array_equal(history["tip_dy"], result.history["tip_dy"])
    assert (out / f"{stem}.pvd").exists() and len(list((out / f"{stem}_vtk").glob("*.vtu"))) == len(result.steps)
    assert imageio_ffmpeg.count_frames_and_secs(str(out / "ramp.mp4"))[0] == len(result.steps)
    assert (out / f"{stem}_plot.png").stat().st_size > 0
    assert f"tip deflection {result.tip_deflection:+.4f}" in capsys.readouterr().out


def test_example_script_runs(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    runpy.run_path(str(ROOT / "examples" / "chamber_height_sweep.py"), run_name="__main__")
    printed = capsys.readouterr().out
    tips = [float(t) for t in re.findall(r"tip deflection ([+-][\d.]+)", printed)]
    assert len(tips) == 3 and tips[0] > 0.1 and abs(tips[1]) < 0.05 and tips[2] < -0.1  # up, none, down
    assert (tmp_path / "out" / "sweep_cy.png").stat().st_size > 0


def test_plot_shows_the_history_on_labelled_axes(small):
    fig = small.plot()
    pa, tip, bending, extension = fig.axes  # area control: the area and pressure panels are the first one again
    assert pa.get_xlabel().startswith("area ratio") and pa.get_ylabel().startswith("pressure")
    assert tip.get_xlabel() == bending.get_xlabel() == extension.get_xlabel() == "pressure p"  # one chamber drives
    for ax, key in ((tip, "tip_dy"), (bending, "tip_rotation"), (extension, "tip_dx")):
        assert np.array_equal(ax.lines[0].get_xdata(), small.pressure[:, 0])
        assert np.array_equal(ax.lines[0].get_ydata(), small.history[key])
    assert np.array_equal(pa.lines[0].get_xdata(), small.area_ratio[:, 0])
    assert np.array_equal(pa.lines[0].get_ydata(), small.pressure[:, 0])
    assert small.command[:, 0].tolist() == [1.0, 1.5, 2.0]
    assert fig._repr_png_().startswith(b"\x89PNG")  # what a notebook displays


@pytest.mark.parametrize("name, label", [("bidirectional", "step"), ("pneunet_finger", "commanded pressure")])
def test_plots_are_against_the_command_when_all_chambers_share_it(name, label):
    scene = tp.load_scene(ROOT / "taichi_pneuma" / "scenes" / f"{name}.toml")
    command = np.array([scene.schedule.commands(i) for i in range(scene.increments + 1)])
    x, x_label = command_axis(command, [c.kind.quantity for c in scene.controls])
    assert x_label == label
    assert np.array_equal(x, np.arange(scene.increments + 1) if label == "step" else command[:, 0])


def test_two_api_runs_of_changed_scenes_saved_in_one_folder_keep_both_results(tmp_path):
    """Result.save's default stem is the scene's name, unless the folder holds another scene's files of that name:
    then the name and 8 hex digits of the scene's hash. Saving the same scene again replaces its own files."""
    from taichi_pneuma.result import scene_sha256

    base = tp.reference_scene(cy=0.15, steps=2, max_area=0.02)
    first = tp.simulate(base)
    second = tp.simulate(base.with_values({"material.E": 2e4}))
    names = [p.name for p in first.save(tmp_path, vtk=False, plot=False)]
    assert names[-2:] == [f"{base.name}_scene.toml", f"{base.name}_summary.json"]
    other = [p.name for p in second.save(tmp_path, vtk=False, plot=False)]
    assert other[-1] == f"{base.name}_{scene_sha256(second.scene)[:8]}_summary.json"
    assert [p.name for p in first.save(tmp_path, vtk=False, plot=False)] == names
    assert (tmp_path / f"{base.name}_summary.json").exists() and len(list(tmp_path.glob("*_summary.json"))) == 2


def test_a_saved_plot_is_titled_by_its_files_stem(tmp_path, monkeypatch):
    """The history plot Result.save writes is titled by the stem its files take (what the run changed of the scene:
    the apps' --set suffix, or the hash where another scene's files are there), not the bare scene name."""
    from taichi_pneuma.render import plots

    titles = []
    drawn = plots.history_figure
    monkeypatch.setattr(plots, "history_figure", lambda result, title=None: titles.append(title) or drawn(result))
    result = tp.simulate(tp.reference_scene(cy=0.15, steps=2, max_area=0.02))
    result.save(tmp_path, "reference_E2e4", vtk=False)
    assert titles == ["reference_E2e4"] and (tmp_path / "reference_E2e4_plot.png").stat().st_size > 0
    assert drawn(result, title="x")._suptitle.get_text() == "x"
