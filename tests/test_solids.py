"""3D solids meshed by gmsh: cavity volumes against closed forms, orientation, regions, errors, the PneuNet."""

import re
import sys

import numpy as np
import pytest

from taichi_pneuma.errors import PneumaInputError
from taichi_pneuma.fem.gmsh_mesher import MeshSizes, Solid, cavity_volume, estimate_tets, mesh_solid
from taichi_pneuma.fem.pneunet import PneuNet
from taichi_pneuma.fem.shapes import Ellipse, Polygon, Rectangle, RectangleUnion, RoundedRectangle
from taichi_pneuma.fem.solids import Box, Cylinder, Ellipsoid, Extrusion, HalfCylinder, RoundedBox

gmsh = pytest.importorskip("gmsh", reason="gmsh is not installed (pip install 'taichi-pneuma[3d]')")

BODY = Box((0.0, 0.0, 0.0), (1.6, 0.8, 0.8))


def rounded_box_volume(size, r):
    """Steiner's formula: the inner box (size - 2r) swept by a ball of radius r."""
    p, q, s = (v - 2 * r for v in size)
    return p * q * s + 2 * (p * q + q * s + s * p) * r + np.pi * (p + q + s) * r**2 + 4 / 3 * np.pi * r**3


def tet_volumes(mesh):
    x = mesh.vertices[mesh.tets]
    return np.linalg.det(x[:, 1:] - x[:, :1]) / 6


def rim(faces):
    """The vertices on edges of one face only: the rim of an open surface (none for a closed one)."""
    edges = np.sort(np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1)
    unique, counts = np.unique(edges, axis=0, return_counts=True)
    return np.unique(unique[counts == 1])


def directed_edges_pair_up(faces):
    """Each directed edge of a closed, consistently oriented surface appears once, its reverse once."""
    directed = {tuple(e) for f in faces for e in ((f[0], f[1]), (f[1], f[2]), (f[2], f[0]))}
    return len(directed) == 3 * len(faces) and all((b, a) in directed for a, b in directed)


# (chamber shape, its exact volume, its smallest radius of curvature: None for flat faces)
CHAMBERS = {
    "box": (Box((0.1, 0.0, 0.0), (0.6, 0.3, 0.4)), 0.6 * 0.3 * 0.4, None),
    "rounded_box": (RoundedBox((0.0, 0.0, 0.0), (0.8, 0.4, 0.4), 0.1), rounded_box_volume((0.8, 0.4, 0.4), 0.1), 0.1),
    "ellipsoid": (Ellipsoid((0.0, 0.05, 0.0), (0.5, 0.25, 0.2)), 4 / 3 * np.pi * 0.5 * 0.25 * 0.2, 0.08),
    "cylinder": (Cylinder((0.0, 0.0, 0.0), 0.2, 1.0, "x"), np.pi * 0.2**2 * 1.0, 0.2),
    "half_cylinder": (HalfCylinder((0.0, -0.1, 0.0), 0.25, 1.0, "x"), np.pi * 0.25**2 / 2 * 1.0, 0.25),
    "extruded_ellipse": (Extrusion(Ellipse((0.0, 0.0), (0.2, 0.3)), 0.5), np.pi * 0.2 * 0.3 * 0.5, 0.13),
    "extruded_rounded_rectangle": (
        Extrusion(RoundedRectangle((0.0, 0.0), (0.8, 0.4), 0.1), 0.5),
        (0.8 * 0.4 - (4 - np.pi) * 0.01) * 0.5,
        0.1,
    ),
    "extruded_polygon": (
        Extrusion(Polygon(((-0.4, -0.2), (0.4, -0.2), (0.0, 0.25))), 0.4, z=0.1),
        0.5 * 0.8 * 0.45 * 0.4,
        None,
    ),
}


