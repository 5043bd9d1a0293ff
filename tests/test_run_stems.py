"""Result-file stems: two different runs into one --out keep both sets of files; a re-run replaces only its own."""

import hashlib
import json
import os
import tomllib

import pytest

from taichi_pneuma.apps.inflate import main

FLAGS = ["--steps", "3", "--growth", "1.5", "--max-area", "0.02", "--no-video", "--quiet"]
PLAIN = "inflate_cy+0.15_growth1.5_steps3_max_area0.02"  # the flags that differ from the reference beam's
STIFF = PLAIN + "_E2e4"  # and the --set as given


def files_of(out, stem):
    """{path: (bytes, mtime)} of every file of the stem's run, its VTU folder's included."""
    paths = [p for p in out.rglob("*") if p.is_file() and p.relative_to(out).parts[0].startswith(stem)]
    return {p: (p.read_bytes(), p.stat().st_mtime_ns) for p in paths}


def test_a_changed_scene_writes_its_own_files_and_a_rerun_replaces_only_its_own(tmp_path, capsys):
    assert main([*FLAGS, "--out", str(tmp_path)]) == 0
    assert main([*FLAGS, "--set", "E=2e4", "--out", str(tmp_path)]) == 0
    summaries = {s: json.loads((tmp_path / f"{s}_summary.json").read_text()) for s in (PLAIN, STIFF)}
    for stem, E in ((PLAIN, 1e4), (STIFF, 2e4)):
        toml = (tmp_path / f"{stem}_scene.toml").read_text()
        assert tomllib.loads(toml)["material"]["E"] == E
        assert summaries[stem]["scene_sha256"] == hashlib.sha256(toml.encode()).hexdigest()
    # the same area ratio in a material twice as stiff takes about twice the pressure
    p = [summaries[s]["chambers"]["main"]["final_pressure"] for s in (PLAIN, STIFF)]
    assert p[1] / p[0] == pytest.approx(2.0, rel=0.1)
    stiff_before = files_of(tmp_path, STIFF)
    assert len(stiff_before) == 8  # history, states, scene, summary, PVD and 3 VTU
    plain_before = os.stat(tmp_path / f"{PLAIN}_summary.json").st_mtime_ns
    assert main([*FLAGS, "--out", str(tmp_path)]) == 0  # the plain run again
    assert os.stat(tmp_path / f"{PLAIN}_summary.json").st_mtime_ns > plain_before
    assert files_of(tmp_path, STIFF) == stiff_before


def test_a_long_change_is_named_by_the_scenes_hash(tmp_path, capsys):
    """Past 40 characters of changes the stem ends in the first 8 hex digits of the scene's SHA-256."""
    sets = ["--set", "chambers[0].center[1]=-0.15", "--set", "material.nu=0.4"]
    assert main([*FLAGS, *sets, "--out", str(tmp_path)]) == 0
    (summary,) = [p for p in os.listdir(tmp_path) if p.endswith("_summary.json")]
    digest = json.loads((tmp_path / summary).read_text())["scene_sha256"]
    assert summary == f"inflate_cy+0.15_{digest[:8]}_summary.json"
    toml = (tmp_path / f"inflate_cy+0.15_{digest[:8]}_scene.toml").read_text()
    assert hashlib.sha256(toml.encode()).hexdigest() == digest
