"""The gmsh mesher's disk cache (io/cache.py): the key of a mesh or of a solid's measures (gmsh's version and a hash
of the mesher's source files, MESHER_SOURCES, with everything that decides it), and the checks a cached entry passes
before it is used (shapes, dtypes, indices in range, positive tetrahedra).
"""

from __future__ import annotations

import functools
import hashlib
from pathlib import Path

import numpy as np

from ..errors import PneumaInputError
from ..io import cache
from .gmsh_session import gmsh_module

MESHER_SOURCES = (
    "gmsh_mesher.py",
    "gmsh_session.py",
    "gmsh_cache.py",
    "solids.py",
    "pneunet.py",
    "shapes.py",
    "polygons.py",
    "wall_thickness.py",
    "curving.py",
)  # the code a cached mesh depends on
CACHE_BYTES_PER_TET = 256  # a cached mesh's arrays take about 50 bytes per tetrahedron: a larger file is not read


@functools.cache  # a memo: the installed gmsh and this package's sources stay what the process loaded
def mesher_version() -> str | None:
    """gmsh's version and a hash of this mesher's source files (MESHER_SOURCES); None without gmsh."""
    import importlib.metadata  # here: a 2D run does not need it

    try:
        version = importlib.metadata.version("gmsh")
    except importlib.metadata.PackageNotFoundError:
        try:
            version = gmsh_module().__version__
        except PneumaInputError:
            return None
    sources = hashlib.sha256(b"".join(Path(__file__).with_name(name).read_bytes() for name in MESHER_SOURCES))
    return f"gmsh {version}, mesher {sources.hexdigest()}"


def cache_key(kind: str, *parts) -> cache.Key | None:
    """The cache entry of the parts (None when the cache is off, without gmsh, or for a part with no exact text)."""
    version = None if cache.directory() is None else mesher_version()
    return None if version is None else cache.key(kind, version, *parts)


def valid_measures(arrays: dict) -> bool:
    """A cached (volume, wall area): two finite positive doubles."""
    measures = arrays["measures"]
    return (
        measures.dtype == np.float64 and measures.shape == (2,) and bool(np.all(np.isfinite(measures) & (measures > 0)))
    )


def valid_mesh(arrays: dict, chambers: int, regions_count: int) -> bool:
    """Whether cached arrays are a SolidMesh of this solid: the arrays named and no other, each of its dtype and
    shape, finite vertices, node indices in range, tetrahedra positively oriented, region tags 0 to regions_count
    (the solid's chambers and regions counted)."""
    walls = [f"chamber{i}" for i in range(chambers)]
    named = {"vertices", "tets", "boundary", "regions", "measures", "curved_edges", "curved_points", *walls}
    if set(arrays) != named or not valid_measures(arrays):
        return False
    vertices, tets, regions = arrays["vertices"], arrays["tets"], arrays["regions"]
    edges, points = arrays["curved_edges"], arrays["curved_points"]
    if not (
        edges.dtype == np.int64
        and edges.shape == (len(points), 2)
        and points.dtype == np.float64
        and points.shape[1:] == (3,)
        and np.isfinite(points).all()
        and (edges.size == 0 or (edges.min() >= 0 and edges.max() < len(vertices)))
    ):
        return False
    faces = [arrays[name] for name in ["boundary", *walls]]
    if not (
        vertices.dtype == np.float64
        and vertices.ndim == 2
        and vertices.shape[1] == 3
        and len(vertices) >= 4
        and np.isfinite(vertices).all()
    ):
        return False
    shaped = [(tets, 4), *((f, 3) for f in faces)]
    if not all(a.dtype == np.int64 and a.ndim == 2 and a.shape[1] == k and len(a) > 0 for a, k in shaped):
        return False
    if not all(a.min() >= 0 and a.max() < len(vertices) for a, _ in shaped):
        return False
    if not (
        regions.dtype == np.int64
        and regions.shape == (len(tets),)
        and regions.min() >= 0
        and regions.max() <= regions_count
    ):
        return False
    x = vertices[tets]
    return bool(np.all(np.linalg.det(x[:, 1:] - x[:, :1]) > 0))
