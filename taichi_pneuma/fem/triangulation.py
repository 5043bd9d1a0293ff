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

import numpy as np

from ..environment import TRIANGLE_BINDINGS as BINDINGS
from ..errors import require

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
        raise ImportError(
            "no Triangle binding is installed: pip install triangle (Python <= 3.13) or pip install meshpy"
        )
    return found[0]


def triangulate(pslg: dict, flags: str, binding: str | None = None) -> dict:
    """Triangle's triangulation of a planar straight-line graph with switches `flags` ('p', 'pqa0.01', ...).

    pslg: 'vertices' (n, 2), 'segments' (s, 2) and optionally 'segment_markers' (s,) and 'holes' (h, 2).
    Returns 'vertices' (N, 2) float64, 'triangles' (M, 3), 'segments' (S, 2) and 'segment_markers' (S,; empty
    unless the pslg has them) as int64. Triangle's failure (it runs out of precision) is a RuntimeError on
    either binding, as in the `triangle` package."""
    return (_with_triangle if (binding or default_binding()) == "triangle" else _with_meshpy)(pslg, flags)


def triangulate_or_refuse(pslg: dict, flags: str) -> dict:
    """triangulate, with its failure (RuntimeError, or no triangle made) a PneumaInputError."""
    try:
        out = triangulate(pslg, flags)
    except RuntimeError:
        out = {}
    require(
        len(out.get("triangles", ())) > 0,
        "Triangle could not mesh the geometry (it ran out of floating-point "
        "precision: features too small for the body's size?)",
    )
    return out


def _with_triangle(pslg: dict, flags: str) -> dict:
    import triangle

    out = triangle.triangulate(pslg, flags)  # it prefixes 'Qz' itself
    return _normalised(
        out.get("vertices", ()),
        out.get("triangles", ()),
        out.get("segments", ()),
        out.get("segment_markers", ()) if "segment_markers" in pslg else (),
    )


def _with_meshpy(pslg: dict, flags: str) -> dict:
    """meshpy's Triangle ends the process (C exit) where the `triangle` package raises, when refinement runs
    out of precision (a geometry whose features are ~1e-16 of its size): no error can be caught then. A forked
    child would catch it, but forking a process whose kernel threads run can deadlock the child, so it is
    not done; `limits` and the geometry checks refuse such geometries before they reach Triangle."""
    return _meshpy_triangulate(pslg, flags)


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
    return {
        "vertices": np.asarray(vertices, dtype=np.float64).reshape(-1, 2),
        "triangles": triangles,
        "segments": np.asarray(segments, dtype=np.int64).reshape(-1, 2),
        "segment_markers": np.asarray(markers, dtype=np.int64).ravel(),
    }
