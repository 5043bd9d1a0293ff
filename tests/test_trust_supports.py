"""Supports are what the scene says (issue 28): no [clamp] means no clamp; supports that leave a rigid-body
motion free are refused, naming it; symmetry models held by rollers alone match the exact finite-strain
answers; and switching a kind with --set drops the old kind's defaults.

The exact answers: the incompressible neo-Hookean (shear modulus mu) thick ring in plane strain (d = 2) and
thick sphere (d = 3), inner radius A, outer B, under inner pressure p. Incompressibility gives r^d = R^d + c,
the hoop stretch lam = r / R, the radial one lam^(1 - d), and radial equilibrium
d sigma_r / dr = (d - 1) (sigma_t - sigma_r) / r with sigma_t - sigma_r = mu (lam^2 - lam^(2 - 2d)) gives

    p = (d - 1) mu int_A^B (lam^2 - lam^(2 - 2d)) (dr/dR) / r dR,   dr/dR = R^(d-1) / r^(d-1),

solved for c (so for r(A) = (A^d + c)^(1/d)). The models use the isochoric neo-Hookean law with C10 = mu / 2
and K = 1000 mu (volume changes of p / K ~ 4e-4). The old left clamp, which every scene without a [clamp]
got, holds the x = 0 edge and gives r(A)/A 1.339 (ring) and 1.106 (octant) for these meshes.
"""

import re
from dataclasses import replace

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.optimize import brentq
from solid_meshes import shell_octant

import taichi_pneuma as tp
from taichi_pneuma.apps import inflate
from taichi_pneuma.errors import PneumaInputError
from taichi_pneuma.fem.meshfile import write_mesh
from taichi_pneuma.fem.planar import BeamGeometry, Geometry
from taichi_pneuma.fem.shapes import Ellipse, Rectangle
from taichi_pneuma.fem.supports import PointSet
from taichi_pneuma.scene.build import ChamberControl, Scene
from taichi_pneuma.scene.schedule import area_ramp
from taichi_pneuma.terms.effects import Gravity, Ground

MU, PRESSURE, INNER, OUTER = 1.0, 0.4429, 1.0, 2.0
ARC = np.linspace(0.0, np.pi / 2, 17)
QUARTER_DISK = [[0.0, 0.0]] + [[float(OUTER * np.cos(t)), float(OUTER * np.sin(t))] for t in ARC]
MATERIAL = f'[material]\nlaw = "neo_hookean"\nC10 = {MU / 2}\nK = {1000 * MU}\n'
ROLLER = "[[rollers]]\nnormal = {}\npoint = {}\n"
RING_ROLLERS = ROLLER.format([1.0, 0.0], [0.0, 0.0]) + ROLLER.format([0.0, 1.0], [0.0, 0.0])
OCTANT_ROLLERS = "".join(ROLLER.format(list(n), [0.0, 0.0, 0.0]) for n in np.eye(3).tolist())


def exact_inner_stretch(d: int, pressure: float = PRESSURE) -> float:
    """r(A)/A of the incompressible neo-Hookean thick ring (d = 2) or sphere (d = 3) (module docstring)."""

    def load(c):
        def integrand(big_r):
            r = (big_r**d + c) ** (1 / d)
            lam = r / big_r
            return (d - 1) * MU * (lam**2 - lam ** (2 - 2 * d)) * big_r ** (d - 1) / r**d

        return quad(integrand, INNER, OUTER, epsabs=1e-13, epsrel=1e-13)[0]

    c = brentq(lambda c: load(c) - pressure, 0.0, 10.0, xtol=1e-14)
    return (INNER**d + c) ** (1 / d) / INNER


def ring_text(supports: str = RING_ROLLERS, increments: int = 4) -> str:
    """The quarter ring as a scene file: the quarter disk of radius 2 less the bore of radius 1, cut by the
    symmetry lines x = 0 and y = 0 (the bore closed by them), under pressure control."""
    return (
        f'[body]\nshape = "polygon"\npoints = {QUARTER_DISK}\n[mesh]\nmax_area = 0.02\norder = 2\n{MATERIAL}'
        f'{supports}[[chambers]]\nname = "bore"\nshape = "ellipse"\ncenter = [0.0, 0.0]\nsemi_axes = [1.0, 1.0]\n'
        f'points = 64\ncontrol = "pressure"\nkeyframes = [[0, 0.0], [{increments}, {PRESSURE}]]\n'
        f"[schedule]\nincrements = {increments}\n"
    )


