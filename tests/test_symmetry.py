"""Chambers cut by symmetry lines: the half model of the centred chamber (cy = 0) against the full model.

The half beam y >= 0 (3.5 x 0.4) has the upper half of the 0.85 x 0.22 ellipse cut out of its bottom edge,
rollers (u_y = 0) on that edge, and the chamber closed by it. It must give the figures of

(a) the full model meshed by mirroring the half mesh about y = 0 (the same nodes, mirrored): to 1e-8. The
    half model's chamber stiffness is 2k (its area is half, so p = 2k (A*/2 - A/2) is the full model's
    k (A* - A)); the penalty clamp and rollers hold their nodes to reaction / K, which the full model has
    no counterpart for at the mirror line, so both use K = 1e13 (the difference scales as 1 / K: 1e-6 of
    the displacements at the default K = 1e9, 1e-10 at 1e13);
(b) the ordinary full mesh from Triangle at the same max_area and chamber polygon: within its meshing
    difference, measured at max_area 0.01: tip dx 2.6 %, pressure 0.35 %, chamber area 2e-5 (at the
    reference mesh, max_area 0.0012: 0.46 %, 0.04 %). Its mesh is not symmetric and bends the beam a
    little (tip dy 0.008 against tip dx 0.09 here; -0.001 at the reference mesh), which a half model
    cannot do.
"""

import numpy as np
import pytest
from solid_meshes import MeshOf

from taichi_pneuma.errors import PneumaInputError
from taichi_pneuma.fem.mesh import Mesh
from taichi_pneuma.fem.planar import BeamGeometry, Geometry
from taichi_pneuma.fem.polygons import enclosed_area, signed_area
from taichi_pneuma.fem.shapes import Ellipse, Rectangle
from taichi_pneuma.fem.supports import PointSet, Roller
from taichi_pneuma.scene.build import ChamberControl, Scene
from taichi_pneuma.scene.schedule import area_ramp
from taichi_pneuma.solve.newton import NewtonOptions
from taichi_pneuma.solve.sensitivity import sensitivity
from taichi_pneuma.solve.simulate import run_schedule

MAX_AREA, POINTS, STEPS, K = 0.01, 64, 8, 1e5
MIRROR = Roller((0.0, 1.0), (0.0, 0.0))
ELLIPSE = Ellipse((0.0, 0.0), (0.85, 0.22), POINTS)


def half_geometry(**kwargs) -> Geometry:
    return Geometry(
        Rectangle((0.0, 0.2), (3.5, 0.4)), (("main", ELLIPSE),), MAX_AREA, PointSet("left"), rollers=(MIRROR,), **kwargs
    )


def mirrored(half: Mesh) -> tuple[Mesh, np.ndarray]:
    """The full mesh: the half mesh and its mirror image about y = 0 sharing the nodes on the line, and the
    index of each half node's image. The tip stays the half's tip nodes, so both name the same points."""
    on_line = half.vertices[:, 1] == 0.0
    image = np.arange(half.n_vertices)
    image[~on_line] = half.n_vertices + np.arange(np.count_nonzero(~on_line))
    vertices = np.vstack([half.vertices, half.vertices[~on_line] * [1.0, -1.0]])
    triangles = np.vstack([half.triangles, image[half.triangles][:, [0, 2, 1]]])
    wall = half.chambers[0]
    loop = np.concatenate([wall, image[wall[-2:0:-1]]])
    return Mesh(
        vertices,
        triangles,
        (loop,),
        np.union1d(half.boundary, image[half.boundary]),
        np.union1d(half.pinned, image[half.pinned]),
        half.tip,
        (None,),
        (),
    ), image


def ramp(geometry, stiffness: float, clamp_stiffness: float):
    built = Scene(
        geometry, (ChamberControl(area_ramp(3.5, STEPS, stiffness)),), STEPS - 1, clamp_stiffness=clamp_stiffness
    ).build()
    return built, run_schedule(built, options=NewtonOptions(tol=1e-9))


@pytest.fixture(scope="module")
def models():
    half = ramp(half_geometry(), 2 * K, 1e13)
    full_mesh, image = mirrored(half[0].mesh)
    full = ramp(MeshOf(full_mesh), K, 1e13)
    ordinary = ramp(BeamGeometry(max_area=MAX_AREA, chamber_points=POINTS).general(), K, 1e9)
    return half, full, ordinary, image