@pytest.mark.parametrize("name", list(CHAMBERS))
def test_cavity_volume_and_orientation(name):
    """The wall triangles enclose the chamber's closed-form volume (exactly for flat faces, to O(h^2 / R^2)
    for curved ones), oriented outward from the cavity: a closed surface whose 1/3 int x . n dA is the
    positive cavity volume; tetrahedra are positive and, with the outer boundary (oriented outward from the
    body), fill exactly the volume the boundary encloses minus the cavity."""
    shape, exact, radius = CHAMBERS[name]
    h = 0.1
    mesh = mesh_solid(Solid(BODY, (("c", shape),)), MeshSizes(0.25, near_chambers=h, distance=0.1))
    wall = mesh.chambers["c"]
    volume = cavity_volume(mesh.vertices, wall)
    assert volume > 0
    if radius is None:
        assert volume == pytest.approx(exact, rel=1e-12)
    else:
        assert abs(volume - exact) / exact < 0.5 * (h / radius) ** 2
        assert volume < exact  # the triangles' corners lie on the convex curved surface: an inscribed polyhedron
    assert len(rim(wall)) == 0 and directed_edges_pair_up(wall) and directed_edges_pair_up(mesh.boundary)
    assert np.all(tet_volumes(mesh) > 0)
    enclosed = cavity_volume(mesh.vertices, mesh.boundary)
    assert enclosed == pytest.approx(BODY.size[0] * BODY.size[1] * BODY.size[2], rel=1e-12)
    assert tet_volumes(mesh).sum() == pytest.approx(enclosed - volume, rel=1e-12)
    assert mesh.vertices.shape[1] == 3 and len(np.unique(mesh.tets)) == len(mesh.vertices)


@pytest.mark.parametrize("name", ["ellipsoid", "cylinder"])
def test_cavity_volume_converges_at_second_order(name):
    """Halving the wall's mesh size cuts the volume error about four times (linear triangles on a curved
    surface: an O(h^2) gap); observed order between 1.6 and 2.6."""
    shape, exact, _ = CHAMBERS[name]
    errors = [
        abs(cavity_volume(m.vertices, m.chambers["c"]) - exact)
        for m in (
            mesh_solid(Solid(BODY, (("c", shape),)), MeshSizes(0.3, near_chambers=h, distance=0.05))
            for h in (0.1, 0.05)
        )
    ]
    assert 1.6 < np.log2(errors[0] / errors[1]) < 2.6


@pytest.mark.parametrize(
    "body, volume",
    [
        (Cylinder((0.0, 0.0, 0.0), 0.6, 2.0, "x"), np.pi * 0.36 * 2.0),
        (HalfCylinder((0.0, -0.2, 0.0), 0.6, 2.0, "x", base=0.3), (np.pi * 0.36 / 2 + 1.2 * 0.3) * 2.0),
        (Extrusion(Rectangle((0.0, 0.0), (2.0, 1.2)), 1.0), 2.4),
        (
            Extrusion(RectangleUnion((Rectangle((0.0, 0.0), (2.0, 1.2)), Rectangle((0.5, 0.9), (1.0, 0.6)))), 1.0),
            2.4 + 1.0 * 0.6,
        ),
        (Extrusion(Polygon(((-1.0, -0.6), (1.0, -0.6), (1.2, 0.6), (-1.0, 0.8))), 1.0), 2.74),  # shoelace area x depth
    ],
)
def test_bodies_mesh_to_their_volume(body, volume):
    """Every body shape: the tetrahedra fill its volume (exactly for flat faces) around a box chamber."""
    chamber = Box((0.0, 0.0, 0.0), (0.4, 0.3, 0.3))
    mesh = mesh_solid(Solid(body, (("c", chamber),)), MeshSizes(0.2, near_chambers=0.1))
    filled = tet_volumes(mesh).sum() + cavity_volume(mesh.vertices, mesh.chambers["c"])
    tolerance = 1e-12 if not isinstance(body, (Cylinder, HalfCylinder)) else 0.5 * (0.2 / 0.6) ** 2
    assert filled == pytest.approx(volume, rel=tolerance)


def test_regions_are_the_parts_of_the_body_inside_their_shapes():
    """Tetrahedra tagged k are those inside region k's shape (a later region wins), and fill its
    intersection with the body exactly; the interfaces are conforming (no tetrahedron straddles them)."""
    bottom = Box((0.0, -0.3, 0.0), (1.6, 0.2, 0.8))
    corner = Box((0.6, -0.3, 0.0), (0.4, 0.4, 2.0))  # overlaps the bottom slab and sticks out of the body
    mesh = mesh_solid(
        Solid(BODY, (("c", Box((0.0, 0.1, 0.0), (0.4, 0.2, 0.4))),), (("bottom", bottom), ("corner", corner))),
        MeshSizes(0.2),
    )
    assert mesh.region_names == ("bottom", "corner")
    centroid = mesh.vertices[mesh.tets].mean(axis=1)
    in_bottom = centroid[:, 1] < -0.2
    in_corner = (centroid[:, 0] > 0.4) & (centroid[:, 1] < -0.1)
    expected = np.where(in_corner, 2, np.where(in_bottom, 1, 0))
    assert np.array_equal(mesh.regions, expected)
    volumes = np.bincount(mesh.regions, weights=tet_volumes(mesh))
    assert volumes[2] == pytest.approx(0.4 * 0.3 * 0.8, rel=1e-12)
    assert volumes[1] == pytest.approx(1.6 * 0.2 * 0.8 - 0.4 * 0.2 * 0.8, rel=1e-12)


