"""The inflate app as a user runs it."""

import json
import os

import numpy as np
import pytest

from taichi_pneuma.apps.inflate import main


def test_chamber_escaping_the_beam_is_one_clear_line(tmp_path, capsys):
    assert main(["--cy", "0.5", "--out", str(tmp_path / "out")]) == 2
    lines = [l for l in capsys.readouterr().err.splitlines() if l.strip()]
    assert len(lines) == 1 and lines[0].startswith("error: ") and "cy = 0.5" in lines[0]


@pytest.mark.parametrize(
    "flags, word",
    [
        (["--nu", "0.5"], "nu = 0.5"),
        (["--E", "-1"], "E = -1"),
        (["--k", "0"], "k = 0"),
        (["--growth", "nan"], "--growth"),
        (["--steps", "1"], "steps = 1"),
        (["--steps", "0"], "steps = 0"),
        (["--nu", "-1"], "nu = -1"),
        (["--E", "inf"], "--E = inf"),
        (["--growth", "-1"], "growth = -1"),
        (["--cx", "1.2"], "horizontally"),
        (["--max-cuts", "-1"], "--max-cuts = -1"),
        (["--tol", "0"], "tol = 0"),
    ],
)
def test_bad_values_are_refused_with_exit_2(tmp_path, capsys, flags, word):
    assert main([*flags, "--out", str(tmp_path / "out")]) == 2
    assert word in capsys.readouterr().err
    assert not (tmp_path / "out").exists() or not any((tmp_path / "out").iterdir())


def test_unwritable_output_directory(tmp_path, capsys):
    blocker = tmp_path / "file"
    blocker.write_text("not a directory")
    assert main(["--out", str(blocker / "sub"), "--steps", "2"]) == 2
    assert "not writable" in capsys.readouterr().err


def test_short_run_writes_history_states_and_summary(tmp_path, capsys):
    out = tmp_path / "out"
    assert (
        main(
            [
                "--cy",
                "0.15",
                "--growth",
                "1.5",
                "--steps",
                "4",
                "--max-area",
                "0.01",
                "--out",
                str(out),
                "--no-video",
                "--quiet",
            ]
        )
        == 0
    )
    printed = capsys.readouterr().out
    assert "vertices" in printed and "tip deflection" in printed and "peak chamber pressure" in printed
    summary = json.loads((out / "inflate_cy+0.15_growth1.5_steps4_max_area0.01_summary.json").read_text())
    history = np.genfromtxt(
        out / "inflate_cy+0.15_growth1.5_steps4_max_area0.01_history.csv", delimiter=",", names=True
    )
    states = np.load(out / "inflate_cy+0.15_growth1.5_steps4_max_area0.01_states.npz")
    assert len(history) == 4 and states["positions"].shape == (4, summary["vertices"], 2)
    assert summary["all_converged"] and summary["chambers"]["main"]["area_ratio"] == pytest.approx(1.5, abs=0.01)
    tip = states["positions"][-1][states["tip"]] - states["rest"][states["tip"]]
    assert tip[:, 1].mean() == pytest.approx(summary["tip_deflection"], abs=1e-12)
    assert not [p for p in os.listdir(out) if "partial" in p]


def test_unconverged_ramp_stops_with_one_line_and_writes_the_steps_done(tmp_path, capsys):
    out = tmp_path / "out"
    assert (
        main(["--steps", "2", "--max-iterations", "5", "--max-cuts", "0", "--no-video", "--quiet", "--out", str(out)])
        == 1
    )
    printed = capsys.readouterr()
    errors = [l for l in printed.err.splitlines() if l.strip()]
    assert len(errors) == 1 and errors[0].startswith("error: step 1: no equilibrium at commanded area")
    assert "residual" in errors[0]
    assert "all converged: False (stopped at step 1: no equilibrium)" in printed.out  # not True for a failed run
    states = np.load(out / "inflate_cy+0.15_steps2_states.npz")
    assert states["positions"].shape[0] == 1  # the rest state, the one step that converged
    summary = json.loads((out / "inflate_cy+0.15_steps2_summary.json").read_text())
    assert (
        summary["steps"] == 1 and summary["stopped"]["step"] == 1 and summary["stopped"]["reason"] == "no equilibrium"
    )
    assert summary["all_converged"] is False
    assert (out / "inflate_cy+0.15_steps2_scene.toml").exists()


