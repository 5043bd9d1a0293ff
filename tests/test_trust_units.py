"""Issue 28, trust round three: every default with a unit follows the scene's units; a material region that
selects nothing and a material law that is not stable are refused at load."""

from __future__ import annotations

import copy
import dataclasses
import re
import tomllib
from types import SimpleNamespace

import numpy as np
import pytest

import taichi_pneuma as tp
from taichi_pneuma.apps import inflate
from taichi_pneuma.errors import PneumaInputError
from taichi_pneuma.fem.planar import Geometry
from taichi_pneuma.fem.shapes import Polygon
from taichi_pneuma.fem.supports import PointSet
from taichi_pneuma.io.units import UNITLESS, UNITS
from taichi_pneuma.materials import IsochoricMaterial
from taichi_pneuma.materials.isochoric import unstable_stretch
from taichi_pneuma.materials.presets import PRESETS
from taichi_pneuma.scene.build import ChamberControl, Material, Region, Scene
from taichi_pneuma.scene.scenefile import key_reference, read_scene, scene_data
from taichi_pneuma.scene.schedule import ChamberSchedule
from taichi_pneuma.terms.chambers import KINDS as CHAMBER_KINDS
from taichi_pneuma.terms.chambers import AreaControl, ClosedGas
from taichi_pneuma.terms.effects import EFFECTS, Gravity, Ground, SelfContact
from taichi_pneuma.terms.obstacles import Obstacle

# A dented wall (balloon_syringe.toml, coarser and stiffer, so that the air's compression matters) in mm and kPa
SYRINGE = """units = "mm-kPa"
[body]
shape = "polygon"
points = [[-15.0, -5.0], [15.0, -5.0], [15.0, 5.0], [8.0, 5.0], [0.0, 1.5], [-8.0, 5.0], [-15.0, 5.0]]
[mesh]
max_area = 2.0
[material]
E = 2000.0
nu = 0.45
[clamp]
side = "bottom"
[tip]
box = [-0.5, 0.5, 0.5, 2.0]
[[chambers]]
name = "main"
shape = "polygon"
points = [[-8.0, -2.0], [8.0, -2.0], [8.0, 4.6], [0.0, 1.1], [-8.0, 4.6]]
control = "syringe"
syringe_volume = 60.0
dead_volume = 20.0
keyframes = [[6, 58.0]]
[schedule]
increments = 6
"""

