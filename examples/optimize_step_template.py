"""A scene template for pneuma-optimize --template: the fibre-reinforced actuator's rubber drawn in gmsh's
OpenCASCADE (the [3d] extra) for a chamber radius, written as two STEP files (its body and its chamber, in mm), and
the shipped fiber_bending_step scene reading them, its threads at the given pitch. The wall is the body's radius
(8 mm) less the chamber's, so this optimises a CAD part's dimension as a CAD tool would draw it:

    pneuma-optimize --template examples/optimize_step_template.py \\
        --vary chamber_radius=5:6.5 --vary pitch=3:8 --refine 10 --trials 30 \\
        --minimize "at(chamber.pressure, tip_rotation, -90)" --constraint "at(max_stretch, tip_rotation, -90)<=1.5"

The parts go to $PNEUMA_PARTS (default: ./parts), one pair per radius (body_r6.000000.step, ...), each written
beside and renamed so that two designs of one radius never read a half-written file. Its geometry is
examples/cad_fiber_actuator_step.py's (build123d): a half-round bar of radius 8 mm over a 2 mm base, 100 mm long,
and a half-round chamber 94 mm long (3 mm end caps) on the same axis.
"""

import os
from contextlib import contextmanager
from pathlib import Path

import taichi_pneuma as tp

LENGTH, RADIUS, BASE, CAP = 100.0, 8.0, 2.0, 3.0


@contextmanager
def quiet_stdout():
    """OpenCASCADE's STEP writer prints to the process's standard output: sent to /dev/null meanwhile."""
    saved, null = os.dup(1), os.open(os.devnull, os.O_WRONLY)
    os.dup2(null, 1)
    try:
        yield
    finally:
        os.dup2(saved, 1)
        os.close(saved)
        os.close(null)


def half_round(occ, radius: float, x0: float, length: float):
    """The half of a cylinder of that radius along x from x0, above the base (y >= BASE)."""
    cylinder = occ.addCylinder(x0, BASE, 0, length, 0, 0, radius)
    upper = occ.addBox(x0, BASE, -radius, length, radius, 2 * radius)
    return occ.intersect([(3, cylinder)], [(3, upper)])[0]


def write_parts(chamber_radius: float, folder: Path) -> list[Path]:
    """The body's and the chamber's STEP files for this chamber radius (written unless there)."""
    import gmsh

    files = [folder / f"{name}_r{chamber_radius:.6f}.step" for name in ("body", "chamber")]
    if all(f.exists() for f in files):
        return files
    gmsh.initialize(["-noenv"], readConfigFiles=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        for i, path in enumerate(files):
            gmsh.model.add(path.stem)
            occ = gmsh.model.occ
            if i == 0:
                base = occ.addBox(0, 0, -RADIUS, LENGTH, BASE, 2 * RADIUS)
                occ.fuse(half_round(occ, RADIUS, 0, LENGTH), [(3, base)])
            else:
                half_round(occ, chamber_radius, CAP, LENGTH - 2 * CAP)
            occ.synchronize()
            partial = path.with_name(f"{path.stem}.{os.getpid()}.partial.step")
            with quiet_stdout():
                gmsh.write(str(partial))
            os.replace(partial, path)
    finally:
        gmsh.finalize()
    return files


def scene(chamber_radius: float = 6.0, pitch: float = 4.0):
    """The fiber_bending_step scene on the parts of this chamber radius, its threads at this pitch (mm), covering
    the body's length."""
    folder = Path(os.environ.get("PNEUMA_PARTS", "parts")).resolve()
    folder.mkdir(parents=True, exist_ok=True)
    body, chamber = write_parts(chamber_radius, folder)
    path = {"layout": "crossed", "center": [1.0, 2.0, 0.0], "axis": "x", "radius": 7.0, "flat": 1.0}
    return tp.load_scene("fiber_bending_step").with_values(
        {
            "body.file": str(body),
            "body.solid": None,
            "chambers[0].file": str(chamber),
            "chambers[0].solid": None,
            "fibers[0].path": {**path, "pitch": pitch, "extent": 98.0},
        }
    )