def test_quality_presets_set_mesh_and_tolerance_unless_overridden(tmp_path, capsys):
    from taichi_pneuma.apps.quality import QUALITY
    from taichi_pneuma.fem.planar import BeamGeometry

    for flags, max_area, stem in (
        (["--quality", "draft"], QUALITY["draft"][0], "inflate_cy+0.15_growth1.2_steps3_draft"),  # named by the preset
        (["--quality", "draft", "--max-area", "0.01"], 0.01, "inflate_cy+0.15_growth1.2_steps3_max_area0.01_draft"),
    ):
        out = tmp_path / str(max_area)
        assert main([*flags, "--steps", "3", "--growth", "1.2", "--no-video", "--quiet", "--out", str(out)]) == 0
        summary = json.loads((out / f"{stem}_summary.json").read_text())
        assert summary["vertices"] == BeamGeometry(cy=0.15, max_area=max_area).mesh().n_vertices
        assert summary["max_residual"] <= QUALITY["draft"][2]


def test_a_quality_preset_writes_its_own_files_beside_the_default_run(tmp_path, capsys):
    flags = ["--steps", "2", "--growth", "1.2", "--max-area", "0.02", "--no-video", "--quiet", "--out", str(tmp_path)]
    assert main(flags) == 0 and main([*flags, "--quality", "high"]) == 0
    default = json.loads((tmp_path / "inflate_cy+0.15_growth1.2_steps2_max_area0.02_summary.json").read_text())
    high = json.loads((tmp_path / "inflate_cy+0.15_growth1.2_steps2_max_area0.02_high_summary.json").read_text())
    assert default["element_order"] == 1 and high["element_order"] == 2  # neither run overwrote the other


def test_command_line_defaults_are_the_solvers_and_the_reference_scenes():
    """The flags' defaults are written as plain numbers (so --help needs no solver import): they must be the
    library's own defaults."""
    import inspect

    from taichi_pneuma.apps import cli, inflate, quality
    from taichi_pneuma.fem.planar import BeamGeometry
    from taichi_pneuma.scene.build import reference_scene
    from taichi_pneuma.solve.newton import NewtonOptions
    from taichi_pneuma.solve.simulate import MAX_CUTS

    assert quality.QUALITY["default"] == (BeamGeometry.max_area, 1, NewtonOptions.tol)
    assert (cli.MAX_ITERATIONS, cli.MAX_CUTS) == (NewtonOptions.max_iterations, MAX_CUTS)
    flags = vars(inflate.parser().parse_args([]))
    defaults = inspect.signature(reference_scene).parameters
    for name in ("cy", "cx", "growth", "steps", "E", "nu", "k"):
        assert flags[name] == defaults[name].default, name


def test_set_changes_the_run(tmp_path, capsys):
    """--set moves the chamber below the axis (the beam curls up instead of down) and stops the inflation
    at 3x; the scene file written beside the results says so."""
    flags = ["--growth", "3.5", "--steps", "4", "--max-area", "0.01", "--no-video", "--quiet"]
    tips = {}
    for name, extra in (
        ("default", []),
        ("set", ["--set", "chambers[0].center[1]=-0.15", "--set", "chambers[0].keyframes=[[3, 3.0]]"]),
    ):
        out = tmp_path / name
        assert main([*flags, *extra, "--out", str(out)]) == 0
        (path,) = out.glob("inflate_cy+0.15_*_summary.json")  # the --set run's: named by its scene's hash
        summary = json.loads(path.read_text())
        tips[name], ratio = summary["tip_deflection"], summary["chambers"]["main"]["area_ratio"]
    assert tips["default"] < -0.1 and tips["set"] > 0.1 and ratio == pytest.approx(3.0, abs=0.01)
    from taichi_pneuma.scene.scenefile import load_scene

    scene = load_scene(tmp_path / "set" / path.name.replace("_summary.json", "_scene.toml"))
    assert scene.geometry.chambers[0][1].center == (0.0, -0.15) and scene.controls[0].schedule.keyframes == ((3, 3.0),)


