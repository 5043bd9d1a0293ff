"""Fuzzing what surrounds a run (issue 21): the state the output directory is in (Hypothesis: each result
name absent, a file, a folder, a link to a file or folder outside, a dangling link or a FIFO), signals
at random times, runs of the same scene at once, and any value of the package's environment variables. Whatever
the state, a run ends with its files whole or one `error:` line, never follows a link out of --out, never blocks
and never prints a traceback; a signal ends it with 128 + signal and the steps done kept consistently."""

import importlib.util
import json
import os
import random
import re
import signal
import subprocess
import sys
import tempfile
import time
from contextlib import redirect_stderr, redirect_stdout
from datetime import timedelta
from io import StringIO
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, note, settings
from hypothesis import strategies as st

from taichi_pneuma.apps.inflate import main
from taichi_pneuma.environment import CHOICES

SCENES = Path(__file__).resolve().parent.parent / "taichi_pneuma" / "scenes"
CHEAP = (
    (SCENES / "reference_beam.toml")
    .read_text()
    .replace("max_area = 0.0012", "max_area = 0.02")
    .replace("[35, 3.5]", "[2, 1.3]")
    .replace("increments = 35", "increments = 2")
)
ENV = {**os.environ, "PYTHONUNBUFFERED": "1"}
STEM = "reference_beam"
NAMES = [
    f"{STEM}_history.csv",
    f"{STEM}_states.npz",
    f"{STEM}_summary.json",
    f"{STEM}_scene.toml",
    f"{STEM}.pvd",
    f"{STEM}_vtk",
    f".{STEM}.lock",
    f".{STEM}_history.csv.partial.csv",
    f".{STEM}_summary.json.partial.json",
    f".{STEM}_history.csv.999999999.abcdefgh.partial",
    f"{STEM}_vtk/{STEM}_0000.vtu",
    f"{STEM}_vtk/.{STEM}_0001.vtu.partial.vtu",
]
STATES = ["file", "folder", "link to a file", "link to a folder", "dangling link", "fifo"]


def make(path: Path, state: str, outside: Path) -> None:
    if not path.parent.is_dir() or path.parent.is_symlink():
        return  # inside a name made something else (or outside): left as it is
    if state == "file":
        path.write_text("planted")
    elif state == "folder":
        path.mkdir()
        (path / "inside").write_text("planted")
    elif state == "link to a file":
        path.symlink_to(outside / "victim.txt")
    elif state == "link to a folder":
        path.symlink_to(outside, target_is_directory=True)
    elif state == "dangling link":
        path.symlink_to(outside / "nothing-here")
    else:
        os.mkfifo(path)


def snapshot(directory: Path) -> dict:
    return {str(p.relative_to(directory)): p.read_bytes() if p.is_file() else None for p in directory.rglob("*")}


@settings(
    max_examples=25,
    deadline=timedelta(seconds=60),
    derandomize=True,
    database=None,
    suppress_health_check=[HealthCheck.too_slow],
)
@given(st.lists(st.tuples(st.sampled_from(NAMES), st.sampled_from(STATES)), max_size=4, unique_by=lambda s: s[0]))
def test_any_state_of_the_output_directory_gives_whole_files_or_one_error_line(planted):
    note(f"planted: {planted}")
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        outside, out, scene = work / "outside", work / "out", work / "scene.toml"
        outside.mkdir()
        (outside / "victim.txt").write_text("precious")
        (outside / f"{STEM}_0000.vtu").write_text("someone's")
        out.mkdir()
        scene.write_text(CHEAP)
        for name, state in sorted(planted, key=lambda s: s[0].count("/")):
            make(out / name, state, outside)
        before = snapshot(outside)
        err = StringIO()
        start = time.perf_counter()
        with redirect_stderr(err), redirect_stdout(StringIO()):
            code = main(["--scene", str(scene), "--out", str(out), "--no-video", "--quiet"])
        lines = [line for line in err.getvalue().splitlines() if line.strip()]
        assert time.perf_counter() - start < 30
        assert snapshot(outside) == before, "a file outside --out changed"
        if code == 0:
            assert lines == []
            summary = json.loads((out / f"{STEM}_summary.json").read_text())
            for name in NAMES[:5]:
                assert (out / name).is_file() and not (out / name).is_symlink(), name
            listed = re.findall(r'file="([^"]+)"', (out / f"{STEM}.pvd").read_text())
            assert len(listed) == summary["steps"] and all((out / f).is_file() for f in listed)
        else:
            assert code == 2 and len(lines) == 1 and lines[0].startswith("error: "), lines


