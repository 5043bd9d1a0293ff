"""A scene's mesh size and memory, estimated before meshing, and its refusal past the limits (limits.py).

Each geometry estimates its own mesh (Body.size_estimate: elements, nodes, its walls' node counts). A 2D
geometry's triangles are estimated from a fit to Triangle's output for 'pq' meshes (48 meshes: the shipped
scenes and the reference beam, small and large chambers, 12 to 1800 outline points, max_area 1e-4 to 0.1; the
estimate lies between 0.95 and 1.54 times the real count):

    triangles ~ 1.6 (body area - chamber areas) / max_area + 3 (outline points),   vertices ~ triangles / 2 + points

each uniform refinement multiplying them by 4, a quadratic triangle counted as 4 linear ones; self-contact's pairs
(k (k - 2) for a wall of k nodes) are counted as BYTES_PER_PAIR / BYTES_PER_TRIANGLE triangles. A 3D geometry from
shapes estimates its tetrahedra from its volume and edge lengths, a mesh file counts them; a quadratic tetrahedron
counts 8 times. The memory adds the stored states: positions (and, with contact, contact forces) of every step, 8
bytes per coordinate each. The figures behind the byte counts: docs/performance.md, "The resource limits".
"""

from __future__ import annotations

from .. import limits
from ..errors import require

# per dimension: the cells' name, the limit's unit (linear elements' worth) and a linear element's bytes
CELLS = {
    2: ("triangles", "triangles", limits.BYTES_PER_TRIANGLE),
    3: ("tetrahedra", "elements", limits.BYTES_PER_TETRAHEDRON),
}


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
    check_mesh_size(scene, max_triangles)
    limits.check_increments(scene.increments, max_increments)


def check_mesh_size(scene, max_elements: int) -> None:
    """A surface body's facets against the limit first (Body.check_facets); then the geometry's size estimate
    (Body.size_estimate), each element counted as its family's weight in linear elements and a wall's self-contact
    pairs (2D) as BYTES_PER_PAIR / BYTES_PER_TRIANGLE triangles; the memory adds the stored states (module
    docstring)."""
    geometry = scene.geometry
    geometry.check_facets(limits.Budget(max_elements))
    estimate = geometry.size_estimate()
    family = geometry.family
    linear = estimate.elements * family.weight
    pairs = sum(effect.pairs(list(estimate.walls)) for effect in scene.effects) if estimate.walls else 0
    worth = linear + pairs * limits.BYTES_PER_PAIR / limits.BYTES_PER_TRIANGLE
    per_step = 2 if any(e.contact for e in scene.effects) else 1
    cells, unit, per_element = CELLS[geometry.dim]
    memory = per_element * worth + 8 * geometry.dim * per_step * estimate.nodes * (scene.increments + 1)
    counted = f" {family.adjective} {cells}, counted {family.weight} times" if family.order > 1 else f" {cells}"
    basis = f" ({estimate.basis})" if estimate.basis else ""
    contact = f" and {pairs} self-contact pairs (walls of {max(estimate.walls)} nodes)" if pairs else ""
    require(
        worth <= max_elements,
        f"the mesh would have about {estimate.elements:.3g}{counted}{basis}{contact} and need about "
        f"{memory / 1e9:.3g} GB; the limit is {max_elements} {unit} (--max-triangles raises it)",
    )
