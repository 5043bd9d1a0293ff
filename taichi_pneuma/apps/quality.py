"""The --quality presets, relative to the scene's own [mesh], so that a scene in any units (or none) has a coarser,
faster draft and a finer high of itself (on the reference beams, the meshes the accuracy studies measured): the
ladders and factors (QUALITY, QUALITY_3D, QUALITY_WALL, MESH_FILE_ORDER), a scene with its preset applied and the
line that says what the preset means for it (with_quality), and the preset's measured error where it was measured
(preset_note).
"""

from __future__ import annotations

import argparse

from ..fem.elements import FAMILIES
from ..fem.solid_geometry import SolidGeometry
from ..fem.surface_import import SurfaceGeometry
from ..io.units import AREA, LENGTH

# 2D: the rungs a preset lies above the scene's own on planar_preset's ladder, and the reference beam's mesh (its
# presets are QUALITY below; tests/test_cli.py checks the beam's defaults agree).
QUALITY_STEPS = {"draft": -1, "default": 0, "high": 1, "accurate": 2}
AREA_STEP = 0.005 / 0.0012  # the ladder's area ratio: the reference beam's draft max area over its own
REFERENCE_MESH = (0.0012, 1)  # the reference beam's (max area, order)
QUALITY_TOL = {"draft": 1e-4, "default": 1e-6, "high": 1e-6, "accurate": 1e-9}  # the Newton tolerance
# The 3D presets of a body meshed from shapes: (factor on the scene's tetrahedron edge length, which is also the
# new grading distance, factor on its edge length near the chambers (None: uniform at the new edge length), element
# order (None: the scene's own)), read off beam_3d_ellipsoid's tip against mesh size and grading (docs/3d.md, "3D
# presets": the error is near the chambers' thin walls), whose [mesh] (0.2, 0.1 near the chamber, quadratic) they
# turn into the measured (0.3, 0.3, linear), (0.3, 0.15), (0.3, 0.1) and (0.2, 0.08). A linear scene stays linear
# above draft:
# fiber_bending_3d's high made quadratic (13k nodes) found no equilibrium at 38 kPa (Newton stalled at 3.5e-6); and
# the grading runs over the new edge length (over 1.5 times the scene's 2 mm, its high found none at 98 kPa).
QUALITY_3D: dict[str, tuple[float, float | None, int | None]] = {
    "draft": (1.5, None, 1),
    "default": (1.5, 1.5, None),
    "high": (1.5, 1.0, None),
    "accurate": (1.0, 0.8, None),
}
# ... and those of a body sized through its walls (mesh.through_wall), where the edges through the wall decide the
# accuracy and the bulk matters little: the near factor divides the edges through the wall (default 2/3 of the
# scene's, high 4/3 of them, accurate twice), the bulk stays the scene's above default. Read off the actuators'
# meshes (docs/actuators.md "Converged references", 2026-12-07): fiber_bending_3d (5 mm, 4 near the chamber:
# 1.5 %) at default 3.1 %, high 0.23 %; fiber_twist_3d (3 mm, 2 near it: 1.6 %) at default 7.7 %, high 0.13 %.
QUALITY_WALL: dict[str, tuple[float, float | None, int | None]] = {
    "draft": (1.5, None, 1),
    "default": (1.5, 1.5, None),
    "high": (1.0, 0.75, None),
    "accurate": (1.0, 0.5, None),
}
# A mesh file's order at each preset: its tetrahedra cannot be remeshed, so high and accurate make them quadratic.
MESH_FILE_ORDER = {"draft": 1, "default": None, "high": 2, "accurate": 2}
ORDER_WORDS = {f.order: f.adjective for f in FAMILIES}
SIGNIFICANT = 12  # digits a preset's size keeps: the reference beams' presets come out as their exact decimals


def significant(x: float) -> float:
    """x rounded to SIGNIFICANT digits (0.0012 * (0.005 / 0.0012) is 0.005, not 0.005000000000000001)."""
    return float(f"{x:.{SIGNIFICANT}g}")


