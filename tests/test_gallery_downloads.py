"""Each gallery script runs on its own, as a reader who downloads it from the site runs it: the file alone in an empty
folder, `python plot_x.py` there, with nothing of the repository on the path but the package (examples/ is not: a
helper beside the scripts would be missing from the download). It must finish without a traceback, write its
figure there as PNG (no display: Agg) and nothing outside its folder: nothing beside it, and its temporary files
(TMPDIR) removed."""

import importlib.util
import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SCRIPTS = sorted((ROOT / "examples").glob("plot_*.py"))


def test_there_are_gallery_scripts():
    assert len(SCRIPTS) >= 5


@pytest.mark.slow  # about 60 s of one core for all scripts together (plot_fiber_bending.py the longest, about 19 s)
@pytest.mark.parametrize("script", SCRIPTS, ids=lambda path: path.name)
def test_a_downloaded_gallery_script_runs_alone_in_an_empty_folder(script, tmp_path):
    folder, scratch = tmp_path / "download", tmp_path / "tmp"
    folder.mkdir()
    scratch.mkdir()
    (folder / script.name).write_bytes(script.read_bytes())
    env = {key: value for key, value in os.environ.items() if key not in ("PYTHONPATH", "MPLBACKEND", "TMPDIR")}
    # the package from this checkout (an installed one would do as well)
    env |= {"PYTHONPATH": str(ROOT), "MPLBACKEND": "Agg", "TMPDIR": str(scratch)}
    start = time.perf_counter()
    run = subprocess.run(
        [sys.executable, script.name], cwd=folder, env=env, capture_output=True, text=True, timeout=600
    )
    seconds = time.perf_counter() - start
    output = run.stdout + run.stderr
    print(f"{script.name}: {seconds:.1f} s")
    if run.returncode and "taichi-pneuma[3d]" in output and importlib.util.find_spec("gmsh") is None:
        pytest.skip("the script meshes a 3D shape, and gmsh is not installed")
    assert run.returncode == 0, output[-3000:]
    assert "Traceback" not in output, output[-3000:]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["download", "tmp"]
    pictures = sorted(p.name for p in folder.iterdir() if p.name != script.name)
    assert pictures and pictures[0] == f"{script.stem}.png" and all(p.endswith(".png") for p in pictures), pictures
    assert f"wrote {script.stem}.png" in run.stdout
    assert list(scratch.iterdir()) == [], "temporary files left behind"
