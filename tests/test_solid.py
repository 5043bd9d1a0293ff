"""3D bodies: tetrahedral meshes from arrays, every 3D term against finite differences, the enclosed volume against
independent computations, the patch test, the inversion bound, ground contact under gravity, and the refusals."""

import numpy as np
import pytest
from fd import dense_hessian, fd_gradient, fd_hessian
from solid_meshes import PLANES, Z_ROLLERS, extruded_beam, scene_of, shell_octant

import taichi_pneuma as tp
from taichi_pneuma.errors import PneumaInputError
from taichi_pneuma.fem.elements import TET_EDGES, TRIANGLE_P2, boundary_facets
from taichi_pneuma.fem.layered import spherical_shell_octant
from taichi_pneuma.fem.supports import PointSet, Roller
from taichi_pneuma.fem.tetmesh import tet_mesh
from taichi_pneuma.limits import Budget
from taichi_pneuma.materials import StableNeoHookean
from taichi_pneuma.scene.build import Material
from taichi_pneuma.scene.schedule import ChamberSchedule
from taichi_pneuma.solve.newton import NewtonSolver
from taichi_pneuma.terms import Clamp, Elasticity, NormalClamp
from taichi_pneuma.terms.base import Term
from taichi_pneuma.terms.chambers import AreaControl, PressureControl
from taichi_pneuma.terms.effects import Gravity, Ground, SelfContact
from taichi_pneuma.terms.model import EnergyModel

RNG = np.random.default_rng(3)


def tet_volumes(points, tets):
    """Signed volume of each tetrahedron's corners, det[x1 - x0, x2 - x0, x3 - x0] / 6."""
    x = points[tets[:, :4]]
    return np.linalg.det(np.stack([x[:, 1] - x[:, 0], x[:, 2] - x[:, 0], x[:, 3] - x[:, 0]], axis=2)) / 6


def cone_volume(points, triangles, origin=(0.0, 0.0, 0.0)):
    """1/6 sum (x0 - o) . ((x1 - o) x (x2 - o)) over flat triangles: the volume a closed surface encloses."""
    x0, x1, x2 = (points[triangles[:, i]] - origin for i in range(3))
    return float(np.einsum("ij,ij->i", x0, np.cross(x1, x2)).sum() / 6)


def test_tet_mesh_orients_drops_unused_nodes_and_adds_midside_nodes():
    vertices, tets, wall = spherical_shell_octant(1.0, 2.0, 2, 1)
    mixed = tets.copy()
    mixed[::2] = mixed[::2][:, [0, 2, 1, 3]]  # every other tetrahedron inside out
    padded = np.vstack([vertices, [[9.0, 9.0, 9.0]]])  # a node no tetrahedron uses
    volume = np.abs(tet_volumes(vertices, tets)).sum()
    edges = len(np.unique(np.sort(np.vstack([tets[:, list(e)] for e in TET_EDGES]), axis=1), axis=0))
    for order in (1, 2):
        mesh = tet_mesh(padded, mixed, {"c": wall[:, ::-1]}, order=order, clamp=None, rollers=PLANES)
        assert mesh.n_vertices == len(vertices) + (edges if order == 2 else 0)
        assert np.all(tet_volumes(mesh.vertices, mesh.elements) > 0) and mesh.volume == pytest.approx(volume, rel=1e-12)
        assert mesh.nodal_measures().sum() == pytest.approx(volume, rel=1e-12)
        # the surface facets point out of the body: the divergence theorem gives its volume
        assert cone_volume(mesh.vertices, mesh.surface) == pytest.approx(volume, rel=1e-12)
        # the chamber wall (given inside out) points out of the cavity: cones from the origin fill the cavity
        assert (
            cone_volume(mesh.vertices, mesh.chambers[0]) == pytest.approx(abs(cone_volume(vertices, wall)), rel=1e-12)
            and cone_volume(mesh.vertices, mesh.chambers[0]) > 0
        )
        assert np.array_equal(
            np.unique(np.concatenate([mesh.boundary, mesh.chambers[0].ravel()])), np.unique(mesh.surface)
        )
        if order == 2:
            for k, (i, j) in enumerate(TET_EDGES):
                middle = 0.5 * (mesh.vertices[mesh.elements[:, i]] + mesh.vertices[mesh.elements[:, j]])
                assert np.allclose(mesh.vertices[mesh.elements[:, 4 + k]], middle, atol=1e-15)
            corners = np.zeros(mesh.n_vertices, dtype=bool)
            corners[mesh.elements[:, :4]] = True  # the consistent load of a quadratic tetrahedron: -V/20 at corners
            assert np.all(mesh.nodal_measures()[corners] < 0) and np.all(mesh.nodal_measures()[~corners] > 0)