def planar_preset(quality: str, max_area: float, order: int) -> tuple[float, int]:
    """A 2D preset's (max area, order) for a scene meshed at (max area A, order o). The ladder of meshes
    (P1, r A), (P1, A), (P2, r A), (P2, A), (P2, A / r), (P2, A / r^2) (r = AREA_STEP: each rung has about as many
    nodes as the one below it or more, and is more accurate) holds a linear scene on rung 1, a quadratic one on rung
    3; the preset is the rung QUALITY_STEPS[quality] above it: draft one below, default the scene as written, high
    one above, accurate two (a rung at A keeps the scene's area as it is written). On the reference beam (0.0012, P1):
    (0.005, P1), (0.0012, P1), (0.005, P2), (0.0012, P2), the accuracy study's presets."""
    if order not in (1, 2):  # the ladder is of linear and quadratic meshes: a higher order keeps the scene's mesh
        return max_area, order
    rung = (1 if order == 1 else 3) + QUALITY_STEPS[quality]
    exponent = 1 - rung % 2 if rung <= 3 else 3 - rung
    return (significant(max_area * AREA_STEP**exponent) if exponent else max_area), 1 if rung <= 1 else 2


# the reference beam's presets: (max triangle area, element order, Newton tolerance); the flags' beam takes them
QUALITY = {q: (*planar_preset(q, *REFERENCE_MESH), tol) for q, tol in QUALITY_TOL.items()}
# each preset's measured tip error against the converged tip, on the reference beam (2D, nu = 0.45: docs/accuracy.md)
# and on beam_3d_ellipsoid (3D: docs/3d.md; pneunet_3d's peak tip: 6.5 % and 3.6 % at default and high, its presets
# being factors on its own mesh; pneuma-bench --sections presets_3d measures both): the scene line of a run
QUALITY_ERROR = {
    2: {"draft": 28.4, "default": 8.0, "high": 0.64, "accurate": 0.07},
    3: {"draft": 26, "default": 2.8, "high": 1.6, "accurate": 1.0},  # curved quadratic tetrahedra (docs/3d.md)
}


# The shipped 3D scenes' converged references: (the history column measured, its peak over the shipped ramp, its
# uncertainty), from quadratic meshes refined towards it (beam_3d_ellipsoid and pneunet_3d: docs/3d.md; the
# actuators: benchmarks/actuators.py, docs/actuators.md "Converged references"), and each preset's measured error
# against it ("as written": the scene's own [mesh]; pneuma-bench --sections presets_3d, docs/3d.md "3D presets").
# The references were refined on straight-sided quadratic tetrahedra; "as written" (but fiber_twist_3d's) and the
# beam's presets are measured on the curved ones (the default, 2026-12-07), the other presets' on straight ones.
ACTUATORS_3D = ("fiber_bending_3d", "blocked_force_3d", "fiber_twist_3d")
CONVERGED_3D = {
    "beam_3d_ellipsoid": ("tip_dy", -0.1974, 0.0005),
    "pneunet_3d": ("tip_dy", -1.100, 0.01),
    "fiber_bending_3d": ("tip_rotation", -154.1, 2.7),
    "blocked_force_3d": ("blocked_force", 874.1, 1.2),
    "fiber_twist_3d": ("tip_twist", -55.9, 2.1),
}
MEASURED_ERROR_3D: dict[str, dict[str, float]] = {
    "beam_3d_ellipsoid": dict(QUALITY_ERROR[3]),
    "pneunet_3d": {"as written": 2.0, "draft": 63, "default": 6.5, "high": 3.6},
    "fiber_bending_3d": {"as written": 0.94, "draft": 80, "default": 3.1, "high": 0.23},
    "fiber_twist_3d": {"as written": 1.6, "draft": 55, "default": 7.2, "high": 0.19},
    "blocked_force_3d": {"as written": 1.4, "draft": 46, "high": 0.69},
}


