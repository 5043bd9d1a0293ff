"""The fibre-reinforced bending actuator of the shipped fiber_bending_3d scene, drawn in build123d (OpenCASCADE,
not gmsh) and exported as STEP: taichi_pneuma/scenes/fiber_actuator.step, which fiber_bending_step.toml reads; and
its rubber (the body less the chamber) as STL, triangulated to 0.05 mm: fiber_actuator.stl, beside it.

Its body is a half-round bar, radius 8 mm over a flat base 2 mm thick, 100 mm long along x from x = 0 (the axis at
y = 2 mm, z = 0); its chamber a half-round cavity of radius 6 mm, 94 mm long (3 mm end caps), on the same axis, the
base's top face its floor. The two solids are labelled "body" and "chamber" in the file; the scene subtracts the
chamber from the body. Lengths in millimetres (the file says so: a STEP file carries its unit).

    pip install build123d   # (not a dependency of taichi-pneuma: only this script needs it)
    python examples/cad_fiber_actuator_step.py [OUT.step]    (and OUT.stl)
"""

import sys
from pathlib import Path

from build123d import Box, Compound, Cylinder, Location, export_step, export_stl

LENGTH, RADIUS, BASE, CHAMBER_RADIUS, CAP = 100.0, 8.0, 2.0, 6.0, 3.0


def half_round(radius: float, length: float) -> object:
    """The half of a cylinder of that radius along x above the plane y = 0, centred at the origin."""
    cylinder = Cylinder(radius, length, rotation=(0, 90, 0))
    upper = Box(length, radius, 2 * radius).locate(Location((0, radius / 2, 0)))
    return cylinder & upper


def actuator() -> Compound:
    axis = Location((LENGTH / 2, BASE, 0))
    base = Box(LENGTH, BASE, 2 * RADIUS).locate(Location((LENGTH / 2, BASE / 2, 0)))
    body = (half_round(RADIUS, LENGTH).moved(axis) + base).clean()
    chamber = half_round(CHAMBER_RADIUS, LENGTH - 2 * CAP).moved(axis)
    body.label, chamber.label = "body", "chamber"
    return Compound(children=[body, chamber], label="fiber_actuator")


if __name__ == "__main__":
    shipped = Path(__file__).parents[1] / "taichi_pneuma/scenes/fiber_actuator.step"
    out = Path(sys.argv[1]) if len(sys.argv) > 1 else shipped
    part = actuator()
    export_step(part, str(out))
    body, chamber = part.children
    export_stl(body - chamber, str(out.with_suffix(".stl")), tolerance=0.05, angular_tolerance=0.2)
    print(f"wrote {out}: body {part.children[0].volume:.1f} mm^3, chamber {part.children[1].volume:.1f} mm^3")