def octant_text(supports: str = OCTANT_ROLLERS) -> str:
    """The octant of the thick sphere from a mesh file (octant.msh, curved quadratic tetrahedra), the cavity
    closed by the three symmetry planes, under pressure control."""
    return (
        f'[body]\nshape = "mesh"\nfile = "octant.msh"\n[mesh]\norder = 2\n{MATERIAL}{supports}'
        f'[[chambers]]\nname = "cavity"\nshape = "mesh_surface"\ngroup = "cavity"\ncontrol = "pressure"\n'
        f"keyframes = [[0, 0.0], [4, {PRESSURE}]]\n[schedule]\nincrements = 4\n"
    )


def block_text(supports: str) -> str:
    """A 2 x 1 block (left edge on x = 0) with an elliptic chamber inside, area-controlled."""
    return (
        f'[body]\nshape = "rectangle"\ncenter = [1.0, 0.5]\nsize = [2.0, 1.0]\n[mesh]\nmax_area = 0.05\n{supports}'
        f'[[chambers]]\nname = "c"\nshape = "ellipse"\ncenter = [1.0, 0.5]\nsemi_axes = [0.5, 0.2]\n'
        f"keyframes = [[0, 1.0], [2, 1.5]]\n[schedule]\nincrements = 2\n"
    )


def scene_file(tmp_path, text: str, name: str = "scene"):
    path = tmp_path / f"{name}.toml"
    path.write_text(text)
    return path


@pytest.fixture(scope="module")
def octant_dir(tmp_path_factory):
    directory = tmp_path_factory.mktemp("octant")
    write_mesh(directory / "octant.msh", shell_octant(4, 2, order=2, curved=True), ("cavity",))
    return directory


def stretches(result, nodes) -> np.ndarray:
    """The deformed over the rest distance from the origin of the nodes, at the last step."""
    x = result.mesh.vertices[nodes]
    return np.linalg.norm(x + result.displacements[-1][nodes], axis=1) / np.linalg.norm(x, axis=1)


def test_the_exact_answers_are_those_the_issue_quotes():
    assert exact_inner_stretch(2) == pytest.approx(1.533, abs=5e-4)
    assert exact_inner_stretch(3, 0.4439) == pytest.approx(1.178, abs=5e-4)


def test_a_quarter_ring_held_by_two_rollers_alone_inflates_to_the_exact_radius(tmp_path):
    """The scene file has no [clamp]: nothing else holds the ring, and its bore grows round to the exact r(A)/A
    (0.05 % here; the old left clamp's 1.339 is 13 % off)."""
    result = tp.simulate(tp.load_scene(scene_file(tmp_path, ring_text())))
    stretch = stretches(result, result.mesh.chambers[0])  # the bore's wall, at radius INNER
    assert result.converged and stretch.mean() == pytest.approx(exact_inner_stretch(2), rel=2e-3)
    assert np.ptp(stretch) < 2e-3  # round: the x = 0 end of the wall moves like the rest
    assert result.scene.geometry.clamp is None and len(result.mesh.pinned) == 0


def test_a_sphere_octant_from_a_mesh_file_held_by_three_symmetry_planes_inflates_to_the_exact_radius(octant_dir):
    """Curved quadratic tetrahedra (4 divisions, 2 layers): 0.2 % from the exact r(A)/A (the left clamp: 1.106)."""
    result = tp.simulate(tp.load_scene(scene_file(octant_dir, octant_text(), "octant")))
    inner = np.flatnonzero(np.abs(np.linalg.norm(result.mesh.vertices, axis=1) - INNER) < 1e-9)
    stretch = stretches(result, inner).mean()
    assert result.converged and stretch == pytest.approx(exact_inner_stretch(3), rel=5e-3)
    assert len(result.mesh.pinned) == 0


