"""Resource guards: a run whose size would exhaust memory or time is refused, in one line naming the
estimate, the limit and the command-line flag that raises it; before any work where an estimate can
tell, and by a budget the mesher and the terms keep to where it cannot.

Before meshing, the mesh size is estimated from a fit to Triangle's output for 'pq' meshes
(48 meshes: the shipped scenes and the reference beam, small and large chambers, 12 to 1800 outline
points, max_area 1e-4 to 0.1; the estimate lies between 0.95 and 1.54 times the real count):

    triangles ~ 1.6 (body area - chamber areas) / max_area + 3 (outline points),   vertices ~ triangles / 2 + points

and the memory from the measured peak of a solve, about BYTES_PER_TRIANGLE per triangle (3.9-4.1 kB
at 35k-114k triangles, CPU backend), plus the stored states: positions (and, with contact, contact
forces) of every step, 16 bytes per vertex each. Each uniform refinement multiplies the triangles by 4;
a quadratic triangle counts as 4 linear ones (it has as many nodes, and a Hessian block 4 times larger).
A 3D geometry (dim = 3) gives its own size_estimate() (tetrahedra, nodes), counted against the same limit as
elements: a linear tetrahedron one, a quadratic one 8 (its Hessian block is 6.25 times a linear one's, and its
measured memory 6.2 times). The memory estimate is BYTES_PER_TETRAHEDRON per linear tetrahedron: the peak RSS
of a Newton ramp above the process's before the mesh, 11.9 kB per tetrahedron for 195k linear tetrahedra
(2.5 GB) and 74 kB per quadratic one for 50k (3.9 GB), CG with multigrid, whose memory grows linearly (the
peak is the Hessian pattern's construction, 144 (row, column) pairs per linear tetrahedron, 900 per quadratic
one; benchmarks/scale_3d.py). So 200k linear tetrahedra pass the default limit, and 50k quadratic ones need
--max-triangles 410000 (a sparse Cholesky factor instead grows as n^(4/3): the direct backends need more).
Self-contact holds a pair per (wall node, wall edge not incident to it): k (k - 2) for a wall of k nodes,
quadratic in the wall; a pair costs about BYTES_PER_PAIR (its indices, its 36-entry Hessian block and
the assembled matrix's share: 2.5-2.7 kB measured at 0.25M-4M pairs), counted as BYTES_PER_PAIR /
BYTES_PER_TRIANGLE triangles.

The estimate cannot see what quality meshing does to thin features: a strip of width w and length l
needs about l / w triangles across any max_area (Triangle's minimum angle forces triangles as small as
the strip is wide). So the mesher runs under a budget (budget(), set by the commands for their run):
Triangle is given at most element_cap() Steiner points (its S switch) and stops there, and a mesh
that reached the cap, or has more triangles than the budget, is refused (check_mesh); the terms check
what they allocate against it too (check_pairs, before self-contact allocates its pairs). A 3D mesher
meets the same budget through element_cap(weight) and check_mesh. Without a budget (library use that
sets none) nothing is capped.

A mesh file is read under a memory bound (memory_bound, read_allowance: READ_BYTES plus
READ_BYTES_PER_FILE_BYTE per byte of the file; on Linux, by the address-space limit): a small file whose arrays
are compressed, or whose node numbers are sparse, cannot claim gigabytes before any check sees it.
"""

from __future__ import annotations

import os
import resource
from contextlib import contextmanager
from contextvars import ContextVar

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

_budget: ContextVar[int | None] = ContextVar("triangle budget", default=None)


@contextmanager
def budget(max_triangles: int = MAX_TRIANGLES):
    """Mesh and allocate under a budget of max_triangles linear triangles (their worth of memory) in the block."""
    token = _budget.set(int(max_triangles))
    try:
        yield
    finally:
        _budget.reset(token)