def with_quality(scene, args: argparse.Namespace):
    """The scene file's scene with its --quality preset applied, and the line that says what the preset means for
    this scene ('' where nothing was asked: --quality not given). A 2D scene: planar_preset's max area and order (the
    default: the scene as written). A 3D body from shapes, where --quality was given: QUALITY_3D's factors
    (QUALITY_WALL's for a body sized through its walls) on its edge lengths (the grading distance: the new edge
    length), and its order. A mesh file, where --quality was given: its own tetrahedra (they cannot be remeshed), in
    MESH_FILE_ORDER's order."""
    quality, given = args.quality, getattr(args, "quality_given", False)
    tol = f"; Newton tolerance {args.tol:g}"
    geometry, units = scene.geometry, scene.units
    if scene.dim == 2:
        own = (geometry.max_area, geometry.order)
        max_area, order = planar_preset(quality, *own)
        area = units.suffix(AREA)
        if (max_area, order) != own:
            scene = scene.with_values({"mesh.max_area": max_area, "mesh.order": order})
        said = (
            f"max area {max_area:g}{area} (x{max_area / own[0]:.3g} the scene's {own[0]:g}{area}), "
            f"{ORDER_WORDS[order]} triangles (the scene's: {ORDER_WORDS[own[1]]})"
        )
        return scene, (f"quality {quality}: {said}{tol}" if given else "")
    if not given:
        return scene, ""
    if not isinstance(geometry, SolidGeometry | SurfaceGeometry):  # a mesh file: its own tetrahedra
        order = MESH_FILE_ORDER[quality] or geometry.order
        if order != geometry.order:
            scene = scene.with_values({"mesh.order": order})
        return scene, (
            f"quality {quality}: the mesh file's own tetrahedra (a mesh file cannot be remeshed), "
            f"{ORDER_WORDS[order]} (the scene's: {ORDER_WORDS[geometry.order]}){tol}"
        )
    bulk, near, preset_order = (QUALITY_3D if geometry.sizes.through_wall is None else QUALITY_WALL)[quality]
    order = preset_order or geometry.order
    sizes, length = geometry.sizes, units.suffix(LENGTH)
    size = significant(bulk * sizes.size)
    own_near = geometry.mesh_sizes.near
    close = size if near is None else significant(near * own_near)
    scenes = f"{own_near:g}{length}"
    if isinstance(geometry, SolidGeometry) and sizes.through_wall is not None:  # (a surface body has none)
        scenes += f" ({sizes.through_wall:g} through its thinnest wall, {geometry.wall:g}{length})"
    scene = scene.with_values({**mesh_values(geometry, size, close, size), "mesh.order": order})
    near_chambers = (
        f"uniform (the scene's: {scenes} near the chambers)"
        if near is None
        else f"{close:g}{length} near the chambers (x{close / own_near:.3g} the scene's {scenes})"
    )
    said = (
        f"tetrahedra of {size:g}{length} (x{size / sizes.size:.3g} the scene's {sizes.size:g}{length}), "
        f"{near_chambers}, {ORDER_WORDS[order]} (the scene's: {ORDER_WORDS[geometry.order]})"
    )
    return scene, f"quality {quality}: {said}{tol}"


def mesh_values(geometry, size: float, near: float, distance: float) -> dict:
    """The [mesh] values (dotted keys) that mesh a body from shapes at these lengths: near as near_chambers, or, for
    a scene sized through its walls, as the edges through its thinnest wall (through_wall = wall / near)."""
    values = {"mesh.size": size, "mesh.distance": distance}
    if geometry.sizes.through_wall is None:
        return {**values, "mesh.near_chambers": near}
    return {**values, "mesh.through_wall": significant(geometry.wall / near)}


def preset_note(scene, args: argparse.Namespace | None) -> str:
    """What the run's mesh is measured to cost in accuracy ('' where it was not measured: a mesh file, a scene file
    of other lengths, a scene --set changed): the reference beam's flags' preset, or a shipped 3D scene's preset or
    own [mesh] (MEASURED_ERROR_3D against CONVERGED_3D; another 3D body from shapes with --quality: the beam's figure,
    said to be the beam's)."""
    if args is None or not hasattr(args, "quality") or getattr(args, "set", None):
        return ""
    given = getattr(args, "quality_given", False)
    from_shapes = isinstance(scene.geometry, SolidGeometry)
    if scene.dim == 2:
        if getattr(args, "scene", None):  # a scene file's rung need not be the reference beam's of the same name
            return ""
        error = QUALITY_ERROR[2][args.quality]
        return f"; --quality {args.quality}: tip within {error:g} % of converged on the reference beam"
    if not from_shapes:
        return ""
    preset = args.quality if given else "as written"
    measured = MEASURED_ERROR_3D.get(scene.name, {})
    what = f"--quality {args.quality}" if given else "mesh as written"
    if preset in measured:
        column, value, _ = CONVERGED_3D[scene.name]
        measure = "tip" if column == "tip_dy" else column
        return f"; {what}: {measure} within {measured[preset]:g} % of converged ({value:g})"
    if not given:
        return ""
    return f"; {what}: not measured on this scene (on beam_3d_ellipsoid: tip within {QUALITY_ERROR[3][preset]:g} %)"