@pytest.mark.parametrize(
    "supports, free",
    [
        ("", "translation along x, translation along y, rotation about z"),
        (ROLLER.format([1.0, 0.0], [0.0, 0.0]), "translation along y"),
        (ROLLER.format([1.0, 1.0], [0.0, 0.0]), "translation along [0.707, -0.707], rotation about z"),
        (ROLLER.format([1.0, 0.0], [0.0, 0.0]) + ROLLER.format([1.0, 0.0], [2.0, 0.0]), "translation along y"),
    ],
    ids=["none", "a roller on x = 0", "a slanted roller through one vertex", "rollers on two parallel edges"],
)
def test_a_body_whose_supports_leave_a_motion_free_is_refused_naming_it(tmp_path, supports, free):
    scene = tp.load_scene(scene_file(tmp_path, block_text(supports)))
    with pytest.raises(PneumaInputError, match=f"leave free: {re.escape(free)};"):
        scene.build()


def test_a_3d_body_from_a_mesh_file_without_its_clamp_is_refused_naming_the_six_free_motions():
    scene = tp.load_scene("beam_3d")
    loose = replace(scene, geometry=replace(scene.geometry, clamp=None))
    with pytest.raises(
        PneumaInputError,
        match="leave free: translation along x, translation along y, translation "
        "along z, rotation about x, rotation about y, rotation about z;",
    ):
        loose.build()


def test_a_clamp_at_one_vertex_leaves_the_rotation_about_it_free():
    geometry = Geometry(
        Rectangle((0.0, 0.0), (1.0, 0.4)),
        (("c", Ellipse((0.0, 0.0), (0.2, 0.1), 16)),),
        0.02,
        PointSet(box=(-0.51, -0.21, -0.49, -0.19)),
    )
    scene = Scene(geometry, (ChamberControl(area_ramp(1.2, 2, 1e5)),), 1)
    with pytest.raises(PneumaInputError, match=r"\(clamp 1 vertices\) leave free: rotation about z;"):
        scene.build()


def test_the_ground_holds_a_body_under_gravity_only_normal_to_it():
    """A frictionless ground holds the vertical translation and the tilt of a body its weight presses on it,
    never the sliding along it; without gravity, nothing."""
    body = Geometry(Rectangle((0.0, 0.0), (1.0, 0.4)), (("c", Ellipse((0.0, 0.0), (0.2, 0.1), 16)),), 0.02)
    scene = Scene(body, (ChamberControl(area_ramp(1.2, 2, 1e5)),), 1)
    with pytest.raises(PneumaInputError, match=r"\(no clamp, ground\) leave free: translation along x;"):
        replace(scene, effects=(Gravity(1.0), Ground(-0.25))).build()
    with pytest.raises(PneumaInputError, match="leave free: translation along x, translation along y, rotation"):
        replace(scene, effects=(Ground(-0.25),)).build()