def element_cap(weight: float = 1.0) -> int | None:
    """The most elements (or points) a mesher may make in the active budget, each counting `weight` linear
    triangles (a quadratic triangle 4, each uniform refinement 4 times more); None without a budget."""
    limit = _budget.get()
    return None if limit is None else max(1, int(limit // weight))


def refusal(what: str, triangles: float, limit: int | None) -> str:
    return (f"{what}: about {triangles:.3g} triangles' worth, {BYTES_PER_TRIANGLE * triangles / 1e9:.3g} GB; the "
            f"limit is {limit} triangles (--max-triangles raises it)")


def check_mesh(elements: int, weight: float, how: str, stopped_at: int | None = None) -> None:
    """Refuse (in the active budget) a mesh whose elements, each worth `weight` triangles, pass the budget,
    or that its mesher (how: "Triangle") stopped at its cap of stopped_at points before finishing."""
    limit = _budget.get()
    if limit is None:
        return
    require(stopped_at is None, f"the mesh needs more than {limit} triangles: {how} stopped at its cap of "
                                f"{stopped_at} added points (thin features or narrow gaps need triangles as small "
                                f"as they are wide, whatever max_area is); the limit is {limit} triangles "
                                f"(--max-triangles raises it)")
    require(elements * weight <= limit, refusal(f"the mesh has {elements} elements", elements * weight, limit))


def check_pairs(pairs: int, what: str) -> None:
    """Refuse (in the active budget) a term about to allocate `pairs` contact pairs past the budget's memory."""
    limit = _budget.get()
    worth = pairs * BYTES_PER_PAIR / BYTES_PER_TRIANGLE
    require(limit is None or worth <= limit, refusal(f"{what} would hold {pairs} point-edge pairs", worth, limit))


def wall_pairs(points: list[int]) -> int:
    """Point-edge pairs of closed walls of these node counts: each node with each edge not incident to it."""
    return sum(k * (k - 2) for k in points)


def check_scene(scene, max_triangles: int = MAX_TRIANGLES, max_increments: int = MAX_INCREMENTS) -> None:
    """Refuse (PneumaInputError) a scene whose estimated mesh (its terms' pairs included) or increment count
    is past the limits."""
    geometry = scene.geometry
    if getattr(geometry, "dim", 2) == 3:
        check_solid(scene, max_triangles)
    else:
        check_planar(scene, max_triangles)
    check_increments(scene.increments, max_increments)


def check_increments(increments: int, limit: int = MAX_INCREMENTS, raised_by: str = "--max-increments") -> None:
    """Refuse a schedule of more than `limit` increments (raised_by: what raises the limit, named in the message)."""
    count = increments if increments < 10**12 else f"about 10^{len(str(increments)) - 1}"  # not 401 digits
    require(increments <= limit, f"the schedule has {count} increments; the limit is {limit} ({raised_by} raises it)")


def check_solid(scene, max_elements: int) -> None:
    """A 3D scene: its geometry's (tetrahedra, nodes) estimate, a quadratic tetrahedron counted 8 times (module
    docstring)."""
    geometry = scene.geometry
    tetrahedra, nodes = geometry.size_estimate()
    linear = tetrahedra * (8 if geometry.order == 2 else 1)
    per_step = 2 if any(e.contact for e in scene.effects) else 1
    memory = BYTES_PER_TETRAHEDRON * linear + 24 * per_step * nodes * (scene.increments + 1)
    quadratic = " quadratic tetrahedra, counted 8 times" if geometry.order == 2 else " tetrahedra"
    require(linear <= max_elements, f"the mesh has {tetrahedra}{quadratic} and needs about {memory / 1e9:.3g} GB; "
                                    f"the limit is {max_elements} elements (--max-triangles raises it)")


def check_planar(scene, max_triangles: int) -> None:
    """A 2D scene: the triangles estimated from its outlines and its terms' pairs (module docstring)."""
    from .fem.geometry import signed_area

    geometry = scene.geometry
    loops = [geometry.body.polygon()] + [shape.polygon() for _, shape in geometry.chambers]
    area = abs(signed_area(loops[0])) - sum(abs(signed_area(loop)) for loop in loops[1:])
    points = sum(len(loop) for loop in loops)
    nodes_per_point = 2 ** geometry.refinements * geometry.order
    walls = [len(loop) * nodes_per_point for loop in loops[1:]]
    pairs = sum(effect.pairs(walls) for effect in scene.effects)
    triangles = (1.6 * area / geometry.max_area + 3 * points) * 4 ** geometry.refinements
    linear = triangles * (4 if geometry.order == 2 else 1)
    worth = linear + pairs * BYTES_PER_PAIR / BYTES_PER_TRIANGLE
    vertices = linear / 2 + points
    per_step = 2 if any(e.contact for e in scene.effects) else 1
    memory = BYTES_PER_TRIANGLE * worth + 16 * per_step * vertices * (scene.increments + 1)
    quadratic = " quadratic triangles, counted 4 times" if geometry.order == 2 else " triangles"
    contact = f" and {pairs} self-contact pairs (walls of {max(walls)} nodes)" if pairs else ""
    require(worth <= max_triangles,
            f"the mesh would have about {triangles:.3g}{quadratic} (meshed area {area:.4g} / max_area "
            f"{geometry.max_area:.3g}, {points} outline points){contact} and need about {memory / 1e9:.3g} GB; "
            f"the limit is {max_triangles} triangles (--max-triangles raises it)")


def check_frame(width: int, height: int, max_pixels: int = MAX_FRAME_PIXELS, what: str = "--size",
                raised_by: str = "--max-frame-pixels") -> None:
    """Refuse a video frame size of more than max_pixels pixels (what: the size's name in the message; raised_by:
    what raises the limit)."""
    require(width * height <= max_pixels,
            f"{what} {width}x{height} is {width * height} pixels per frame; the limit is {max_pixels} "
            f"({raised_by} raises it)")


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