# Scenes between them holding every key with a unit and a default (each written out), for the walk below
PLANAR = """[body]
shape = "rectangle"
center = [0.0, 0.0]
size = [3.5, 0.8]
[mesh]
max_area = 0.05
[material]
E = 1e4
[clamp]
side = "left"
stiffness = 1e9
[[rollers]]
normal = [0.0, 1.0]
point = [0.0, -0.4]
tolerance = 1e-6
[[chambers]]
name = "main"
shape = "ellipse"
center = [0.0, 0.1]
semi_axes = [0.5, 0.15]
control = "area"
stiffness = 1e5
keyframes = [[2, 1.5]]
[schedule]
increments = 2
[effects.gravity]
density = 1.0
g = 9.81
[effects.ground]
height = -0.5
dhat = 0.01
stiffness = 1e3
[effects.self_contact]
dhat = 0.005
stiffness = 1e4
[[obstacles]]
name = "post"
shape = "sphere"
center = [2.5, 0.0]
radius = 0.2
dhat = 0.01
stiffness = 1e3
"""
KINDS = {
    "closed_gas": 'control = "closed_gas"\natmosphere = 101325.0',
    "syringe": 'control = "syringe"\natmosphere = 101325.0\nsyringe_volume = 2.0\ndead_volume = 0.0',
}
EXTRUDED = """[body]
shape = "extrusion"
depth = 0.8
z = 0.0
[body.profile]
shape = "rectangle"
center = [0.0, 0.0]
size = [3.5, 0.8]
[mesh]
size = 0.2
[[chambers]]
name = "main"
shape = "extrusion"
depth = 0.3
z = 0.0
control = "volume"
stiffness = 1e6
keyframes = [[2, 1.5]]
[chambers.profile]
shape = "ellipse"
center = [0.0, 0.1]
semi_axes = [0.5, 0.15]
[effects.surface_contact]
stiffness = 1e5
[schedule]
increments = 2
"""
PNEUNET = """[body]
shape = "pneunet"
chamber_length = 0.4
chamber_height = 0.5
chamber_width = 0.6
radius = 0.08
gap = 0.1
wall = 0.08
end = 0.55
base = 0.07
layer = 0.15
slit = 0.0
[mesh]
size = 0.2
[[chambers]]
name = "c1"
shape = "mesh_surface"
group = "c1"
control = "pressure"
keyframes = [[2, 100.0]]
[schedule]
increments = 2
"""
HALF_CYLINDER = """[body]
shape = "half_cylinder"
center = [0.0, 0.0, 0.0]
radius = 0.4
length = 3.5
base = 0.1
fillet = 0.0
[mesh]
size = 0.2
[[chambers]]
name = "main"
shape = "half_cylinder"
center = [0.0, 0.1, 0.0]
radius = 0.2
length = 3.0
base = 0.0
fillet = 0.0
control = "pressure"
keyframes = [[2, 100.0]]
[schedule]
increments = 2
"""
RECTANGLE = 'shape = "rectangle"\ncenter = [0.0, 0.0]\nsize = [3.5, 0.8]'
UNION = 'shape = "union"\nrectangles = [{ center = [0.0, 0.0], size = [3.5, 0.8] }]'  # a rectangle's center, in a union
BASES = [
    (tomllib.loads(text), dim)
    for text, dim in (
        (PLANAR, 2),
        *((PLANAR.replace('control = "area"\nstiffness = 1e5', kind), 2) for kind in KINDS.values()),
        (PLANAR.replace(RECTANGLE, UNION), 2),
        (EXTRUDED, 3),
        (EXTRUDED.replace(RECTANGLE, UNION), 3),
        (PNEUNET, 3),
        (HALF_CYLINDER, 3),
    )
]

# The size of each system's unit of each dimension in SI, by hand: (2D, 3D). A mass is pressure x length x s^2
# (kg in mm-kPa, t in mm-MPa); a 2D energy is per unit depth; a chamber's measure an area (2D) or a volume (3D)
DIMENSIONS = (
    "length",
    "area",
    "plane area",
    "pressure",
    "acceleration",
    "density",
    "time",
    "nodal penalty stiffness",
    "measure penalty stiffness",
)
BY_HAND = {
    "mm-kPa": dict(
        zip(
            DIMENSIONS,
            (
                (1e-3, 1e-3),
                (1e-6, 1e-9),
                (1e-6, 1e-6),
                (1e3, 1e3),
                (1e-3, 1e-3),
                (1e9, 1e9),
                (1.0, 1.0),
                (1e3, 1.0),
                (1e9, 1e12),
            ),
        )
    ),
    "mm-MPa": dict(
        zip(
            DIMENSIONS,
            (
                (1e-3, 1e-3),
                (1e-6, 1e-9),
                (1e-6, 1e-6),
                (1e6, 1e6),
                (1e-3, 1e-3),
                (1e12, 1e12),
                (1.0, 1.0),
                (1e6, 1e3),
                (1e12, 1e15),
            ),
        )
    ),
    "m-Pa": dict.fromkeys(DIMENSIONS, (1.0, 1.0)),
}


def at(data: dict, key: str):
    """The table holding a dotted key of the reference ('chambers[].atmosphere': the first chamber's), and its name;
    None where the data has no such table."""
    *path, name = key.split(".")
    for part in path:
        part, items = part.removesuffix("[]"), part.endswith("[]")
        data = data.get(part) if isinstance(data, dict) else None
        data = (data[0] if data else None) if items else data
    return (data, name) if isinstance(data, dict) and name in data else (None, name)


def applies(data: dict, when: str) -> bool:
    if not when:
        return True
    key, value = when.split(" = ")
    table, name = at(data, key)
    return table is not None and table[name] == tomllib.loads(f"v = {value}")["v"]


def read(data: dict, units: str | None):
    data = copy.deepcopy(data)
    if units is not None:
        data["units"] = units
    return read_scene(data, "walk")