def test_half_mesh_cuts_the_chamber_wall_at_the_line():
    mesh = half_geometry().mesh()
    wall = mesh.vertices[mesh.chambers[0]]
    assert wall[0].tolist() == [0.85, 0.0] and wall[-1].tolist() == [-0.85, 0.0]
    assert np.all(wall[1:-1, 1] > 0)
    assert np.allclose((wall[:, 0] / 0.85) ** 2 + (wall[:, 1] / 0.22) ** 2, 1.0, atol=1e-12)
    assert mesh.wall_origins[0][1] == 0.0
    half_polygon = signed_area(ELLIPSE.polygon()) / 2
    assert enclosed_area(wall, mesh.wall_origins[0]) == pytest.approx(half_polygon, rel=1e-12)
    assert mesh.area == pytest.approx(3.5 * 0.4 - half_polygon, rel=1e-12)
    ((held, normal),) = mesh.rollers
    assert np.array_equal(held, np.flatnonzero(mesh.vertices[:, 1] == 0.0)) and normal.tolist() == [0.0, 1.0]
    assert set(mesh.chambers[0][[0, -1]]) <= set(held)


def test_quadratic_half_mesh_wall_is_corner_midside_corner():
    mesh = half_geometry(order=2).mesh()
    wall = mesh.vertices[mesh.chambers[0]]
    assert len(wall) % 2 == 1
    assert np.allclose(np.hypot(wall[:, 0] / 0.85, wall[:, 1] / 0.22), 1.0, atol=1e-14)  # on the ellipse
    assert wall[0, 1] == wall[-1, 1] == 0.0  # the ends on the line
    chord, along = wall[2::2] - wall[0:-1:2], wall[1::2] - wall[0:-1:2]  # each midside node between its corners
    assert np.all(np.abs(np.sum(along * chord, axis=1) / np.sum(chord * chord, axis=1) - 0.5) < 0.1)
    assert enclosed_area(wall[0::2], mesh.wall_origins[0]) == pytest.approx(
        signed_area(ELLIPSE.polygon()) / 2, rel=1e-12
    )


def test_quarter_model_closes_the_chamber_at_the_lines_crossing():
    geometry = Geometry(
        Rectangle((0.875, 0.2), (1.75, 0.4)),
        (("main", ELLIPSE),),
        MAX_AREA,
        rollers=(MIRROR, Roller((1.0, 0.0), (0.0, 0.0))),
    )
    mesh = geometry.mesh()
    wall = mesh.vertices[mesh.chambers[0]]
    assert mesh.wall_origins[0].tolist() == [0.0, 0.0]
    assert {tuple(wall[0]), tuple(wall[-1])} == {(0.85, 0.0), (0.0, 0.22)}
    assert enclosed_area(wall, mesh.wall_origins[0]) == pytest.approx(signed_area(ELLIPSE.polygon()) / 4, rel=1e-12)
    assert mesh.area == pytest.approx(1.75 * 0.4 - signed_area(ELLIPSE.polygon()) / 4, rel=1e-12)


@pytest.mark.parametrize(
    "body, rollers, message",
    [
        (
            Rectangle((0.0, 0.1), (3.5, 0.2)),
            (MIRROR, Roller((0.0, 1.0), (0.0, 0.2))),
            "into one wall from line to line",
        ),
        (Rectangle((0.0, 0.2), (3.5, 0.4)), (), "not inside the body"),
        (Rectangle((0.0, 0.2), (3.5, 0.4)), (Roller((0.0, 1.0), box=(-2, -0.1, 2, 0.1)),), "not inside the body"),
    ],
    ids=["between parallel lines", "no roller", "box roller"],
)
def test_a_chamber_cut_off_a_symmetry_line_is_refused(body, rollers, message):
    with pytest.raises(PneumaInputError, match=message):
        Geometry(body, (("main", ELLIPSE),), MAX_AREA, rollers=rollers)


