"""The single place where Taichi (or Quadrants, see backend.py) is initialised: float64, the caller's arch,
offline kernel cache.

The backend is imported by init(), so that importing this module (the apps' --help does) stays cheap.
"""

from __future__ import annotations

from .errors import PneumaInputError

ARCHES = ("cpu", "cuda", "vulkan", "metal", "opengl", "gpu")  # arch names; backend.ARCHES: those the backend has
_current: str | None = None


def init(arch: str = "cpu", cpu_threads: int | None = None) -> None:
    """Initialise Taichi once with float64 fields on `arch`; a later call with the same arch is a no-op.

    cpu_threads: the size of Taichi's CPU thread pool (default: every core); a study's worker
    processes use 1 each, so that N workers keep N cores busy. An arch the backend lacks or cannot start,
    or one whose kernels have no 64-bit floats (what "gpu" gives without CUDA: Vulkan, Metal, OpenGL), is a
    PneumaInputError."""
    global _current
    if arch not in ARCHES:
        raise PneumaInputError(f"arch = {arch!r} is not one of {', '.join(ARCHES)}")
    if _current == arch:
        return
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
    if chosen not in (ti.x64, ti.arm64, ti.cuda):  # the backends whose kernels have 64-bit floats
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