def test_every_default_with_a_unit_is_si_converted_into_every_unit_system():
    """Walks every key of the reference that declares a unit and has a numeric default: in each system a scene
    without the key reads as the scene with the key written out as its SI default divided by the size of the
    system's unit (by hand, BY_HAND); a numerical default (calibrated for unitless scenes) is refused in a scene
    with units, naming the key, and taken as it is in a unitless one."""
    rows = [row for row in key_reference() if row.unit and row.default not in ("required", "none")]
    assert {row.key for row in rows} >= {
        "chambers[].atmosphere",
        "clamp.stiffness",
        "effects.gravity.g",
        "chambers[].stiffness",
        "effects.ground.dhat",
        "rollers[].tolerance",
    }
    for row in rows:
        base = next(
            ((data, dim) for data, dim in BASES if at(data, row.key)[0] is not None and applies(data, row.when)), None
        )
        assert base is not None, f"no scene of the walk has {row.key} ({row.when})"
        data, dim = base
        default = tomllib.loads(f"v = {row.default}")["v"]
        for units in (None, *UNITS):
            size = 1.0 if units is None else BY_HAND[units][row.unit][dim - 2]
            without, written = copy.deepcopy(data), copy.deepcopy(data)
            del at(without, row.key)[0][at(without, row.key)[1]]
            table, name = at(written, row.key)
            table[name] = [v / size for v in default] if isinstance(default, list) else default / size
            if row.scaled or units is None:
                assert scene_data(read(without, units)) == scene_data(read(written, units)), (row.key, units)
            else:
                key = re.escape(row.key.replace("[]", "[0]"))
                with pytest.raises(PneumaInputError, match=rf"missing key '{key}': a scene with units gives it"):
                    read(without, units)


def test_a_mm_kpa_syringe_without_atmosphere_compresses_its_air_from_101_325_kpa():
    """Before: the default atmosphere 101325 was taken in kPa: peak pressure 3.36 kPa without the key, 2.31 with
    atmosphere = 101.325. Now both are the same run, and Boyle's law holds at 101.325 kPa."""
    data = tomllib.loads(SYRINGE)
    written = copy.deepcopy(data)
    written["chambers"][0]["atmosphere"] = 101.325
    runs = [tp.simulate(read_scene(d, "syringe")) for d in (data, written)]
    assert all(run.converged for run in runs)
    peaks = [max(step.chambers["main"].pressure for step in run.steps) for run in runs]
    assert peaks[0] == pytest.approx(peaks[1], rel=1e-9)
    rest, last = runs[0].steps[0].chambers["main"].area, runs[0].steps[-1].chambers["main"]
    # p_abs G = p_atm V_atm: G = A + dead + syringe - displaced, V_atm = A_rest + dead + syringe
    assert (last.pressure + 101.325) * (last.area + 20.0 + 60.0 - 58.0) == pytest.approx(
        101.325 * (rest + 80.0), rel=1e-9
    )


def test_the_default_modulus_is_1e4_pa_and_max_area_must_be_given_with_units():
    """E's default is 1e4 Pa (10 kPa in a mm-kPa scene; before: 1e4 kPa); mesh.max_area's default 0.0012 is
    for unitless scenes (0.0012 mm^2 would mesh a 30 mm body into hundreds of thousands of triangles)."""
    data = tomllib.loads(PLANAR)
    del data["material"]["E"]
    assert read(data, "mm-kPa").material.youngs_modulus == pytest.approx(10.0)
    assert read(data, "mm-MPa").material.youngs_modulus == pytest.approx(0.01)
    assert read(data, None).material.youngs_modulus == 1e4
    del data["mesh"]["max_area"]
    with pytest.raises(PneumaInputError, match="missing key 'mesh.max_area': a scene with units gives it"):
        read(data, "mm-kPa")
    assert read(data, None).geometry.max_area == 0.0012


def error_line(capsys) -> str:
    lines = [line for line in capsys.readouterr().err.splitlines() if line.strip()]
    assert len(lines) == 1 and lines[0].startswith("error: "), lines
    return lines[0]