@pytest.mark.parametrize("order", [1, 2])
def test_open_wall_area_gradient_and_hessian_match_finite_differences(order):
    """The chamber term on an open wall: dA/dx and the energy's gradient and Hessian by central differences."""
    built = Scene(half_geometry(order=order), (ChamberControl(area_ramp(3.5, STEPS, K)),), STEPS - 1).build()
    chamber, config = built.chambers[0], built.model.config
    chamber.set_command(1.7)
    dofs = chamber.dofs
    rng = np.random.default_rng(1)
    u0 = 0.02 * rng.standard_normal(config.u.shape)
    h = 1e-6

    def at(step):
        config.u[:] = u0
        config.u.ravel()[dofs] += step
        return chamber.area(), chamber.energy(), chamber.gradient().ravel()[dofs]

    _, _, gradient = at(0.0)
    area_gradient = chamber.area_and_gradient()[1].ravel()
    hessian = np.zeros((built.model.n_dofs,) * 2)
    np.add.at(hessian, chamber.hessian_pattern(), chamber.hessian_values())
    ((low_dofs, v, c),) = chamber.low_rank()
    hessian[np.ix_(low_dofs, low_dofs)] += c * np.outer(v, v)
    steps = h * np.eye(len(dofs))
    fd = [(at(s)[:2], at(-s)[:2]) for s in steps]
    assert np.allclose([(p[0] - m[0]) / (2 * h) for p, m in fd], area_gradient, rtol=0, atol=1e-8)
    assert np.allclose([(p[1] - m[1]) / (2 * h) for p, m in fd], gradient, rtol=0, atol=1e-7 * np.abs(gradient).max())
    fd_hessian = np.array([(at(s)[2] - at(-s)[2]) / (2 * h) for s in steps]).T
    assert np.allclose(hessian[np.ix_(dofs, dofs)], fd_hessian, rtol=0, atol=1e-6 * np.abs(fd_hessian).max())


def test_half_model_equals_mirrored_full_model(models):
    (half_built, half), (full_built, full), _, image = models
    rest = half_built.mesh.vertices
    u_half = half.positions[-1] - rest
    u_full = full.positions[-1] - full_built.mesh.vertices
    scale = np.abs(u_half).max()
    assert np.abs(u_half - u_full[: len(rest)]).max() <= 1e-8 * scale
    assert np.abs(u_half - u_full[image] * [1.0, -1.0]).max() <= 1e-8 * scale
    for h, f in zip(half.steps, full.steps):
        for name in ("tip_dx", "tip_dy", "tip_rotation"):
            assert getattr(h, name) == pytest.approx(getattr(f, name), rel=1e-8)
        assert 2 * h.chambers["main"].area == pytest.approx(f.chambers["main"].area, rel=1e-8)
        assert h.chambers["main"].pressure == pytest.approx(f.chambers["main"].pressure, rel=1e-8, abs=1e-8)
    assert half.steps[-1].chambers["main"].area_ratio == pytest.approx(3.5, rel=0.01)  # less p / (k A_rest)


def test_half_model_agrees_with_the_ordinary_full_mesh(models):
    (_, half), _, (_, ordinary), _ = models
    h, o = half.steps[-1], ordinary.steps[-1]
    assert h.tip_dx == pytest.approx(o.tip_dx, rel=0.05)
    assert h.chambers["main"].pressure == pytest.approx(o.chambers["main"].pressure, rel=0.01)
    assert 2 * h.chambers["main"].area == pytest.approx(o.chambers["main"].area, rel=1e-4)


def test_named_tip_drives_history_and_sensitivities(models):
    """A tip box naming the nodes of the right edge's upper half: the history's tip and the tip Jacobian are
    the means over exactly those nodes."""
    (half_built, half), _, _, _ = models
    box = (1.7, 0.19, 1.8, 0.41)
    built = Scene(
        half_geometry(tip=PointSet(box=box)),
        (ChamberControl(area_ramp(3.5, STEPS, 2 * K)),),
        STEPS - 1,
        clamp_stiffness=1e13,
    ).build()
    rest = built.mesh.vertices
    chosen = np.flatnonzero((rest[:, 0] >= 1.7) & (rest[:, 1] >= 0.19))
    assert np.array_equal(built.mesh.tip, chosen) and len(chosen) >= 2
    u = half.positions[-1] - rest
    sens = sensitivity(built, np.array([3.5]), u)
    assert sens.tip[:2, 0] == pytest.approx(sens.displacements[chosen, :, 0].mean(axis=0), rel=1e-12)
    result = run_schedule(built, options=NewtonOptions(tol=1e-9))
    final = (result.positions[-1] - rest)[chosen]
    assert [result.steps[-1].tip_dx, result.steps[-1].tip_dy] == pytest.approx(final.mean(axis=0).tolist(), rel=1e-12)
