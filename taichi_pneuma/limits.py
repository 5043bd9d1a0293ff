"""Resource guards: a run whose size would exhaust memory or time is refused, in one line naming the
estimate, the limit and the command-line flag that raises it; before any work where an estimate can tell
(fem/sizing.py estimates a scene's mesh), and by a budget the mesher and the terms keep to where it cannot.

This module holds the limits, the measured costs they are counted in (BYTES_PER_TRIANGLE, BYTES_PER_TETRAHEDRON,
BYTES_PER_PAIR, BYTES_PER_FIBER_ENTRY, BYTES_PER_FACET, READ_BYTES...: where each figure comes from is on the
performance page, docs/performance.md, "The resource limits"), the budget (Budget: element_cap() for a mesher,
check_mesh(), check_pairs(), check_entries() and check_facets() for what was made or is about to be; passed
explicitly, Scene.build(budget) -> mesh(budget), terms(..., budget)) and the plain checks of counts (increments,
fibres, obstacles, frame pixels: check_count) and of a file reader's memory (memory_bound, read_allowance). Budget()
(library use that sets none) caps nothing.
"""

from __future__ import annotations

import os
import resource
from contextlib import contextmanager
from dataclasses import dataclass

from .errors import require

MAX_TRIANGLES = 200_000
MAX_INCREMENTS = 2_000
MAX_FRAME_PIXELS = 3840 * 2160
BYTES_PER_TRIANGLE = 4_000
BYTES_PER_PAIR = 2_500
READ_BYTES = 256_000_000  # memory a mesh file's reader may take, beyond READ_BYTES_PER_FILE_BYTE per byte of the file
READ_BYTES_PER_FILE_BYTE = 16  # meshio's gmsh 2.2 reader peaks at 7.2 bytes per file byte (a 10.9 MB file: 78 MB)
MAX_RUNS = 100_000  # runs of one design study (apps/sweep.py --max-runs)
BYTES_PER_TETRAHEDRON = 12_000  # measured, see the module docstring
# A fibre's Hessian entry (a cord segment's dense 2 (d + 1) d block, 576 entries in 3D): the peak the solver reaches
# on one, measured with tracemalloc over Fiber.terms, the Newton solver's FixedPattern of the model's pattern and one
# assembled matrix (crossed braids of 4, 16 and 64 strands on a 200-node box: 82.9, 81.8 and 81.3 bytes an entry;
# the resident size grew by 81 bytes an entry from 4 to 64 strands): the term's int64 rows and columns, the model's
# concatenated copy, FixedPattern's int64 keys and np.unique's sorted copy, order and inverse. 96: that, rounded up.
BYTES_PER_FIBER_ENTRY = 96
# fibres and obstacles a scene may hold (--max-fibers, --max-obstacles): each is a term of its own, with its own
# kernel launches every Newton iteration. Each cap is the count that makes the shipped fiber_bending_3d (6,756 linear
# tetrahedra, ~0.4 s a Newton iteration) run about twice as long: 100 more fibres took it from 0.35-0.45 to 0.81 s an
# iteration; obstacles cost ~1.0 ms each an iteration (100: 0.44 s, 1000: 1.42 s), so ~440 double it
# (docs/performance.md, "The resource limits")
MAX_FIBERS = 100
MAX_OBSTACLES = 400
# a surface file's facet (a triangle of an STL; fem/surface_import.py) until gmsh has remeshed it: the peak resident
# size of reading, repairing, classifying, reparametrising and meshing spheres of 43k, 173k and 691k facets at a
# coarse size, above the process's before, was 1.70, 1.45 and 1.18 kB a facet (gmsh took 40-85 us a facet); 2 kB,
# half a triangle's worth: the default limit passes 400,000 facets
BYTES_PER_FACET = 2_000


def refusal(what: str, triangles: float, limit: int | None) -> str:
    return (
        f"{what}: about {triangles:.3g} triangles' worth, {BYTES_PER_TRIANGLE * triangles / 1e9:.3g} GB; the "
        f"limit is {limit} triangles (--max-triangles raises it)"
    )


