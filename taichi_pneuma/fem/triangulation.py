"""Shewchuk's Triangle through whichever Python binding is installed.

Two bindings run the same C code (Triangle 1.6): `triangle` (wheels for Python <= 3.13 on Linux x86_64,
macOS arm64, Windows) and `meshpy` (its meshpy.triangle; wheels for Python 3.10-3.15 on Linux x86_64
and aarch64, macOS, Windows). Both are called with the same switches, Triangle's 'Qz' (quiet, zero-based
numbering) followed by the caller's, so they return the same mesh, vertex for vertex, once each
triangle's corners start at its smallest vertex number (tests/test_triangulation.py compares them where
both are installed). `triangle` is used when it is installed, else `meshpy`; PNEUMA_TRIANGLE=triangle|meshpy
forces one.
"""

from __future__ import annotations

import importlib.util
import os
import pickle
import sys
import warnings

import numpy as np

BINDINGS = ("triangle", "meshpy")
CHOICE_VARIABLE = "PNEUMA_TRIANGLE"


def installed() -> tuple[str, ...]:
    """The bindings installed here, in order of preference."""
    return tuple(name for name in BINDINGS if importlib.util.find_spec(name) is not None)


def default_binding() -> str:
    """PNEUMA_TRIANGLE if set, else the first installed binding."""
    forced = os.environ.get(CHOICE_VARIABLE, "")
    if forced:
        if forced not in BINDINGS:
            raise ImportError(f"{CHOICE_VARIABLE}={forced!r} is not one of {', '.join(BINDINGS)}")
        return forced
    found = installed()
    if not found:
        raise ImportError("no Triangle binding is installed: pip install triangle (Python <= 3.13) or pip install meshpy")
    return found[0]


def triangulate(pslg: dict, flags: str, binding: str | None = None) -> dict:
    """Triangle's triangulation of a planar straight-line graph with switches `flags` ('p', 'pqa0.01', ...).

    pslg: 'vertices' (n, 2), 'segments' (s, 2) and optionally 'segment_markers' (s,) and 'holes' (h, 2).
    Returns 'vertices' (N, 2) float64, 'triangles' (M, 3), 'segments' (S, 2) and 'segment_markers' (S,; empty
    unless the pslg has them) as int64. Triangle's failure (it runs out of precision) is a RuntimeError on
    either binding, as in the `triangle` package."""
    return (_with_triangle if (binding or default_binding()) == "triangle" else _with_meshpy)(pslg, flags)


def _with_triangle(pslg: dict, flags: str) -> dict:
    import triangle

    out = triangle.triangulate(pslg, flags)  # it prefixes 'Qz' itself
    return _normalised(out.get("vertices", ()), out.get("triangles", ()), out.get("segments", ()),
                       out.get("segment_markers", ()) if "segment_markers" in pslg else ())


def _with_meshpy(pslg: dict, flags: str) -> dict:
    """meshpy's Triangle ends the process (C exit) where the `triangle` package raises, when refinement runs
    out of precision: on Linux a refining call ('q' or 'a') runs in a forked child, whose exit becomes a
    RuntimeError. (A plain 'p' triangulation adds no points and cannot run out of precision.)"""
    if sys.platform == "linux" and ("q" in flags or "a" in flags):
        return _in_child(_meshpy_triangulate, pslg, flags)
    return _meshpy_triangulate(pslg, flags)


def _in_child(function, *args):
    """function(*args), computed in a forked child process and sent back through a pipe; RuntimeError if the
    child ends without sending it."""
    read_end, write_end = os.pipe()
    with warnings.catch_warnings():  # Python >= 3.12 warns on forking a process with threads (the kernels' pool)
        warnings.simplefilter("ignore", DeprecationWarning)
        pid = os.fork()
    if pid == 0:  # the child: send the result, then leave without running the parent's exit handlers
        os.close(read_end)
        try:
            with os.fdopen(write_end, "wb") as pipe:
                pipe.write(pickle.dumps(function(*args)))
        finally:
            os._exit(0)
    os.close(write_end)
    with os.fdopen(read_end, "rb") as pipe:
        sent = pipe.read()
    _, status = os.waitpid(pid, 0)
    if status != 0 or not sent:
        raise RuntimeError(f"Triangle ended its process (exit status {os.waitstatus_to_exitcode(status)})")
    return pickle.loads(sent)


def _meshpy_triangulate(pslg: dict, flags: str) -> dict:
    from meshpy import _internals
    from meshpy.triangle import MeshInfo

    given, out = MeshInfo(), MeshInfo()
    given.set_points(np.asarray(pslg["vertices"], dtype=np.float64))
    markers = pslg.get("segment_markers")
    given.set_facets(np.asarray(pslg["segments"]).tolist(), None if markers is None else np.asarray(markers).tolist())
    if "holes" in pslg:
        given.set_holes(np.asarray(pslg["holes"], dtype=np.float64).tolist())
    _internals.triangulate("Qz" + flags, given, out, MeshInfo(), None)
    return _normalised(out.points, out.elements, out.facets, out.facet_markers if markers is not None else ())


def _normalised(vertices, triangles, segments, markers) -> dict:
    """The output as arrays, each triangle's corners rotated to start at its smallest vertex number: the
    bindings' builds of Triangle may start a triangle at another of its corners (the same triangle, the
    same orientation), which would change the order of floating-point sums over its corners."""
    triangles = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    first = np.argmin(triangles, axis=1)
    triangles = np.take_along_axis(triangles, (first[:, None] + np.arange(3)) % 3, axis=1)
    return {"vertices": np.asarray(vertices, dtype=np.float64).reshape(-1, 2),
            "triangles": triangles,
            "segments": np.asarray(segments, dtype=np.int64).reshape(-1, 2),
            "segment_markers": np.asarray(markers, dtype=np.int64).ravel()}