def test_quadratic_boundary_facets_are_the_midside_nodes_of_their_edges():
    mesh = shell_octant(2, 1, order=2)
    for facets in (boundary_facets(mesh.family, mesh.elements), *mesh.chambers):
        x = mesh.vertices[facets]
        for k in range(3):
            assert np.allclose(x[:, 3 + k], 0.5 * (x[:, k] + x[:, (k + 1) % 3]), atol=1e-15)


@pytest.mark.parametrize(
    "case, message",
    [
        ("interior face", "is not a face on the mesh's boundary"),
        ("open wall", "lies on no roller plane"),
        ("gmsh order", "node 8 is not near the middle of edge 13"),
        ("quadratic as linear", "set order = 2"),
        ("flat", "is flat"),
        ("2D points", "vertices must be finite"),
        ("bad index", "names a vertex that does not exist"),
        ("shared wall", "shares wall triangles"),
    ],
)
def test_bad_mesh_data_is_refused_naming_the_problem(case, message):
    vertices, tets, wall = spherical_shell_octant(1.0, 2.0, 2, 2)
    arguments = dict(clamp=None, rollers=PLANES)
    chambers = {"c": wall}
    if case == "interior face":
        chambers = {"c": tets[:1, [0, 1, 3]]}  # a face the prism split shares between two tetrahedra
    elif case == "open wall":
        arguments["rollers"] = PLANES[:2]
    elif case == "gmsh order":
        quadratic = shell_octant(2, 2, order=2)
        vertices, tets = quadratic.vertices, quadratic.elements[:, [0, 1, 2, 3, 4, 5, 6, 7, 9, 8]]
        chambers, arguments["order"] = {"c": quadratic.chambers[0]}, 2
    elif case == "quadratic as linear":
        quadratic = shell_octant(2, 2, order=2)
        vertices, tets, chambers = quadratic.vertices, quadratic.elements, {"c": quadratic.chambers[0]}
    elif case == "flat":
        vertices = vertices.copy()
        vertices[tets[0, 3]] = vertices[tets[0, :3]].mean(axis=0)
    elif case == "2D points":
        vertices = vertices[:, :2]
    elif case == "bad index":
        tets = tets.copy()
        tets[0, 0] = len(vertices)
    elif case == "shared wall":
        chambers = {"a": wall, "b": wall[:1]}
    with pytest.raises(PneumaInputError, match=message):
        tet_mesh(vertices, tets, chambers, **arguments)


def state(mesh, scale, seed):
    return scale * np.random.default_rng(seed).standard_normal(mesh.vertices.shape)


@pytest.mark.parametrize("order", [1, 2])
@pytest.mark.parametrize("body", ["shell", "prism"])
def test_every_3d_term_matches_finite_differences(body, order):
    """Elasticity, the chamber (volume control, a wall closed by three symmetry planes or by two parallel ones),
    the clamp, a roller, gravity and the ground: gradients and the exact Hessian against central differences."""
    mesh = shell_octant(2, 1, order) if body == "shell" else extruded_beam(0.4, order, chamber_points=8)[0]
    model = EnergyModel(mesh.vertices, force_floor=1.0, energy_resolution=1e-12)
    config = model.config
    n = mesh.n_elements
    elastic = model.add(
        Elasticity(
            config, mesh.elements, StableNeoHookean, StableNeoHookean.parameters(np.full(n, 1e4), np.full(n, 0.45))
        )
    )
    chamber = model.add(AreaControl(1e4).term(config, mesh.chambers[0], "c", order, mesh.wall_origins[0]))
    chamber.set_command(1.4)
    pinned = mesh.tip if body == "prism" else mesh.boundary[:5]
    others = [
        model.add(Clamp(config, pinned, 1e3)),
        model.add(NormalClamp(config, mesh.boundary[::3], (1.0, 2.0, 2.0), 1e3)),
    ]
    others += Gravity(2.0, 3.0).terms(config, mesh, mesh.nodal_measures(), Budget())
    lowest = mesh.vertices[mesh.boundary, 1].min()
    ground = Ground(lowest - 0.02, dhat=0.05, stiffness=10.0)
    others += [model.add(t) for t in ground.terms(config, mesh, None, Budget())]
    model.add(others[2])
    u = state(mesh, 0.01, order)
    model.set_displacements(u)
    assert others[-1].energy() > 0  # the ground's barrier is active
    for term in [elastic, chamber, *others]:
        g = term.gradient().ravel()
        assert np.linalg.norm(g - fd_gradient(model, term, u)) <= 1e-6 * np.linalg.norm(g), term.name
    hessian = dense_hessian(model.n_dofs, model.terms, psd_only=False)
    assert np.linalg.norm(hessian - fd_hessian(model, model.terms, u)) < 1e-6 * np.linalg.norm(hessian)
    assert np.allclose(hessian, hessian.T, atol=1e-9 * np.abs(hessian).max())
    projected = dense_hessian(model.n_dofs, [elastic], psd_only=True)
    assert np.linalg.eigvalsh(projected).min() > -1e-9 * np.abs(projected).max()