@dataclass(frozen=True)
class Budget:
    """What a mesher may make and a term allocate: `triangles` linear triangles (their worth of memory), or
    None: nothing capped (Budget(), the library's default; the commands give Budget(--max-triangles)).
    Scene.build hands it to the geometry's mesh() and to each effect's terms()."""

    triangles: int | None = None

    def element_cap(self, weight: float = 1.0) -> int | None:
        """The most elements (or points) a mesher may make, each counting `weight` linear triangles (a quadratic
        triangle 4, each uniform refinement 4 times more); None without a limit."""
        return None if self.triangles is None else max(1, int(self.triangles // weight))

    def check_mesh(self, elements: int, weight: float, how: str, stopped_at: int | None = None) -> None:
        """Refuse a mesh whose elements, each worth `weight` triangles, pass the budget, or that its mesher
        (how: "Triangle") stopped at its cap of stopped_at points before finishing."""
        limit = self.triangles
        if limit is None:
            return
        require(
            stopped_at is None,
            f"the mesh needs more than {limit} triangles: {how} stopped at its cap of "
            f"{stopped_at} added points (thin features or narrow gaps need triangles as "
            f"small as they are wide, whatever max_area is); the limit is {limit} triangles "
            f"(--max-triangles raises it)",
        )
        require(elements * weight <= limit, refusal(f"the mesh has {elements} elements", elements * weight, limit))

    def check_pairs(self, pairs: int, what: str) -> None:
        """Refuse a term about to allocate `pairs` contact pairs past the budget's memory."""
        limit = self.triangles
        worth = pairs * BYTES_PER_PAIR / BYTES_PER_TRIANGLE
        require(limit is None or worth <= limit, refusal(f"{what} would hold {pairs} point-edge pairs", worth, limit))

    def check_entries(self, entries: int, what: str) -> None:
        """Refuse a term about to allocate `entries` Hessian entries (a fibre's cord segments' blocks) past the
        budget's memory, BYTES_PER_FIBER_ENTRY each."""
        limit = self.triangles
        worth = entries * BYTES_PER_FIBER_ENTRY / BYTES_PER_TRIANGLE
        require(limit is None or worth <= limit, refusal(f"{what} would hold {entries} Hessian entries", worth, limit))

    def check_facets(self, facets: int, what: str) -> None:
        """Refuse a surface (what: its files) of `facets` triangles past the budget's memory before gmsh reads it,
        BYTES_PER_FACET each."""
        limit = self.triangles
        worth = facets * BYTES_PER_FACET / BYTES_PER_TRIANGLE
        require(limit is None or worth <= limit, refusal(f"{what} has {facets} facets", worth, limit))


def wall_pairs(points: list[int]) -> int:
    """Point-edge pairs of closed walls of these node counts: each node with each edge not incident to it."""
    return sum(k * (k - 2) for k in points)


def check_count(count: int, what: str, limit: int, raised_by: str, holder: str = "the scene") -> None:
    """Refuse `holder` having more than `limit` of `what` (raised_by: what raises the limit, named in the message)."""
    shown = count if count < 10**12 else f"about 10^{len(str(count)) - 1}"  # not 401 digits
    require(count <= limit, f"{holder} has {shown} {what}; the limit is {limit} ({raised_by} raises it)")


def check_increments(increments: int, limit: int = MAX_INCREMENTS, raised_by: str = "--max-increments") -> None:
    """Refuse a schedule of more than `limit` increments."""
    check_count(increments, "increments", limit, raised_by, "the schedule")


def check_frame(
    width: int,
    height: int,
    max_pixels: int = MAX_FRAME_PIXELS,
    what: str = "--size",
    raised_by: str = "--max-frame-pixels",
) -> None:
    """Refuse a video frame size of more than max_pixels pixels (what: the size's name in the message; raised_by:
    what raises the limit)."""
    require(
        width * height <= max_pixels,
        f"{what} {width}x{height} is {width * height} pixels per frame; the limit is {max_pixels} "
        f"({raised_by} raises it)",
    )


def address_space() -> int | None:
    """This process's virtual memory size in bytes (Linux: /proc/self/statm), None where it cannot be read."""
    try:
        with open("/proc/self/statm") as f:
            return int(f.read().split()[0]) * os.sysconf("SC_PAGE_SIZE")
    except (OSError, ValueError, IndexError):
        return None


@contextmanager
def memory_bound(extra: int):
    """Allocations of more than `extra` bytes beyond the process's current virtual size fail (MemoryError) in the
    block: the address-space limit (RLIMIT_AS) is lowered to that for the block, then restored. Where the size
    cannot be read (not Linux) nothing is bounded. Only for code that runs alone (a file reader before the solve):
    every thread of the process is bounded meanwhile."""
    size = address_space()
    soft, hard = resource.getrlimit(resource.RLIMIT_AS)
    if size is None:
        yield
        return
    bound = size + extra
    for limit in (soft, hard):
        if limit != resource.RLIM_INFINITY:
            bound = min(bound, limit)
    resource.setrlimit(resource.RLIMIT_AS, (bound, hard))
    try:
        yield
    finally:
        resource.setrlimit(resource.RLIMIT_AS, (soft, hard))


def read_allowance(file_bytes: int) -> int:
    """The memory a reader of a file of file_bytes bytes may take: READ_BYTES + READ_BYTES_PER_FILE_BYTE per byte
    (meshio holds the text, its parsed numbers and the arrays at once; a compressed array or a sparse
    numbering can claim far more: a 234 KB VTU 2.4 GB, a gmsh file with one node numbered 400000000 1.6 GB)."""
    return READ_BYTES + READ_BYTES_PER_FILE_BYTE * file_bytes
