"""The single place where Taichi is initialised (float64, the caller's backend, offline kernel cache).

Taichi itself is imported by init(), so that importing this module (the apps' --help does) stays cheap.
"""

from __future__ import annotations

from .errors import PneumaInputError

ARCHES = ("cpu", "cuda", "vulkan", "metal", "opengl", "gpu")  # Taichi's backends by their attribute names
_current: str | None = None


def init(arch: str = "cpu", cpu_threads: int | None = None) -> None:
    """Initialise Taichi once with float64 fields on `arch`; a later call with the same arch is a no-op.

    cpu_threads: the size of Taichi's CPU thread pool (default: every core); a study's worker
    processes use 1 each, so that N workers keep N cores busy."""
    global _current
    if arch not in ARCHES:
        raise PneumaInputError(f"arch = {arch!r} is not one of {', '.join(ARCHES)}")
    if _current == arch:
        return
    import taichi as ti

    threads = {} if cpu_threads is None else {"cpu_max_num_threads": cpu_threads}
    ti.init(arch=getattr(ti, arch), default_fp=ti.f64, offline_cache=True, log_level=ti.WARN, **threads)
    _current = arch


def current_arch() -> str | None:
    """The backend Taichi was initialised on (None before init)."""
    return _current


def ensure_initialised() -> None:
    """Initialise on the CPU if the caller has not chosen a backend yet."""
    if _current is None:
        init("cpu")