def inflate_scene(tmp_path, text: str, *flags) -> int:
    (tmp_path / "scene.toml").write_text(text)
    return inflate.main(
        ["--scene", str(tmp_path / "scene.toml"), "--out", str(tmp_path / "out"), "--no-video", "--quiet", *flags]
    )


def test_a_material_region_that_selects_no_element_is_refused_naming_it(tmp_path, capsys):
    """Before: a region box outside the body was silently ignored (the run went on with the base material)."""
    text = PLANAR.replace(
        "E = 1e4\n",
        "E = 1e4\nregions = [{ box = [-1.75, -0.4, 1.75, -0.3], E = 5e4 }, { box = [5.0, 5.0, 6.0, 6.0], E = 5e4 }]\n",
    )
    assert inflate_scene(tmp_path, text) == 2
    line = error_line(capsys)
    assert "material.regions[1]: box = [5.0, 5.0, 6.0, 6.0] holds no element's centroid" in line


def test_a_material_region_group_without_elements_is_refused_naming_it():
    """A volume group the mesh names but whose tetrahedra all lie in other groups."""
    mesh = SimpleNamespace(
        n_elements=3,
        vertices=np.zeros((4, 3)),
        elements=np.zeros((3, 4), dtype=int),
        regions=np.zeros(3, dtype=int),
        region_groups={"layer": 1},
    )
    scene = tp.load_scene("reference_beam")
    scene = dataclasses.replace(scene, regions=(Region(None, scene.material, "layer"),))
    with pytest.raises(PneumaInputError, match=r"material.regions\[0\]: group = 'layer' has no elements"):
        scene.element_material(mesh)


LAW = PLANAR.replace("E = 1e4\n", 'law = "yeoh"\nC10 = 100.0\n')


@pytest.mark.parametrize(
    "assignments, coefficient, where",
    [
        (["material.C20=-10"], "C20 = -10", "uniaxial tension at stretch 1.83"),
        (["material.C20=10", "material.C30=-5"], "C30 = -5", "uniaxial tension at stretch 1.86"),
        (
            ["material.law=mooney_rivlin", "material.C10=1000", "material.C01=-800"],
            "C01 = -800",
            "uniaxial compression at stretch 0.888",
        ),
    ],
)
def test_a_law_that_is_not_stable_is_refused_at_load_naming_the_coefficient(
    tmp_path, capsys, assignments, coefficient, where
):
    """Before: Yeoh with C20 < 0 and Mooney-Rivlin with C01 = -800 failed at step 3-4 with 'not a descent
    direction (g.d = nan)', blaming Newton; Yeoh with C30 < 0 ran silently. By hand, incompressible uniaxial
    tension has d2w/dlam2 = W1 (2 + 4/lam^3) + W11 (2 lam - 2/lam^2)^2 + 6 C01 / lam^4, W1 = C10 + 2 C20 a + 3 C30
    a^2, W11 = 2 C20 + 6 C30 a, a = lam^2 + 2/lam - 3: C10 = 100, C20 = -10 gives 0 at lam = 1.833 (W1 = 71.0:
    188.1 - 188.6); Mooney-Rivlin C10 = 1000, C01 = -800 gives 1000 (2 + 4/lam^3) = 4800/lam^4, lam^4 + 2 lam =
    2.4, lam = 0.888."""
    flags = [f for a in assignments for f in ("--set", a)]
    assert inflate_scene(tmp_path, LAW, *flags) == 2
    line = error_line(capsys)
    assert "is not stable" in line and f"because of {coefficient} < 0" in line and where in line, line