@pytest.mark.parametrize(
    "assignment, word",
    [
        ("material.nu=0.5", "material.nu"),
        ("chambers[1].center=[0, 0]", "chambers[1].center"),
        ("mesh.maxarea=0.1", "mesh.maxarea"),
        ("material.E", "KEY=VALUE"),
    ],
)
def test_bad_set_is_one_line_and_exit_2(tmp_path, capsys, assignment, word):
    assert main(["--set", assignment, "--steps", "2", "--no-video", "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: --set") and word in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "out").exists()


def test_step_lines_are_whole_lines_when_output_is_not_a_terminal(tmp_path, capsys):
    """Piped or logged output gets one line per step and no progress-bar redraws (no carriage returns)."""
    assert main(["--steps", "4", "--growth", "1.5", "--max-area", "0.01", "--no-video", "--out", str(tmp_path)]) == 0
    captured = capsys.readouterr()
    assert "\r" not in captured.out and "\r" not in captured.err
    steps = [line for line in captured.out.splitlines() if line.startswith("  step")]
    assert [line.split()[1] for line in steps] == ["0/3", "1/3", "2/3", "3/3"]
    assert all(line.rstrip().endswith(tuple("0123456789")) for line in steps)  # each ends with its residual


def test_a_3d_frame_too_small_for_its_layout_is_refused_before_the_solve(tmp_path, capsys):
    """beam_3d at 320x160 (its view would be 68x14 pixels): exit 2 naming the smallest size, no result file."""
    assert main(["--scene", "beam_3d", "--size", "320x160", "--out", str(tmp_path / "out")]) == 2
    assert "at least 384x192" in capsys.readouterr().err
    assert not (tmp_path / "out").exists() or not any((tmp_path / "out").iterdir())


@pytest.mark.parametrize("app", ["inflate", "reach", "sweep"])
def test_list_scenes_prints_every_shipped_scene_a_line_each_and_exits_0(app, capsys):
    """--list-scenes on every app: one line per shipped scene file, its name first, then its description's first
    sentence (at most 100 characters)."""
    import importlib

    from taichi_pneuma.scene.shipped import shipped

    with pytest.raises(SystemExit) as done:
        importlib.import_module(f"taichi_pneuma.apps.{app}").main(["--list-scenes"])
    assert done.value.code == 0
    lines = capsys.readouterr().out.splitlines()
    assert [line.split()[0] for line in lines] == shipped() and len(lines) >= 20
    assert all(20 < len(line) <= 121 for line in lines)


def test_a_preset_driven_past_the_strains_it_was_fitted_to_warns_once(tmp_path, capsys):
    """pneunet_mm_kpa in Dragon Skin 10 (fitted to 0-200 % strain, a stretch of 3) to 40 kPa in 4 steps: its largest
    stretch passes 3 on the way (3.9 at the end), and one warning line names the step, the preset and its range."""
    flags = ["--scene", "pneunet_mm_kpa", "--set", "material.preset=dragon_skin_10", "--set", "schedule.increments=4"]
    flags += [f for i in range(6) for f in ("--set", f"chambers[{i}].keyframes=[[4, 40.0]]")]
    assert main([*flags, "--no-video", "--quiet", "--out", str(tmp_path)]) == 0
    warnings = [line for line in capsys.readouterr().err.splitlines() if "fitted to" in line]
    summary = json.loads(next(tmp_path.glob("*_summary.json")).read_text())
    assert summary["max_stretch"] > 3.0 and len(warnings) == 1
    assert (
        "past 3 (engineering strain 200 %), the largest in the data preset 'dragon_skin_10' was fitted" in warnings[0]
    )