@settings(
    max_examples=30,
    deadline=timedelta(seconds=60),
    derandomize=True,
    database=None,
    suppress_health_check=[HealthCheck.too_slow],
)
@given(
    st.sampled_from(sorted(CHOICES)),
    st.one_of(
        st.sampled_from(
            ["", "taichi", "quadrants", "triangle", "meshpy", "TAICHI", " taichi", "x" * 5000, "../taichi"]
        ),
        st.text(st.characters(blacklist_categories=("Cs",), blacklist_characters="\x00"), max_size=30),
    ),
)
def test_any_value_of_the_environment_variables_runs_or_is_one_error_line(variable, value):
    """PNEUMA_BACKEND and PNEUMA_TRIANGLE set to anything: a run (the name allowed and installed) or one error line
    naming the variable, before any work (issue 28: the sweep recorded the error per row and exited 0)."""
    note(f"{variable}={value!r}")
    previous = os.environ.get(variable)
    os.environ[variable] = value
    try:
        with tempfile.TemporaryDirectory() as tmp:
            scene = Path(tmp) / "scene.toml"
            scene.write_text(CHEAP)
            err = StringIO()
            with redirect_stderr(err), redirect_stdout(StringIO()):
                code = main(["--scene", str(scene), "--out", str(Path(tmp) / "out"), "--no-video", "--quiet"])
    finally:
        os.environ.pop(variable) if previous is None else os.environ.__setitem__(variable, previous)
    lines = [line for line in err.getvalue().splitlines() if line.strip()]
    usable = value == "" or (value in CHOICES[variable] and importlib.util.find_spec(value) is not None)
    if usable:
        assert code == 0 and lines == [], lines
    else:
        assert code == 2 and len(lines) == 1 and lines[0].startswith(f"error: environment variable {variable}="), lines
        assert len(lines[0]) < 400


def run_and_signal(out: Path, signum: int, delay: float) -> tuple[int, str]:
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "taichi_pneuma.apps.inflate",
            "--steps",
            "60",
            "--max-area",
            "0.02",
            "--no-video",
            "--quiet",
            "--out",
            str(out),
        ],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
        env=ENV,
    )
    time.sleep(delay)
    proc.send_signal(signum)
    _, stderr = proc.communicate(timeout=120)
    return proc.returncode, stderr


def consistent(out: Path) -> None:
    """The files a run left: a summary, history and states that agree, a PVD listing VTU files that exist,
    no private folder left."""
    stem = "inflate_cy+0.15_steps60_max_area0.02"
    assert not [p for p in out.rglob("*.partial")], "a private folder was left"
    if (out / f"{stem}_summary.json").exists():
        steps = json.loads((out / f"{stem}_summary.json").read_text())["steps"]
        history = np.genfromtxt(out / f"{stem}_history.csv", delimiter=",", names=True)
        assert np.atleast_1d(history).shape[0] == steps
        assert np.load(out / f"{stem}_states.npz")["positions"].shape[0] == steps
    if (out / f"{stem}.pvd").exists():
        listed = re.findall(r'file="([^"]+)"', (out / f"{stem}.pvd").read_text())
        assert all((out / f).is_file() for f in listed)


@pytest.mark.slow
def test_signals_at_random_times_end_with_128_plus_signal_and_consistent_files(tmp_path):
    """Four runs, each sent SIGINT, SIGTERM or SIGHUP at a random time (seeded): while loading, during
    the ramp or while saving."""
    rng = random.Random(21)
    for k in range(4):
        signum = rng.choice([signal.SIGINT, signal.SIGTERM, signal.SIGHUP])
        delay = rng.uniform(0.2, 6.0)
        code, stderr = run_and_signal(tmp_path / f"out{k}", signum, delay)
        context = f"{signal.Signals(signum).name} after {delay:.2f} s: exit {code}\n{stderr}"
        assert code in (0, 128 + signum) and "Traceback" not in stderr, context
        errors = [line for line in stderr.splitlines() if line.startswith("error:")]
        assert len(errors) == (code != 0), context
        if (tmp_path / f"out{k}").exists():
            consistent(tmp_path / f"out{k}")


@pytest.mark.slow
def test_runs_of_one_scene_at_once_never_interleave(tmp_path):
    """Three runs of the same scene into one --out: each ends done or refused (another run holds the
    stem); the files left are one run's, whole."""
    procs = [
        subprocess.Popen(
            [
                sys.executable,
                "-m",
                "taichi_pneuma.apps.inflate",
                "--steps",
                "30",
                "--max-area",
                "0.02",
                "--no-video",
                "--quiet",
                "--out",
                str(tmp_path),
            ],
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
            text=True,
            env=ENV,
        )
        for _ in range(3)
    ]
    outcomes = [(p.wait(timeout=300), p.stderr.read()) for p in procs]
    assert all(
        code == 0
        or (code == 2 and "another run is writing the results named 'inflate_cy+0.15_steps30_max_area0.02'" in err)
        for code, err in outcomes
    ), outcomes
    assert any(code == 0 for code, _ in outcomes)
    consistent(tmp_path)
    summary = json.loads((tmp_path / "inflate_cy+0.15_steps30_max_area0.02_summary.json").read_text())
    assert summary["steps"] == 30 and len(os.listdir(tmp_path / "inflate_cy+0.15_steps30_max_area0.02_vtk")) == 30