def test_chamber_cut_by_the_body_boundary_has_an_open_wall_closed_by_its_cap():
    """Half a model: an ellipsoid centred on the body's face z = 0 leaves an open wall, its rim on z = 0; the
    boundary has a hole there that the wall (reversed: outward from the rubber) fills, and with the origin
    on the plane (where x . n = 0 on the flat cap) the wall alone gives the half volume."""
    half = Box((0.0, 0.0, 0.2), (1.6, 0.8, 0.4))
    shape, exact, _ = CHAMBERS["ellipsoid"]
    mesh = mesh_solid(Solid(half, (("c", shape),)), MeshSizes(0.2, near_chambers=0.05, distance=0.05))
    wall = mesh.chambers["c"]
    edge = rim(wall)
    assert len(edge) > 0
    assert np.allclose(mesh.vertices[edge, 2], 0.0, atol=1e-12)
    assert np.all(mesh.vertices[wall].mean(axis=1)[:, 2] > 0)
    assert directed_edges_pair_up(np.vstack([wall[:, ::-1], mesh.boundary]))
    assert cavity_volume(mesh.vertices, wall) == pytest.approx(exact / 2, rel=0.02)


def test_estimate_bounds_the_count_before_meshing():
    """The estimate (volume over the regular tetrahedron of the local size) lies above gmsh's count, within
    a factor of two; a solid over the budget is refused before meshing, naming the estimate and the flag."""
    solid = Solid(BODY, (("c", CHAMBERS["ellipsoid"][0]),))
    for sizes in (MeshSizes(0.1), MeshSizes(0.25, near_chambers=0.06)):
        count = len(mesh_solid(solid, sizes).tets)
        assert 0.5 < count / estimate_tets(solid, sizes) < 1.0
    with pytest.raises(PneumaInputError, match=r"about [\d.]+e\+08 tetrahedra .* limit is 200000 .*--max-triangles"):
        mesh_solid(solid, MeshSizes(0.002))


@pytest.mark.parametrize(
    "solid, message",
    [
        (Solid(BODY, (("c", Ellipsoid((5.0, 0.0, 0.0), (0.3, 0.2, 0.2))),)), "chamber 'c' lies outside the body"),
        (
            Solid(
                BODY,
                (
                    ("a", Ellipsoid((0.0, 0.0, 0.0), (0.3, 0.2, 0.2))),
                    ("b", Ellipsoid((0.2, 0.0, 0.0), (0.3, 0.2, 0.2))),
                ),
            ),
            "chambers 'a' and 'b' overlap",
        ),
        (
            Solid(BODY, (("a", Box((-0.2, 0.0, 0.0), (0.4, 0.2, 0.2))), ("b", Box((0.2, 0.0, 0.0), (0.4, 0.2, 0.2))))),
            "chamber 'a' touches another chamber",
        ),
        (Solid(BODY, (("c", Box((0.0, 0.0, 0.0), (2.0, 1.0, 1.0))),)), "no rubber is left"),
        (
            Solid(
                BODY, (("c", Box((0.0, 0.0, 0.0), (0.2, 0.2, 0.2))),), (("r", Box((5.0, 5.0, 5.0), (1.0, 1.0, 1.0))),)
            ),
            "region 'r' lies outside the body",
        ),
        # two outline points 1e-13 apart: OpenCASCADE cannot make the line between them
        (
            Solid(
                BODY, (("c", Extrusion(Polygon(((0.0, 0.0), (0.3, 0.0), (0.3, 1e-13), (0.3, 0.2), (0.0, 0.2))), 0.3)),)
            ),
            "gmsh could not mesh the solid: .*Could not create line",
        ),
    ],
)
def test_bad_solids_are_one_clear_error_and_leave_gmsh_finalised(solid, message):
    with pytest.raises(PneumaInputError, match=message):
        mesh_solid(solid, MeshSizes(0.2))
    assert not gmsh.isInitialized()


