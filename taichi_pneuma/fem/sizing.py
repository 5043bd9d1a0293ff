"""A scene's mesh size and memory, estimated before meshing, and its refusal past the limits (limits.py).

A 2D geometry's triangles are estimated from a fit to Triangle's output for 'pq' meshes (48 meshes: the shipped
scenes and the reference beam, small and large chambers, 12 to 1800 outline points, max_area 1e-4 to 0.1; the
estimate lies between 0.95 and 1.54 times the real count):

    triangles ~ 1.6 (body area - chamber areas) / max_area + 3 (outline points),   vertices ~ triangles / 2 + points

each uniform refinement multiplying them by 4, a quadratic triangle counted as 4 linear ones; self-contact's pairs
(k (k - 2) for a wall of k nodes) are counted as BYTES_PER_PAIR / BYTES_PER_TRIANGLE triangles. A 3D geometry gives
its own size_estimate() (tetrahedra, nodes), a quadratic tetrahedron counted 8 times. The memory adds the stored
states: positions (and, with contact, contact forces) of every step, 8 bytes per coordinate each. The figures behind
the byte counts: docs/performance.md, "The resource limits".
"""

from __future__ import annotations

from .. import limits
from ..errors import require
from .polygons import signed_area


def check_scene(
    scene,
    max_triangles: int = limits.MAX_TRIANGLES,
    max_increments: int = limits.MAX_INCREMENTS,
    max_fibers: int = limits.MAX_FIBERS,
    max_obstacles: int = limits.MAX_OBSTACLES,
) -> None:
    """Refuse (PneumaInputError) a scene whose fibre or obstacle count, estimated mesh (its terms' pairs included) or
    increment count is past the limits."""
    limits.check_count(len(scene.fibers), "[[fibers]] tables", max_fibers, "--max-fibers")
    limits.check_count(len(scene.obstacles), "[[obstacles]] tables", max_obstacles, "--max-obstacles")
    geometry = scene.geometry
    if geometry.dim == 3:
        check_solid(scene, max_triangles)
    else:
        check_planar(scene, max_triangles)
    limits.check_increments(scene.increments, max_increments)


def check_solid(scene, max_elements: int) -> None:
    """A 3D scene: its geometry's (tetrahedra, nodes) estimate, a quadratic tetrahedron counted 8 times (module
    docstring)."""
    geometry = scene.geometry
    tetrahedra, nodes = geometry.size_estimate()
    family = geometry.family
    linear = tetrahedra * family.weight
    per_step = 2 if any(e.contact for e in scene.effects) else 1
    memory = limits.BYTES_PER_TETRAHEDRON * linear + 24 * per_step * nodes * (scene.increments + 1)
    quadratic = f" {family.words}" + (f", counted {family.weight} times" if family.weight > 1 else "")
    require(
        linear <= max_elements,
        f"the mesh has {tetrahedra}{quadratic} and needs about {memory / 1e9:.3g} GB; "
        f"the limit is {max_elements} elements (--max-triangles raises it)",
    )


def check_planar(scene, max_triangles: int) -> None:
    """A 2D scene: the triangles estimated from its outlines and its terms' pairs (module docstring)."""
    geometry = scene.geometry
    loops = [geometry.body.polygon()] + [shape.polygon() for _, shape in geometry.chambers]
    area = abs(signed_area(loops[0])) - sum(abs(signed_area(loop)) for loop in loops[1:])
    points = sum(len(loop) for loop in loops)
    nodes_per_point = 2**geometry.refinements * geometry.order
    walls = [len(loop) * nodes_per_point for loop in loops[1:]]
    pairs = sum(effect.pairs(walls) for effect in scene.effects)
    triangles = (1.6 * area / geometry.max_area + 3 * points) * 4**geometry.refinements
    family = geometry.family
    linear = triangles * family.weight
    worth = linear + pairs * limits.BYTES_PER_PAIR / limits.BYTES_PER_TRIANGLE
    vertices = linear / 2 + points
    per_step = 2 if any(e.contact for e in scene.effects) else 1
    memory = limits.BYTES_PER_TRIANGLE * worth + 16 * per_step * vertices * (scene.increments + 1)
    quadratic = f" {family.words}" + (f", counted {family.weight} times" if family.weight > 1 else "")
    contact = f" and {pairs} self-contact pairs (walls of {max(walls)} nodes)" if pairs else ""
    require(
        worth <= max_triangles,
        f"the mesh would have about {triangles:.3g}{quadratic} (meshed area {area:.4g} / max_area "
        f"{geometry.max_area:.3g}, {points} outline points){contact} and need about {memory / 1e9:.3g} GB; "
        f"the limit is {max_triangles} triangles (--max-triangles raises it)",
    )