def test_the_first_line_lists_the_supports_and_a_refused_scene_exits_2(tmp_path, capsys):
    ring = scene_file(tmp_path, ring_text(increments=2), "ring")
    assert inflate.main(["--scene", str(ring), "--out", str(tmp_path / "out"), "--no-video", "--quiet"]) == 0
    first = capsys.readouterr().out.splitlines()[0]
    mesh = tp.load_scene(ring).geometry.mesh()
    counts = [len(nodes) for nodes, _ in mesh.rollers]
    assert f"; no clamp, roller [1, 0] {counts[0]} vertices, roller [0, 1] {counts[1]} vertices; terms: " in first
    assert "clamp," not in first.split("terms:")[1]
    loose = scene_file(tmp_path, block_text(""), "loose")
    assert inflate.main(["--scene", str(loose), "--out", str(tmp_path / "out2"), "--no-video"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [
        "error: the supports (no clamp) leave free: translation along x, translation along y, rotation "
        "about z; a static body needs a [clamp] (side or box) or [[rollers]] that hold every rigid motion"
    ]


def test_no_clamp_survives_the_scene_file_round_trip(tmp_path):
    scene = tp.load_scene(scene_file(tmp_path, ring_text()))
    text = scene.to_toml()
    assert "[clamp]" not in text
    assert tp.load_scene(scene_file(tmp_path, text, "again")) == scene
    stiff = scene.with_value("clamp.stiffness", 1e7)
    assert stiff.geometry.clamp is None and stiff.clamp_stiffness == 1e7
    again = tp.load_scene(scene_file(tmp_path, stiff.to_toml(), "stiff"))
    assert again == stiff and again.geometry.clamp is None
    clamped = scene.with_value("clamp.side", "left")
    assert clamped.geometry.clamp == PointSet("left")
    assert tp.load_scene(scene_file(tmp_path, clamped.to_toml(), "clamped")).geometry.clamp == PointSet("left")


def test_geometries_have_no_clamp_unless_given_and_the_reference_beam_keeps_its_left_clamp():
    assert Geometry(Rectangle((0.0, 0.0), (1.0, 0.4)), ()).clamp is None
    assert BeamGeometry().general().clamp == PointSet("left")
    mesh = tp.reference_scene().build().mesh
    assert np.array_equal(mesh.pinned, np.flatnonzero(mesh.vertices[:, 0] <= mesh.vertices[:, 0].min() + 1e-6))


def test_switching_the_chamber_kind_from_the_command_line_drops_the_old_kinds_defaults(tmp_path, capsys):
    """--set chambers[0].control=pressure on the area-controlled reference beam: its default stiffness is no
    longer an 'unknown key'; the chamber is pressure-controlled, its keyframes now pressures."""
    flags = [
        "--scene",
        "reference_beam",
        "--set",
        "chambers[0].control=pressure",
        "--set",
        "chambers[0].keyframes=[[0, 0.0], [2, 50.0]]",
        "--set",
        "schedule.increments=2",
        "--set",
        "mesh.max_area=0.02",
        "--out",
        str(tmp_path / "out"),
        "--no-video",
        "--quiet",
    ]
    assert inflate.main(flags) == 0
    assert "chamber main: pressure control" in capsys.readouterr().out


def test_switching_a_variant_through_the_api_keeps_what_the_user_set_and_refuses_what_the_new_kind_lacks():
    scene = tp.reference_scene()
    assert scene.with_value("chambers[0].control", "pressure").controls[0].kind.name == "pressure"
    with pytest.raises(PneumaInputError, match=r"unknown key 'chambers\[0\].stiffness'"):
        scene.with_values({"chambers[0].control": "pressure", "chambers[0].stiffness": 2e5})
    square = ((-0.3, 0.1), (0.3, 0.1), (0.3, 0.2), (-0.3, 0.2))
    polygon = scene.with_values({"chambers[0].shape": "polygon", "chambers[0].points": square})
    assert polygon.geometry.chambers[0][1].points == square  # the ellipse's points = 128 dropped, not refused
    rounded = scene.with_values(
        {"chambers[0].shape": "rounded_rectangle", "chambers[0].size": [1.0, 0.3], "chambers[0].radius": 0.1}
    )
    assert rounded.geometry.chambers[0][1].center == (0.0, 0.15)  # a key both shapes have keeps its value
    gas = scene.with_value("chambers[0].control", "closed_gas").with_values(
        {"chambers[0].control": "syringe", "chambers[0].syringe_volume": 10.0}
    )
    assert gas.controls[0].kind.syringe_volume == 10.0


def test_switching_the_material_form_drops_the_old_forms_keys():
    """The [material] is a preset, a form of the isochoric law, or E and nu: setting law or preset drops the old
    form's keys the new one lacks (E = 1e4 and nu = 0.45, written out though never given, refused before)."""
    scene = tp.reference_scene()
    law = scene.with_values({"material.law": "yeoh", "material.C10": 1000.0, "material.C20": 10.0})
    assert (law.material.law, law.material.C20, law.material.poisson_ratio) == ("yeoh", 10.0, None)  # nu: the law's
    assert law.with_value("material.law", "neo_hookean").material.C20 == 0.0
    preset = law.with_values({"units": "mm-kPa", "material.preset": "ecoflex_00_30"})
    assert preset.material.preset == "ecoflex_00_30"
    back = preset.with_values({"material.law": "neo_hookean", "material.C10": 5.0})
    assert back.material.law == "neo_hookean" and back.material.C10 == 5.0
    with pytest.raises(PneumaInputError, match="material.E = 20000.0: .*takes C10, ... and K or nu, not E"):
        law.with_value("material.E", 2e4)  # not a switch: a key the law lacks