@pytest.mark.parametrize(
    "make, message",
    [
        (lambda: Solid(BODY, (("body", Box((0, 0, 0), (0.2, 0.2, 0.2))),)), "names .* other than 'body'"),
        (
            lambda: Solid(BODY, (("a", Box((0, 0, 0), (0.2, 0.2, 0.2))),), (("a", Box((0, 0, 0), (1, 1, 1))),)),
            "distinct",
        ),
        (lambda: Solid((1, 2), ()), "body: .* is not a 3D shape"),
        (lambda: MeshSizes(0.1, near_chambers=-0.2), r"near_chambers = -0.2 must be > 0"),
        (lambda: MeshSizes(float("nan")), "size = nan must be a finite number"),
        (lambda: Box((0, 0, 0), (1, -1, 1)), "size = .* must be > 0"),
        (lambda: Box((0, 0), (1, 1, 1)), r"center = \(0, 0\) must be three numbers"),
        (lambda: RoundedBox((0, 0, 0), (1, 1, 0.4), 0.2), r"radius = 0.2 must lie in \(0, 0.2\)"),
        (lambda: Cylinder((0, 0, 0), 0.1, 1.0, "w"), "axis = 'w' is not one of x, y, z"),
        (lambda: HalfCylinder((0, 0, 0), 0.1, 1.0, "y"), "axis = 'y' is not one of x, z"),
        (lambda: HalfCylinder((0, 0, 0), 0.1, 1.0, "x", base=-0.1), "base = -0.1 must be >= 0"),
        (lambda: Extrusion("circle", 1.0), "is not a 2D shape"),
        (lambda: PneuNet(chambers=0), "chambers = 0 must be an integer from 1 to 64"),
        (lambda: PneuNet(chambers=2.5), "chambers = 2.5 must be an integer"),
        (lambda: PneuNet(gap=-0.1), "gap = -0.1 must be > 0"),
        (lambda: PneuNet(radius=0.3), r"radius = 0.3 must be < 0.2 \(half the chamber's shortest side\)"),
    ],
)
def test_bad_parameters_are_named(make, message):
    with pytest.raises(PneumaInputError, match=message):
        make()


