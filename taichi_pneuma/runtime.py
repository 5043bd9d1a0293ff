"""The single place where Taichi (or Quadrants, see backend.py) is initialised: float64, the caller's arch,
offline kernel cache.

The backend is imported by init(), so that importing this module (the apps' --help does) stays cheap.
An arch other than the CPU is started first in a child process (probe): a driver that crashes the process
that starts it (Taichi's Vulkan or OpenGL backend without a driver segfaults) ends the child, and the
command says so in one line.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys

from .errors import PneumaInputError

ARCHES = ("cpu", "cuda", "vulkan", "metal", "opengl", "gpu")  # arch names; backend.ARCHES: those the backend has
PROBE_SECONDS = 300
_current: str | None = None


def probe(arch: str) -> None:
    """Start Taichi on `arch` in a child process (start()): PneumaInputError with the child's error line, or
    naming the signal that ended it (a driver that crashed), unless it started."""
    package = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, [package, os.environ.get("PYTHONPATH")]))}
    code = f"import sys; from taichi_pneuma import runtime; sys.exit(runtime.start_alone({arch!r}))"
    try:
        done = subprocess.run(
            [sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=PROBE_SECONDS, check=False
        )
    except subprocess.TimeoutExpired:
        raise PneumaInputError(f"arch = {arch!r}: Taichi did not start it within {PROBE_SECONDS} s here") from None
    if done.returncode == 0:
        return
    errors = [line for line in done.stderr.splitlines() if line.startswith("error: ")]
    if errors:
        raise PneumaInputError(errors[-1].removeprefix("error: "))
    how = (
        f"signal {signal.Signals(-done.returncode).name}"
        if done.returncode < 0 and -done.returncode in signal.valid_signals()
        else f"exit code {done.returncode}"
    )
    raise PneumaInputError(
        f"arch = {arch!r}: starting it here crashed a test process ({how}; no working driver for "
        f"it?); use cpu, or cuda (an NVIDIA GPU)"
    )


def start_alone(arch: str) -> int:
    """The probe's child: start(arch); 0, or its error line and 2."""
    try:
        start(arch)
    except PneumaInputError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    return 0


def init(arch: str = "cpu", cpu_threads: int | None = None) -> None:
    """Initialise Taichi once with float64 fields on `arch`; a later call with the same arch is a no-op.

    cpu_threads: the size of Taichi's CPU thread pool (default: every core); a study's worker
    processes use 1 each, so that N workers keep N cores busy. An arch the backend lacks or cannot start,
    or one whose kernels have no 64-bit floats (what "gpu" gives without CUDA: Vulkan, Metal, OpenGL), is a
    PneumaInputError."""
    if arch not in ARCHES:
        raise PneumaInputError(f"arch = {arch!r} is not one of {', '.join(ARCHES)}")
    if _current == arch:
        return
    if arch != "cpu":
        probe(arch)
    start(arch, cpu_threads)


def start(arch: str, cpu_threads: int | None = None) -> None:
    """ti.init on `arch` (init's checks after its probe)."""
    global _current
    from .backend import ARCHES as AVAILABLE
    from .backend import ti

    if arch not in AVAILABLE:
        raise PneumaInputError(f"arch = {arch!r} is not one this backend has: {', '.join(AVAILABLE)}")
    threads = {} if cpu_threads is None else {"cpu_max_num_threads": cpu_threads}
    _current = None  # ti.init resets whatever ran before; until it succeeds, nothing runs
    try:
        ti.init(arch=AVAILABLE[arch], default_fp=ti.f64, offline_cache=True, log_level=ti.WARN, **threads)
    except RuntimeError as exc:
        raise PneumaInputError(f"arch = {arch!r}: Taichi cannot start it here ({exc})") from None
    chosen = ti.lang.impl.current_cfg().arch  # ti.gpu is whichever GPU backend is found, the CPU if none
    if arch != "cpu" and chosen in (ti.x64, ti.arm64):  # Taichi falls back to the CPU with a warning only
        ti.reset()
        other = "" if arch == "cuda" else ", or cuda (an NVIDIA GPU)"
        raise PneumaInputError(
            f"arch = {arch!r} is not available here (Taichi would run on the CPU instead); use cpu{other}"
        )
    if chosen not in (ti.x64, ti.arm64, ti.cuda):  # the backends whose kernels have 64-bit floats
        ti.reset()
        raise PneumaInputError(
            f"arch = {arch!r} gives Taichi's {chosen.name} backend here, which cannot run this "
            f"program's 64-bit kernels; use cpu, or cuda (an NVIDIA GPU)"
        )
    _current = arch


def current_arch() -> str | None:
    """The backend Taichi was initialised on (None before init)."""
    return _current


def ensure_initialised() -> None:
    """Initialise on the CPU if the caller has not chosen a backend yet."""
    if _current is None:
        init("cpu")