@pytest.mark.parametrize("law, coefficients", [("yeoh", {"C20": -1.0}), ("mooney_rivlin", {"C01": -10.0})])
def test_a_negative_coefficient_that_keeps_the_law_stable_is_accepted(law, coefficients):
    """By hand, d2w/dlam2 = W1 I1'' + W11 I1'^2 + C01 I2'' (isochoric.py's docstring) at its smallest over the
    principal stretches 1/3 to 3, C10 = 100: Yeoh C20 = -1 (W1 = 100 - 2 a, W11 = -2): uniaxial lam = 3 (a = 6.67):
    86.7 x 2.148 - 2 x 5.778^2 = 119.4; pure shear lam = 3 (a = 7.11): 85.8 x 2.074 - 2 x 5.926^2 = 107.7;
    equibiaxial lam = 3^1/2 (a = 3.11): 93.8 x 4.741 - 2 x 6.672^2 = 355.6. Mooney-Rivlin C01 = -10: uniaxial
    lam = 3: 100 x 2.148 - 10 x 6/81 = 214.1; equibiaxial lam = 3^1/2: 100 x 4.741 - 10 x (36 + 12/9) = 100.7; pure
    shear: 90 x 2.074 = 186.7. All > 0: stable, so accepted."""
    material = IsochoricMaterial(law, 100.0, **coefficients)
    assert material.shear_modulus > 0


@pytest.mark.parametrize("name", sorted(PRESETS))
def test_every_preset_is_a_stable_law(name):
    material = PRESETS[name].material
    assert unstable_stretch(material.C10, material.C01, material.C20, material.C30) is None


# --- API defaults: the Python API converts the same SI defaults as a scene file (units.si_default) ---

MM_KPA = UNITS["mm-kPa"]
WALL = Polygon(((-15.0, -5.0), (15.0, -5.0), (15.0, 5.0), (8.0, 5.0), (0.0, 1.5), (-8.0, 5.0), (-15.0, 5.0)))
DENT = Polygon(((-8.0, -2.0), (8.0, -2.0), (8.0, 4.6), (0.0, 1.1), (-8.0, 4.6)))


def wall_scene(kind, material=None, max_area: float | None = 2.0, effects=(), units=MM_KPA) -> Scene:
    """SYRINGE's dented wall built in Python: 30 x 10 mm, E = 2000 kPa, the air pumped in 40 mm^2 over 4 steps."""
    geometry = Geometry(WALL, (("main", DENT),), max_area, PointSet("bottom"), tip=PointSet(box=(-0.5, 0.5, 0.5, 2.0)))
    return Scene(
        geometry,
        (ChamberControl(ChamberSchedule(kind, ((4, 40.0),))),),
        4,
        Material(2000.0, 0.45) if material is None else material,
        effects=effects,
        units=units,
    )


def test_an_api_built_mm_kpa_closed_gas_chamber_takes_101_325_kpa_as_its_default_atmosphere():
    """Before: ClosedGas()'s (and ChamberSchedule("closed_gas", ...)'s) atmosphere stayed 101325, read as kPa, a
    nearly incompressible gas. Now None, set by the Scene to 101325 Pa / 1000 = 101.325 kPa: the same run as
    atmosphere = 101.325 written out. The wall (E = 100 MPa) is stiff enough for the air's compression to matter:
    the peak is 39.9 kPa at 101.325 kPa and 68.1 kPa with a nearly incompressible gas (101325 kPa)."""
    assert wall_scene(ClosedGas()).controls[0].kind.atmosphere == pytest.approx(101.325, rel=1e-12)
    stiff = Material(1e5, 0.45)
    peaks = [
        max(step.chambers["main"].pressure for step in tp.simulate(wall_scene(kind, stiff)).steps)
        for kind in ("closed_gas", ClosedGas(atmosphere=101.325), ClosedGas(atmosphere=101325.0))
    ]
    assert peaks[0] == pytest.approx(peaks[1], rel=1e-9)
    assert peaks[2] > 1.5 * peaks[1]


def test_api_defaults_with_a_unit_are_si_converted_by_the_scene():
    """By hand, in mm-kPa: E 1e4 Pa = 10 kPa; g 9.81 m/s^2 = 9810 mm/s^2; the clamp's 1e9 Pa (2D: energy per
    depth per length^2, a pressure) = 1e6 kPa. mm-MPa: E = 0.01 MPa. A unitless scene keeps the SI numbers."""
    units = {"mm-kPa": (10.0, 9810.0, 1e6), "mm-MPa": (0.01, 9810.0, 1e3), None: (1e4, 9.81, 1e9)}
    for name, (E, g, clamp) in units.items():
        scene = wall_scene(
            "pressure", Material(), effects=(Gravity(density=1.0),), units=UNITLESS if name is None else UNITS[name]
        )
        assert scene.material.youngs_modulus == pytest.approx(E, rel=1e-12)
        assert scene.effects[0].g == pytest.approx(g, rel=1e-12)
        assert scene.clamp_stiffness == pytest.approx(clamp, rel=1e-12)
        assert read_scene(tomllib.loads(scene.to_toml()), "scene") == scene