def test_enclosed_volume_of_a_closed_wall_is_the_body_volume_it_bounds():
    """The body's own surface taken as a wall (facing out of the body, as a chamber's wall faces out of its cavity,
    so that it encloses a positive volume): its volume is the sum of the tetrahedra's, at rest and moved."""
    mesh = shell_octant(3, 2)
    model = EnergyModel(mesh.vertices, 1.0, 1e-12)
    wall = model.add(PressureControl().term(model.config, mesh.surface, "body", 1))
    for scale in (0.0, 0.05):
        u = state(mesh, scale, 1)
        model.set_displacements(u)
        assert wall.area() == pytest.approx(tet_volumes(mesh.vertices + u, mesh.elements).sum(), rel=1e-12)


def test_curved_quadratic_wall_volume_is_exact():
    """Quadratic triangles with their midside nodes on the sphere (a curved 10-node mesh, read as is): the volume
    equals an independent quadrature of 1/3 int x . n dA with a Gauss rule of degree 9 on the collapsed square."""
    mesh = shell_octant(2, 1, order=2)
    vertices = mesh.vertices.copy()
    inner = np.unique(mesh.chambers[0])
    vertices[inner] /= np.linalg.norm(vertices[inner], axis=1, keepdims=True)  # the wall's nodes onto the sphere r = 1
    curved = tet_mesh(vertices, mesh.elements, {"c": mesh.chambers[0]}, order=2, clamp=None, rollers=PLANES)
    model = EnergyModel(curved.vertices, 1.0, 1e-12)
    chamber = model.add(PressureControl().term(model.config, curved.chambers[0], "c", 2, curved.wall_origins[0]))
    u = state(curved, 0.03, 2)
    model.set_displacements(u)
    s, w = np.polynomial.legendre.leggauss(5)
    s, w = 0.5 * (s + 1), 0.5 * w
    a, b = np.meshgrid(s, s, indexing="ij")  # (xi, eta) = (a, b (1 - a)), Jacobian 1 - a
    points = np.column_stack([a.ravel(), (b * (1 - a)).ravel()])
    weights = (np.outer(w, w) * (1 - a)).ravel()
    N, dN = TRIANGLE_P2.shape_functions(points), TRIANGLE_P2.shape_gradients(points)
    x = (curved.vertices + u)[curved.chambers[0]]  # (f, 6, 3)
    y, s_, t_ = (
        np.einsum("qa,fai->fqi", N, x),
        np.einsum("qa,fai->fqi", dN[:, :, 0], x),
        np.einsum("qa,fai->fqi", dN[:, :, 1], x),
    )
    expected = np.einsum("q,fqi,fqi->", weights, y, np.cross(s_, t_)) / 3
    assert chamber.area() == pytest.approx(expected, rel=1e-13)
    assert abs(chamber.rest_area - np.pi / 6) < 0.1 * abs(cone_volume(mesh.vertices, mesh.chambers[0]) - np.pi / 6)


