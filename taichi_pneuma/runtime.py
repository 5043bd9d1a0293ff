"""The single place where Taichi (or Quadrants, see backend.py) is initialised: float64, the caller's arch,
offline kernel cache."""

from __future__ import annotations

from .backend import ARCHES, ti
from .errors import PneumaInputError

F64_ARCHES = (ti.x64, ti.arm64, ti.cuda)  # the backends whose kernels have 64-bit floats (and atan2 of them)

_current: str | None = None


def init(arch: str = "cpu", cpu_threads: int | None = None) -> None:
    """Initialise Taichi once with float64 fields on `arch`; a later call with the same arch is a no-op.

    cpu_threads: the size of Taichi's CPU thread pool (default: every core); a study's worker
    processes use 1 each, so that N workers keep N cores busy. A backend Taichi cannot start, or one
    whose kernels have no 64-bit floats (what "gpu" gives without CUDA: Vulkan, Metal, OpenGL), is a
    PneumaInputError."""
    global _current
    if arch not in ARCHES:
        raise PneumaInputError(f"arch = {arch!r} is not one of {', '.join(ARCHES)}")
    if _current == arch:
        return
    threads = {} if cpu_threads is None else {"cpu_max_num_threads": cpu_threads}
    _current = None  # ti.init resets whatever ran before; until it succeeds, nothing runs
    try:
        ti.init(arch=ARCHES[arch], default_fp=ti.f64, offline_cache=True, log_level=ti.WARN, **threads)
    except RuntimeError as exc:
        raise PneumaInputError(f"arch = {arch!r}: Taichi cannot start it here ({exc})") from None
    chosen = ti.lang.impl.current_cfg().arch  # ti.gpu is whichever GPU backend is found, the CPU if none
    if chosen not in F64_ARCHES:
        ti.reset()
        raise PneumaInputError(f"arch = {arch!r} gives Taichi's {chosen.name} backend here, which cannot run this "
                               f"program's 64-bit kernels; use cpu, or cuda (an NVIDIA GPU)")
    _current = arch


def current_arch() -> str | None:
    """The backend Taichi was initialised on (None before init)."""
    return _current


def ensure_initialised() -> None:
    """Initialise on the CPU if the caller has not chosen a backend yet."""
    if _current is None:
        init("cpu")
