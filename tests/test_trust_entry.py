"""Issue 28, the entry points: a finished run survives a signal, a signal during cut-backs ends the run at once,
small mesh files cannot claim large memory, and every bad input at every entry point (command lines,
environment variables, the Python API) is one `error:` line (PneumaInputError), never a traceback."""

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

ENV = {**os.environ, "PYTHONUNBUFFERED": "1"}
STEM = "inflate_cy+0.15"
CHEAP = ["--steps", "4", "--max-area", "0.02"]


def app(name: str, *args: str, env: dict | None = None, timeout: float = 120) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", f"taichi_pneuma.apps.{name}", *args], capture_output=True,
                          text=True, env=env or ENV, timeout=timeout, check=False)


def one_error_line(done: subprocess.CompletedProcess, *needles: str) -> str:
    """The run's one `error:` line (exit 2, no traceback), which names each of needles."""
    errors = [line for line in done.stderr.splitlines() if line.startswith("error:")]
    assert done.returncode == 2 and "Traceback" not in done.stderr and len(errors) == 1, done.stderr
    assert all(needle in errors[0] for needle in needles), errors[0]
    return errors[0]


# --- 1. signals -----------------------------------------------------------------------------------------

def signalled_when(line_seen: str, signum: int, out: Path, *flags: str, delay: float = 0.0):
    """Run pneuma-inflate, send signum `delay` s after it prints a line containing line_seen; (exit code, stderr,
    seconds from the signal to the exit). A run still alive 20 s after the signal is killed (exit None)."""
    proc = subprocess.Popen([sys.executable, "-m", "taichi_pneuma.apps.inflate", *CHEAP, "--out", str(out), *flags],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=ENV)
    for line in proc.stdout:
        if line_seen in line:
            time.sleep(delay)
            proc.send_signal(signum)
            break
    sent = time.perf_counter()
    try:
        _, stderr = proc.communicate(timeout=20)
    except subprocess.TimeoutExpired:
        proc.kill()
        _, stderr = proc.communicate()
        return None, stderr, time.perf_counter() - sent
    return proc.returncode, stderr, time.perf_counter() - sent


@pytest.mark.parametrize("signum, delay", [(signal.SIGINT, 0.0), (signal.SIGTERM, 0.0), (signal.SIGTERM, 0.1)],
                         ids=["SIGINT", "SIGTERM", "SIGTERM-0.1s-later"])
def test_a_signal_once_the_last_increment_is_solved_waits_for_every_result_file(tmp_path, signum, delay):
    """The signal comes as the last step's line is printed (the run is finished, no file written yet). Before:
    only the PVD and the VTU files were left."""
    out = tmp_path / "out"
    code, stderr, _ = signalled_when("step   3/3", signum, out, "--size", "128x64", delay=delay)
    assert code == 128 + signum and "Traceback" not in stderr, stderr
    assert [line for line in stderr.splitlines() if line.startswith("error:")] == [
        f"error: interrupted ({'Ctrl-C' if signum == signal.SIGINT else 'SIGTERM'})"]
    summary = json.loads((out / f"{STEM}_summary.json").read_text())
    assert summary["steps"] == 4 and summary["interrupted"] is False and summary["video_frames"] == 4
    rows = (out / f"{STEM}_history.csv").read_text().splitlines()
    assert [row.split(",")[0] for row in rows[1:]] == ["0", "1", "2", "3"]
    assert np.load(out / f"{STEM}_states.npz")["positions"].shape[0] == 4
    for name in (f"{STEM}.mp4", f"{STEM}.png", f"{STEM}_plot.png", f"{STEM}_scene.toml", f"{STEM}.pvd"):
        assert (out / name).stat().st_size > 0, name
    assert len(list((out / f"{STEM}_vtk").glob("*.vtu"))) == 4
    assert not list(out.rglob("*.partial"))


def test_a_signal_while_an_increment_cuts_back_ends_the_run_within_a_second(tmp_path):
    """One Newton iteration per try and 100000 cuts allowed: step 1 creeps by ever smaller cuts. Before: the
    first SIGTERM was noted and waited for the increment's end, minutes away."""
    out = tmp_path / "out"
    code, stderr, seconds = signalled_when("step   0/3", signal.SIGTERM, out, "--max-iterations", "1",
                                           "--max-cuts", "100000", "--no-video", delay=1.0)
    assert code == 143 and seconds < 2.0 and "Traceback" not in stderr, (code, seconds, stderr)
    errors = [line for line in stderr.splitlines() if line.startswith("error:")]
    assert errors == ["error: interrupted during step 1 of 3 (SIGTERM)"]
    summary = json.loads((out / f"{STEM}_summary.json").read_text())
    assert summary["interrupted"] is True and summary["steps"] == 1