def test_symmetry_closures_give_the_volume_of_the_closed_cavity():
    """The octant's cavity closed by its three planes, and the beam's prism chamber closed by the two faces normal
    to z, against independent closed forms: the octant's wall with fan caps from the origin on the planes (a
    closed surface), and depth x the shoelace area of the beam's chamber loop (the caps' nodes moved in their
    planes only)."""
    mesh = shell_octant(3, 1)
    model = EnergyModel(mesh.vertices, 1.0, 1e-12)
    wall = mesh.chambers[0]
    chamber = model.add(PressureControl().term(model.config, wall, "c", 1, mesh.wall_origins[0]))
    u = state(mesh, 0.02, 4)
    held = [np.abs(mesh.vertices[:, axis]) < 1e-12 for axis in range(3)]
    for axis in range(3):
        u[held[axis], axis] = 0.0  # the rim slides in its planes
    model.set_displacements(u)
    closed = np.vstack([mesh.vertices + u, np.zeros(3)])  # the origin, last
    edges = np.sort(np.vstack([wall[:, [0, 1]], wall[:, [1, 2]], wall[:, [2, 0]]]), axis=1)
    unique, counts = np.unique(edges, axis=0, return_counts=True)
    caps = []
    for axis in range(3):  # a fan from the origin over the rim edges in each plane, its normal out of the cavity (-e)
        rim = unique[(counts == 1) & held[axis][unique].all(axis=1)]
        fan = np.column_stack([np.full(len(rim), len(closed) - 1), rim])
        normals = np.cross(closed[fan[:, 1]] - closed[fan[:, 0]], closed[fan[:, 2]] - closed[fan[:, 0]])
        caps.append(np.where((normals[:, axis] > 0)[:, None], fan[:, [0, 2, 1]], fan))
    surface = np.vstack([wall, *caps])
    expected = cone_volume(closed, surface, np.full(3, 0.3))
    assert cone_volume(closed, surface, np.array([0.9, -0.2, 0.4])) == pytest.approx(expected, rel=1e-12)  # closed
    assert chamber.area() == pytest.approx(expected, rel=1e-12)
    beam, planar = extruded_beam(0.1, chamber_points=16)
    model = EnergyModel(beam.vertices, 1.0, 1e-12)
    chamber = model.add(PressureControl().term(model.config, beam.chambers[0], "c", 1, beam.wall_origins[0]))
    in_plane = state(planar, 0.02, 5)
    u = np.column_stack([np.tile(in_plane, (2, 1)), np.zeros(len(beam.vertices))])
    model.set_displacements(u)
    loop = (planar.vertices + in_plane)[planar.chambers[0]]
    shoelace = 0.5 * np.sum(loop[:, 0] * np.roll(loop[:, 1], -1) - np.roll(loop[:, 0], -1) * loop[:, 1])
    assert chamber.area() == pytest.approx(0.8 * shoelace, rel=1e-12)


class HeldAt(Term):
    """1/2 K |u_i - target_i|^2 on the given nodes (over the given axes only, if any): displacements prescribed by
    a stiff penalty."""

    name = "held"

    def __init__(self, config, nodes, target, stiffness, axes=None):
        self.config, self.nodes, self.k = config, nodes, stiffness
        d = config.dim
        self.axes = np.arange(d) if axes is None else np.asarray(axes)
        self.target = np.broadcast_to(target, (len(nodes), d))[:, self.axes]
        self._dofs = (d * nodes[:, None] + self.axes).ravel()

    def _offsets(self):
        return self.config.u[np.ix_(self.nodes, self.axes)] - self.target

    def energy(self):
        return 0.5 * self.k * float(np.sum(self._offsets() ** 2))

    def gradient(self):
        g = np.zeros_like(self.config.u)
        g[np.ix_(self.nodes, self.axes)] = self.k * self._offsets()
        return g

    def hessian_pattern(self):
        return self._dofs, self._dofs

    def hessian_values(self, psd_only=False):
        return np.full(len(self._dofs), self.k)


@pytest.mark.parametrize("order", [1, 2])
def test_patch_test_a_homogeneous_deformation_is_reproduced_exactly(order):
    """x = F X (a finite stretch with shear) is an equilibrium of every interior node (its elastic force vanishes
    to round-off); with the boundary nodes held there (by a penalty of 1e13, so within 1e-10) and the interior
    started at rest, Newton finds it at every interior node."""
    mesh = shell_octant(5, 4, order)
    boundary = np.unique(mesh.surface)
    interior = np.setdiff1d(np.arange(mesh.n_vertices), boundary)
    assert len(interior) > 10
    F = np.array([[1.2, 0.1, 0.0], [0.05, 0.9, 0.1], [0.0, -0.1, 1.1]])
    target = mesh.vertices @ (F - np.eye(3)).T
    model = EnergyModel(mesh.vertices, force_floor=1e-6, energy_resolution=1e-12)
    n = mesh.n_elements
    elastic = model.add(
        Elasticity(
            model.config,
            mesh.elements,
            StableNeoHookean,
            StableNeoHookean.parameters(np.full(n, 1e4), np.full(n, 0.45)),
        )
    )
    model.set_displacements(target)
    force = elastic.gradient()
    assert np.abs(force[interior]).max() < 1e-12 * np.abs(force[boundary]).max()
    model.add(HeldAt(model.config, boundary, target[boundary], 1e13))
    u, record = NewtonSolver(model).solve(np.zeros_like(mesh.vertices))
    assert record.converged
    assert np.abs(u[interior] - target[interior]).max() < 1e-9