@pytest.mark.parametrize(
    "change, key",
    [
        (dict(kind="area"), "chambers[0].stiffness"),
        (dict(kind=AreaControl()), "chambers[0].stiffness"),
        (dict(effects=(Ground(height=-10.0),)), "effects.ground.dhat"),
        (dict(effects=(SelfContact(),)), "effects.self_contact.dhat"),
        (dict(max_area=None), "mesh.max_area"),
    ],
)
def test_api_numerical_defaults_are_refused_in_a_scene_with_units_naming_the_key(change, key):
    """As in a scene file: a default calibrated for unitless scenes (area penalty 1e5, contact dhat, max_area
    0.0012) left None in a scene with units is one PneumaInputError naming the key; unitless, it is taken."""
    arguments = {"kind": "pressure", **change}
    with pytest.raises(PneumaInputError, match=rf"missing key '{re.escape(key)}': a scene with units gives it"):
        wall_scene(**arguments)
    unitless = wall_scene(**arguments, units=UNITLESS)
    assert unitless.geometry.max_area in (2.0, 0.0012)


def test_every_api_default_with_a_unit_is_the_scene_files_default():
    """Each si_default field of the chamber kinds, effects, Material, Scene and Geometry is the key of the key
    reference with the same SI default, unit and scaling: one declaration serves both."""
    rows = {row.key: row for row in key_reference()}
    owners = (
        [(cls, "chambers[].{}") for cls in CHAMBER_KINDS.values()]
        + [(cls, f"effects.{cls.name}.{{}}") for cls in EFFECTS.values()]
        + [(Material, "material.{}"), (Scene, "clamp.{}"), (Geometry, "mesh.{}"), (Obstacle, "obstacles[].{}")]
    )
    names = {"youngs_modulus": "E", "clamp_stiffness": "stiffness"}
    found = 0
    for cls, key in owners:
        for f in dataclasses.fields(cls):
            if "si" in f.metadata:
                row = rows[key.format(names.get(f.name, f.name))]
                assert (tomllib.loads(f"v = {row.default}")["v"], row.unit, row.scaled) == (
                    f.metadata["si"],
                    f.metadata["unit"],
                    f.metadata["scaled"],
                ), row.key
                found += 1
    assert found >= 10


def test_a_3d_force_in_mm_kpa_is_in_mn_on_the_plot_in_the_csv_and_in_the_summary():
    """blocked_force_3d (mm-kPa) on a coarse linear mesh, two steps to 30 kPa: kPa mm^2 is mN, and the blocked-force
    axis, the plate's CSV columns and the summary's force unit all say so."""
    from taichi_pneuma.render.plots import history_panels

    scene = tp.load_scene("blocked_force_3d").with_values(
        {
            "mesh.size": 12,
            "mesh.near_chambers": 6,
            "mesh.distance": 6,
            "mesh.order": 1,
            "schedule.increments": 2,
            "chambers[0].keyframes": [[0, 0.0], [2, 30.0]],
        }
    )
    result = tp.simulate(scene)
    assert result.history["blocked_force"][-1] > 0
    panel = history_panels(result)[-1]
    assert panel.y_label == "force [mN]"
    curves = {label: y for label, _, y, _ in panel.curves}  # the net force and the plate's own (here the same)
    assert list(curves) == ["net (blocked force)", "plate: sum of |f|"]
    assert curves["plate: sum of |f|"][-1] == pytest.approx(result.history["plate.magnitude"][-1])
    header = result.history_csv().splitlines()[0].split(",")
    assert {"plate.fy [mN]", "clamp.fy [mN]", "clamp.mz [mN mm]", "blocked_force [mN]"} <= set(header)
    assert result.summary()["units"]["force"] == "mN"
