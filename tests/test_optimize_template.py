"""Scene templates (study/template.py, pneuma-optimize --template): each design is the Scene a Python file's
scene(**parameters) returns, run in the worker; the recorded design is that scene; every refusal is one line; and the
shipped STEP template (examples/optimize_step_template.py) draws the actuator's parts whose volumes are the closed
forms and runs them."""

import math
import textwrap
from pathlib import Path

import pytest

import taichi_pneuma as tp
from taichi_pneuma.apps.optimize import main
from taichi_pneuma.study import SceneTemplate

CY = "chambers[0].center[1]"
BEAM = tp.reference_scene(steps=11, max_area=0.01)
TEMPLATE = '''
import taichi_pneuma as tp

def scene(height=0.1, stiffness=1e4):
    """the coarse reference beam, its chamber at this height, the rubber this stiff"""
    return tp.reference_scene(steps=11, max_area=0.01).with_values(
        {"chambers[0].center[1]": height, "material.E": stiffness}
    )
'''
EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "optimize_step_template.py"


def template_file(tmp_path, text: str = TEMPLATE, name: str = "part.py") -> Path:
    path = tmp_path / name
    path.write_text(textwrap.dedent(text))
    return path


def test_each_design_is_the_scene_the_template_returns_run_alone(tmp_path):
    template = SceneTemplate.read(template_file(tmp_path))
    report = tp.optimize(
        template, {"height": (-0.15, 0.15)}, maximize="tip_rotation_deg", trials=3, out=tmp_path / "out"
    )
    assert len(report.rows) == 3 and all(r["error"] is None for r in report.rows)
    for row in report.rows:
        folder = tmp_path / "out" / row["folder"]
        alone = tp.simulate(BEAM.with_value(CY, row["height"]))  # the same design, made without the template
        assert tp.load_scene(folder / "scene.toml").to_toml() == alone.scene.to_toml()
        assert row["objective_0"] == pytest.approx(alone.summary()["tip_rotation_deg"], rel=1e-6, abs=1e-6)


@pytest.mark.slow  # spawns two workers
def test_the_app_runs_a_template_on_the_pool_with_set_edits(tmp_path, capsys):
    """--template on 2 worker processes (the file's text travels to them), --set applied to each design."""
    out = tmp_path / "out"
    path = template_file(tmp_path)
    flags = ["--template", str(path), "--vary", "stiffness=5e3:2e4", "--minimize", "tip_dy", "--trials", "2"]
    assert main([*flags, "--set", "chambers[0].center[1]=0.05", "--workers", "2", "--out", str(out)]) == 0
    designs = [tp.load_scene(folder / "scene.toml") for folder in (out / "optimize").iterdir()]
    assert len(designs) == 2 and {d.geometry.chambers[0][1].center[1] for d in designs} == {0.05}  # --set, on each
    assert len({d.material.youngs_modulus for d in designs}) == 2  # the varied parameter
    assert "best: #" in capsys.readouterr().out


@pytest.mark.parametrize(
    "text, name, flags, words",
    [
        (TEMPLATE, "part.txt", ["--vary", "height=0:0.1"], "a template is a Python file (.py)"),
        ("x = 1\n", "part.py", ["--vary", "height=0:0.1"], "it defines no function scene(**parameters)"),
        ("def scene(height):\n    pass\n", "part.py", ["--vary", "height=0:0.1"], "'height' needs a default"),
        ("import nosuchmodule\n", "part.py", ["--vary", "height=0:0.1"], "running it failed: ModuleNotFoundError"),
        ("def scene(height=0.1):\n    return 3\n", "part.py", ["--vary", "height=0:0.1"], "returned int, not a"),
        (TEMPLATE, "part.py", ["--vary", "width=0:0.1"], "no parameter 'width' (it has height, stiffness)"),
        (TEMPLATE, "part.py", ["--vary", "height=0:0.1", "--vary", "height=0:0.2"], "a key is varied twice"),
    ],
)
def test_a_bad_template_is_one_error_line_and_exit_2(tmp_path, capsys, text, name, flags, words):
    path = template_file(tmp_path, text, name)
    out = tmp_path / "out"
    assert main(["--template", str(path), *flags, "--minimize", "tip_dy", "--out", str(out)]) == 2
    lines = [line for line in capsys.readouterr().err.splitlines() if line.strip()]
    assert len(lines) == 1 and lines[0].startswith("error:") and words in lines[0], lines
    assert not any(out.glob("*.db"))


def test_a_template_and_a_scene_together_are_refused(tmp_path, capsys):
    path = template_file(tmp_path)
    args = ["reference_beam", "--template", str(path), "--vary", "height=0:0.1", "--minimize", "tip_dy"]
    assert main([*args, "--out", str(tmp_path / "out")]) == 2
    assert "replaces the scene 'reference_beam': give one of them" in capsys.readouterr().err


@pytest.mark.slow  # gmsh draws and meshes the STEP parts
def test_the_step_template_draws_the_actuator_of_the_closed_forms(tmp_path, monkeypatch):
    """examples/optimize_step_template.py at a chamber radius of 5.5 mm: the rubber meshed from its two STEP files
    has the volume of the parametric fiber_bending_3d's with that chamber on the same coarse mesh (to 0.5 %: two
    meshes of one shape), within 5 % of the closed form (pi R^2 / 2 L + base - pi r^2 / 2 l: 12 mm tetrahedra
    across an 11 mm chamber), and a short ramp on it bends the tip towards the sheet."""
    monkeypatch.setenv("PNEUMA_PARTS", str(tmp_path / "parts"))
    coarse = {"mesh.size": 12.0, "mesh.through_wall": None, "mesh.near_chambers": 6.0, "mesh.distance": 6.0}
    template = SceneTemplate.read(
        EXAMPLE, {**coarse, "schedule.increments": 2, "chambers[0].keyframes": [[0, 0.0], [2, 30.0]]}
    )
    scene = template.build({"chamber_radius": 5.5, "pitch": 5.0})
    assert sorted(p.name for p in (tmp_path / "parts").iterdir()) == ["body_r5.500000.step", "chamber_r5.500000.step"]
    built = scene.build()
    parametric = tp.load_scene("fiber_bending_3d").with_values({**coarse, "chambers[0].radius": 5.5}).build()
    assert built.mesh.volume == pytest.approx(parametric.mesh.volume, rel=0.005)
    rubber = math.pi * 8.0**2 / 2 * 100 + 2 * 16 * 100 - math.pi * 5.5**2 / 2 * 94
    assert built.mesh.volume == pytest.approx(rubber, rel=0.05)
    result = tp.simulate(scene)
    assert result.converged and result.summary()["tip_rotation_deg"] < -1.0
