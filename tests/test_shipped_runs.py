"""Every shipped 2D scene runs as shipped through `pneuma-inflate --scene NAME`, exits 0 and writes its pictures
(shipped_runs.py; the 3D ones: test_shipped_runs_3d.py). A run that stops with no equilibrium (not declared a limit
point) still writes everything up to its last equilibrium, pictures included, and exits 1."""

import json

import imageio.v3 as iio
import imageio_ffmpeg
import pytest
from renderers import SOFTWARE
from shipped_runs import DIMENSIONS, runs_and_writes_its_pictures

from taichi_pneuma.apps.inflate import main

# the solver's flags, not the scene's: balloon_pressure's last step has no equilibrium, and its 8 cuts of 40
# iterations each (the defaults) take 3 times the ramp to find that out
SOLVER = {"balloon_pressure": ["--max-cuts", "3", "--max-iterations", "20"]}


@pytest.mark.parametrize("name", [name for name, dim in DIMENSIONS.items() if dim == 2])
def test_every_shipped_2d_scene_exits_0_and_writes_its_pictures(name, tmp_path, capsys):
    runs_and_writes_its_pictures(name, SOLVER.get(name, []), tmp_path, capsys)


def test_a_ramp_stopped_by_no_equilibrium_writes_its_pictures_and_exits_1(tmp_path, capsys):
    """Four Newton iterations and no cuts cannot reach twice the rest area in one increment: step 1 fails; the rest
    state's files are written, its frame, plot and one-frame video included, then one error line, exit 1."""
    flags = ["--steps", "3", "--growth", "3", "--max-area", "0.02", "--max-iterations", "4", "--max-cuts", "0"]
    assert main([*flags, "--renderer", SOFTWARE, "--size", "192x96", "--quiet", "--out", str(tmp_path)]) == 1
    errors = capsys.readouterr().err.strip().splitlines()
    assert len(errors) == 1 and errors[0].startswith("error: step 1: no equilibrium at commanded area")
    stem = "inflate_cy+0.15_growth3_steps3_max_area0.02"
    summary = json.loads((tmp_path / f"{stem}_summary.json").read_text())
    assert (
        summary["steps"] == 1 and summary["stopped"]["step"] == 1 and summary["stopped"]["reason"] == "no equilibrium"
    )
    assert imageio_ffmpeg.count_frames_and_secs(str(tmp_path / f"{stem}.mp4"))[0] == 1
    assert iio.imread(tmp_path / f"{stem}.png").shape == (96, 192, 3)
    assert iio.imread(tmp_path / f"{stem}_plot.png").ndim == 3