def test_inversion_bound_is_the_first_root_of_the_determinant():
    """max_step along random directions: det F of some element vanishes there (checked through an independent
    cubic: det sampled at four step lengths) and nowhere before."""
    mesh = shell_octant(2, 1)
    model = EnergyModel(mesh.vertices, 1.0, 1e-12)
    n = mesh.n_elements
    elastic = Elasticity(
        model.config, mesh.elements, StableNeoHookean, StableNeoHookean.parameters(np.full(n, 1.0), np.full(n, 0.3))
    )
    for seed in range(5):
        u, dx = state(mesh, 0.05, seed), state(mesh, 0.5, seed + 10)
        model.set_displacements(u)
        alpha = elastic.max_step(dx)
        samples = np.array([tet_volumes(mesh.vertices + u + s * dx, mesh.elements) for s in (0.0, 1.0, 2.0, 3.0)])
        coefficients = np.linalg.solve(np.vander([0.0, 1.0, 2.0, 3.0], 4), samples)  # per element, highest first
        roots = [r.real for c in coefficients.T for r in np.roots(c) if abs(r.imag) < 1e-9 and r.real > 0]
        assert alpha == pytest.approx(min(roots), rel=1e-8)
    model.set_displacements(np.zeros_like(mesh.vertices))
    collapse = elastic.max_step(-mesh.vertices)  # every element shrinks to a point at 1: a triple root, found
    assert 1.0 - 1e-5 < collapse <= 1.0  # to within the cube root of round-off, and never past it


def test_3d_body_resting_on_the_ground_carries_its_weight():
    """The extruded beam, free but for a roller at its left face and the z rollers, lies on the ground under
    gravity: the ground's total force on it is its weight rho g V, straight up."""
    mesh, _ = extruded_beam(0.1, chamber_points=16)
    mesh = tet_mesh(
        mesh.vertices,
        mesh.elements,
        {"main": mesh.chambers[0]},
        clamp=None,
        rollers=Z_ROLLERS + (Roller((1.0, 0.0, 0.0), (-1.75, 0.0, 0.0)),),
    )
    density, g = 1.0, 9.81
    scene = scene_of(
        mesh,
        [ChamberSchedule("pressure", ((1, 0.0),))],
        1,
        Material(1e4, 0.45),
        effects=(Gravity(density, g), Ground(-0.41, dhat=0.01, stiffness=1e3)),
    )
    result = tp.simulate(scene)
    assert result.converged
    fx, fy, _ = result.steps[-1].contact["ground"]
    assert fy == pytest.approx(density * g * mesh.volume, rel=1e-6) and abs(fx) < 1e-9 * fy
    assert result.contact_forces.shape == (2, mesh.n_vertices, 3)


def test_self_contact_is_refused_in_3d():
    mesh, _ = extruded_beam(0.2, chamber_points=8)
    scene = scene_of(mesh, [ChamberSchedule("area", ((1, 1.1),))], 1, effects=(SelfContact(),))
    with pytest.raises(PneumaInputError, match="self_contact is 2D only"):
        scene.build()


def test_3d_point_sets_and_boxes():
    mesh, _ = extruded_beam(0.2, chamber_points=8)
    x = mesh.vertices
    assert set(PointSet("front").select(x, "tip")) == set(np.flatnonzero(x[:, 2] > 0.8 - 1e-6))
    assert set(PointSet(box=(1.7, -1, -1, 2, 1, 1)).select(x, "tip")) == set(np.flatnonzero(x[:, 0] >= 1.7))
    with pytest.raises(PneumaInputError, match="must have 6 numbers on this 3D body"):
        PointSet(box=(0, 0, 1, 1)).select(x, "tip")
    with pytest.raises(PneumaInputError, match="needs a 3D body"):
        PointSet("back").select(x[:, :2], "clamp")
    with pytest.raises(PneumaInputError, match="must have as many components"):
        Roller((0.0, 0.0, 1.0), (0.0, 0.0))