def test_caller_gmsh_session_is_left_as_it_was():
    """With gmsh already initialised by the caller, meshing works in a model of its own and removes only it,
    leaving the caller's current model and options as they were."""
    gmsh.initialize(readConfigFiles=False, interruptible=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.option.setNumber("Mesh.MeshSizeMax", 7.0)
        gmsh.model.add("users_model")
        mesh_solid(Solid(BODY, (("c", Box((0, 0, 0), (0.2, 0.2, 0.2))),)), MeshSizes(0.3))
        assert gmsh.isInitialized() and gmsh.model.list() == ["", "users_model"]
        assert gmsh.model.getCurrent() == "users_model" and gmsh.option.getNumber("Mesh.MeshSizeMax") == 7.0
    finally:
        gmsh.finalize()


def test_missing_gmsh_names_the_install_command(monkeypatch):
    monkeypatch.setitem(sys.modules, "gmsh", None)  # import gmsh now raises ImportError
    with pytest.raises(PneumaInputError, match=r"gmsh, which is not installed: pip install 'taichi-pneuma\[3d\]'"):
        mesh_solid(Solid(BODY, ()), MeshSizes(0.3))


def test_pneunet_dimensions_chambers_and_layer():
    """The generated finger: its bounding box is the stated size, chambers c1..c6 left to right each enclose
    the rounded box's volume (to O(h^2)), the region 'layer' is exactly the bottom slab."""
    finger = PneuNet()
    length, height, width = finger.size
    assert (length, height, width) == pytest.approx((4.0, 0.8, 0.76))
    mesh = mesh_solid(finger.solid(), MeshSizes(0.2, near_chambers=0.05, distance=0.05))
    assert np.allclose(mesh.vertices.min(axis=0), [-2.0, -0.4, -0.38])
    assert np.allclose(mesh.vertices.max(axis=0), [2.0, 0.4, 0.38])
    assert list(mesh.chambers) == [f"c{i}" for i in range(1, 7)] and mesh.region_names == ("layer",)
    exact = rounded_box_volume((0.4, 0.5, 0.6), 0.08)
    centres = []
    for wall in mesh.chambers.values():
        volume = cavity_volume(mesh.vertices, wall)
        assert 0 < exact - volume < 0.5 * (0.05 / 0.08) ** 2 * exact
        centres.append(mesh.vertices[np.unique(wall)].mean(axis=0))
    assert np.allclose(np.array(centres)[:, 0], -1.25 + 0.5 * np.arange(6), atol=0.01)
    centroid_y = mesh.vertices[mesh.tets].mean(axis=1)[:, 1]
    assert np.array_equal(mesh.regions == 1, centroid_y < -0.25)
    assert tet_volumes(mesh)[mesh.regions == 1].sum() == pytest.approx(4.0 * 0.15 * 0.76, rel=1e-12)


def test_pneunet_without_layer_or_rounding():
    mesh = mesh_solid(PneuNet(chambers=2, radius=0.0, layer=0.0, end=0.2).solid(), MeshSizes(0.2))
    assert mesh.region_names == () and not mesh.regions.any()
    for wall in mesh.chambers.values():
        assert cavity_volume(mesh.vertices, wall) == pytest.approx(0.4 * 0.5 * 0.6, rel=1e-12)


def test_shipped_scene_maps_one_to_one_onto_the_generator():
    """The shipped pneunet_3d.toml: its [body] keys are PneuNet's fields, its [mesh] keys MeshSizes' (and the
    order), its chambers and its region name the generated solid's surface and volume groups."""
    import dataclasses
    import tomllib
    from pathlib import Path

    scene = tomllib.loads((Path(__file__).parents[1] / "taichi_pneuma/scenes/pneunet_3d.toml").read_text())
    body = {k: v for k, v in scene["body"].items() if k != "shape"}
    assert scene["body"]["shape"] == "pneunet" and set(body) == {f.name for f in dataclasses.fields(PneuNet)}
    mesh = {k: v for k, v in scene["mesh"].items() if k != "order"}
    assert set(mesh) <= {f.name for f in dataclasses.fields(MeshSizes)}
    solid, _ = PneuNet(**body).solid(), MeshSizes(**mesh)
    assert [c["group"] for c in scene["chambers"]] == [name for name, _ in solid.chambers]
    assert [r["group"] for r in scene["material"]["regions"]] == [name for name, _ in solid.regions]


def test_a_filleted_half_cylinder_loses_a_quarter_round_along_every_edge():
    """fillet = f rounds all six edges (two long ones where the flat face meets the round side, and at each end
    the half circle and the diameter, all right angles): each loses the cross-section (1 - pi/4) f^2 between the
    edge and its quarter round, along the edge's length, about the half circle's at the radius of that
    cross-section's centroid, R - (10 - 3 pi) / (12 - 3 pi) f (Pappus); the corners, where the fillets meet,
    differ by O(f^3). A missed edge would lose 7 f^3 or more less."""
    from taichi_pneuma.fem.gmsh_session import session as _session

    R, L, f = 0.5, 2.0, 0.04
    corner = (1 - np.pi / 4) * f**2
    centroid = R - (10 - 3 * np.pi) / (12 - 3 * np.pi) * f
    removed = corner * (2 * L + 2 * 2 * R) + corner * 2 * np.pi * centroid
    with _session() as session:
        occ = session.model.occ
        sharp = HalfCylinder((0.0, 0.0, 0.0), R, L, "x").build(occ)
        rounded = HalfCylinder((0.0, 0.0, 3.0), R, L, "x", fillet=f).build(occ)
        occ.synchronize()
        lost = occ.getMass(3, sharp) - occ.getMass(3, rounded)
    assert lost == pytest.approx(removed, abs=4 * f**3)  # measured: 2.1-2.8 f^3 at f = 0.02-0.08


@pytest.mark.parametrize(
    "keys, message",
    [({"fillet": 0.3}, "fillet = 0.3 must lie in [0, 0.25)"), ({"fillet": 0.1, "base": 0.2}, "takes base = 0")],
)
def test_a_fillet_too_large_or_on_a_base_is_refused(keys, message):
    with pytest.raises(PneumaInputError, match=re.escape(message)):
        HalfCylinder((0.0, 0.0, 0.0), 0.5, 2.0, "x", **keys)
