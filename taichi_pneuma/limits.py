"""Resource guards: a run whose size would exhaust memory or time is refused before any work, in one
line naming the estimate, the limit and the command-line flag that raises it.

The mesh size is estimated before meshing, from a fit to Triangle's output for 'pq' meshes
(48 meshes: the shipped scenes and the reference beam, small and large chambers, 12 to 1800 outline
points, max_area 1e-4 to 0.1; the estimate lies between 0.95 and 1.54 times the real count):

    triangles ~ 1.6 (body area - chamber areas) / max_area + 3 (outline points),   vertices ~ triangles / 2 + points

and the memory from the measured peak of a solve, about BYTES_PER_TRIANGLE per triangle (3.9-4.1 kB
at 35k-114k triangles, CPU backend), plus the stored states: positions (and, with contact, contact
forces) of every step, 16 bytes per vertex each. Each uniform refinement multiplies the triangles by 4;
a quadratic triangle counts as 4 linear ones (it has as many nodes, and a Hessian block 4 times larger).
A 3D geometry (dim = 3) gives its own size_estimate() (tetrahedra, nodes), counted against the same limit.
"""

from __future__ import annotations

from .errors import require
from .fem.geometry import signed_area

MAX_TRIANGLES = 200_000
MAX_INCREMENTS = 2_000
MAX_FRAME_PIXELS = 3840 * 2160
BYTES_PER_TRIANGLE = 4_000
BYTES_PER_TETRAHEDRON = 6_000


def check_scene(scene, max_triangles: int = MAX_TRIANGLES, max_increments: int = MAX_INCREMENTS) -> None:
    """Refuse (PneumaInputError) a scene whose estimated mesh or increment count is past the limits."""
    geometry = scene.geometry
    if getattr(geometry, "dim", 2) == 3:
        check_solid(scene, max_triangles)
    else:
        check_planar(scene, max_triangles)
    require(scene.increments <= max_increments,
            f"the schedule has {scene.increments} increments; the limit is {max_increments} "
            f"(--max-increments raises it)")


def check_solid(scene, max_elements: int) -> None:
    """A 3D scene: its geometry's (tetrahedra, nodes) estimate, a quadratic tetrahedron counted 8 times (8 times
    a linear one's Hessian block, 9 times its nodes)."""
    geometry = scene.geometry
    tetrahedra, nodes = geometry.size_estimate()
    linear = tetrahedra * (8 if geometry.order == 2 else 1)
    per_step = 2 if any(e.contact for e in scene.effects) else 1
    memory = BYTES_PER_TETRAHEDRON * linear + 24 * per_step * nodes * (scene.increments + 1)
    quadratic = " quadratic tetrahedra, counted 8 times" if geometry.order == 2 else " tetrahedra"
    require(linear <= max_elements, f"the mesh has {tetrahedra}{quadratic} and needs about {memory / 1e9:.3g} GB; "
                                    f"the limit is {max_elements} elements (--max-triangles raises it)")


def check_planar(scene, max_triangles: int) -> None:
    """A 2D scene: the triangles estimated from its outlines (module docstring)."""
    geometry = scene.geometry
    loops = [geometry.body.polygon()] + [shape.polygon() for _, shape in geometry.chambers]
    area = abs(signed_area(loops[0])) - sum(abs(signed_area(loop)) for loop in loops[1:])
    points = sum(len(loop) for loop in loops)
    triangles = (1.6 * area / geometry.max_area + 3 * points) * 4 ** geometry.refinements
    linear = triangles * (4 if geometry.order == 2 else 1)
    vertices = linear / 2 + points
    per_step = 2 if any(e.contact for e in scene.effects) else 1
    memory = BYTES_PER_TRIANGLE * linear + 16 * per_step * vertices * (scene.increments + 1)
    quadratic = " quadratic triangles, counted 4 times" if geometry.order == 2 else " triangles"
    require(linear <= max_triangles,
            f"the mesh would have about {triangles:.3g}{quadratic} (meshed area {area:.4g} / max_area "
            f"{geometry.max_area:.3g}, {points} outline points) and need about {memory / 1e9:.3g} GB; the limit is "
            f"{max_triangles} triangles (--max-triangles raises it)")


def check_frame(width: int, height: int, max_pixels: int = MAX_FRAME_PIXELS) -> None:
    """Refuse a video frame size of more than max_pixels pixels."""
    require(width * height <= max_pixels,
            f"--size {width}x{height} is {width * height} pixels per frame; the limit is {max_pixels} "
            f"(--max-frame-pixels raises it)")
