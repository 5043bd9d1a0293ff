"""Embedded fibres: the cords' energy against finite differences, the tension of a stretched cord, the embedding of
points in linear and quadratic meshes, the layouts' geometry, scene files with [[fibers]], and one compilation."""

import dataclasses
import math
import tomllib

import numpy as np
import pytest
from fd import term_hessian
from solid_meshes import box_with_cavities, box_with_cavity, scene_of
from test_compile_once import compiled_instances

from taichi_pneuma import runtime
from taichi_pneuma.errors import PneumaInputError
from taichi_pneuma.fem.elements import TET_P2
from taichi_pneuma.fem.embedding import embed
from taichi_pneuma.fem.fiber_paths import Crossed, Helix, Line, Polyline, Rings
from taichi_pneuma.fem.mesh import Mesh
from taichi_pneuma.fem.tip import tip_twist
from taichi_pneuma.limits import Budget
from taichi_pneuma.scene.build import Material, reference_scene
from taichi_pneuma.scene.scenefile import read_scene
from taichi_pneuma.scene.schedule import ChamberSchedule
from taichi_pneuma.solve.simulate import run_schedule
from taichi_pneuma.terms.fibers import Fiber
from taichi_pneuma.terms.model import Configuration


@pytest.fixture(scope="module", autouse=True)
def taichi():
    runtime.ensure_initialised()


def rectangle(nx: int = 6, ny: int = 3, width: float = 3.0, height: float = 1.0) -> Mesh:
    """A structured mesh of [0, width] x [0, height], each cell two counter-clockwise triangles."""
    x, y = np.meshgrid(np.linspace(0, width, nx + 1), np.linspace(0, height, ny + 1), indexing="ij")
    corner = (np.arange((nx + 1) * (ny + 1)).reshape(nx + 1, ny + 1)[:-1, :-1]).ravel()
    triangles = np.vstack(
        [
            np.column_stack([corner, corner + ny + 1, corner + ny + 2]),
            np.column_stack([corner, corner + ny + 2, corner + 1]),
        ]
    )
    empty = np.zeros(0, dtype=np.int64)
    return Mesh(np.column_stack([x.ravel(), y.ravel()]), triangles, (), empty, empty, empty, (), ())


def cords(mesh: Mesh, fiber: Fiber):
    config = Configuration(mesh.vertices)
    (term,) = fiber.terms(config, mesh, None, Budget())
    return config, term


CASES = {
    "2D": (rectangle(), Fiber(Polyline(((0.1, 0.2), (2.9, 0.7), (1.5, 0.95))), 2e3, area=0.05, spacing=0.15)),
    "3D": (box_with_cavity(), Fiber(Line((-1.7, -0.3, 0.1), (1.7, -0.1, -0.3)), 1e3, diameter=0.1, spacing=0.2)),
    "3D quadratic": (box_with_cavity(2), Fiber(Rings((0.0, -0.2, 0.0), 0.15, 2, 0.5, "x"), 1e3, area=0.01)),
}


def perturbed(case: str):
    """The case's (mesh, config, cord term) at a random state with some segments taut and some slack, and a random
    step dx from it (seeded)."""
    mesh, fiber = CASES[case]
    config, term = cords(mesh, fiber)
    rng = np.random.default_rng(2)
    config.u[:] = rng.normal(0.0, 0.01, config.u.shape) + 0.005 * mesh.vertices
    return mesh, config, term, rng.normal(0.0, 0.01, config.u.shape)


@pytest.mark.parametrize("case", CASES)
def test_cord_gradient_and_hessian_match_finite_differences(case):
    mesh, fiber = CASES[case]
    config, term = cords(mesh, fiber)
    rng = np.random.default_rng(1)
    config.u[:] = rng.normal(0.0, 0.01, config.u.shape) + 0.005 * mesh.vertices
    lengths = [np.linalg.norm(p) for p in segment_vectors(term)]
    stretched = np.array(lengths) > term.rest_length
    assert 0 < stretched.sum() < len(lengths)  # some segments taut, some slack
    u0, gradient, n = config.u.copy(), term.gradient(), config.u.size
    h = 1e-6
    for i in rng.choice(n, 40, replace=False):
        config.u.flat[i] = u0.flat[i] + h
        up = term.energy()
        config.u.flat[i] = u0.flat[i] - h
        down = term.energy()
        config.u.flat[i] = u0.flat[i]
        assert abs((up - down) / (2 * h) - gradient.flat[i]) < 1e-7 * np.abs(gradient).max()
    hessian = term_hessian(term)
    step = rng.normal(size=u0.shape) * 1e-6
    config.u[:] = u0 + step
    ahead = term.gradient()
    config.u[:] = u0 - step
    behind = term.gradient()
    config.u[:] = u0
    assert np.allclose(
        (ahead - behind).ravel(), 2 * hessian @ step.ravel(), rtol=0, atol=1e-6 * np.abs(hessian @ step.ravel()).max()
    )
    used = np.unique(term.hessian_pattern()[0])
    assert np.linalg.eigvalsh(hessian[np.ix_(used, used)]).min() > -1e-9 * np.abs(hessian).max()  # PSD
    assert np.array_equal(term.hessian_values(psd_only=True), term.hessian_values())


def segment_vectors(term) -> list[np.ndarray]:
    """p_b - p_a of each segment, from the weights (independently of the kernels)."""
    x = term.config.rest + term.config.u
    points = np.einsum("pi,pid->pd", term.weights, x[term.nodes])
    return list(points[term.segments[:, 1]] - points[term.segments[:, 0]])


@pytest.mark.parametrize("case", CASES)
def test_on_the_branches_at_u_plus_dx_a_cord_is_two_sided_where_taut_there_and_absent_where_slack(case):
    mesh, config, term, dx = perturbed(case)
    fiber = CASES[case][1]
    now = np.array([np.linalg.norm(r) for r in segment_vectors(term)]) > term.rest_length
    u0 = config.u.copy()
    config.u[:] = u0 + dx
    ahead = np.array([np.linalg.norm(r) for r in segment_vectors(term)]) > term.rest_length
    config.u[:] = u0
    assert 0 < np.count_nonzero(ahead != now) < len(now)
    assert term.choose_branches(dx) == np.count_nonzero(ahead != now)
    expected = np.zeros_like(config.u)  # k (l - L0) n of every segment taut at u + dx, slack ones left out
    for s, r in enumerate(segment_vectors(term)):
        if ahead[s]:
            force = fiber.E * fiber.section(mesh.dim) / term.rest_length[s] * (np.linalg.norm(r) - term.rest_length[s])
            a, b = term.segments[s]
            np.add.at(expected, term.nodes[b], term.weights[b][:, None] * force * r / np.linalg.norm(r))
            np.add.at(expected, term.nodes[a], -term.weights[a][:, None] * force * r / np.linalg.norm(r))
    assert np.allclose(term.gradient() + term.branch_shift(), expected, rtol=0, atol=1e-12 * np.abs(expected).max())
    assert np.count_nonzero(term.hessian_values().reshape(len(now), -1).any(axis=1)) == np.count_nonzero(ahead)
    assert term.choose_branches(None) == np.count_nonzero(ahead != now)
    assert term.branch_shift() is None


STRAIGHT = {
    "3D": (box_with_cavities({}, 2), Line((-1.75, 0.1, 0.05), (1.75, 0.1, 0.05)), dict(diameter=0.2), 0.0),
    "2D": (rectangle(), Line((0.0, 0.4), (3.0, 0.4)), dict(area=0.02), 1.5),
}


@pytest.mark.parametrize("case", STRAIGHT)
@pytest.mark.parametrize("stretch", [1.1, 1.003, 0.9])
def test_a_straight_cord_pulls_with_EA_times_stretch_minus_one_and_never_pushes(case, stretch):
    mesh, line, section, middle = STRAIGHT[case]
    E = 3e3
    fiber = Fiber(line, E, spacing=0.3, **section)
    area = section.get("area", math.pi * section.get("diameter", 0.0) ** 2 / 4)
    config, term = cords(mesh, fiber)
    config.u[:, 0] = (stretch - 1.0) * mesh.vertices[:, 0]  # uniaxial stretch along x
    right = mesh.vertices[:, 0] > middle + 1e-9
    pull = -term.gradient()[right].sum(axis=0)  # what the cord exerts on the right part of the body
    tension = E * area * max(stretch - 1.0, 0.0)
    assert pull[0] == pytest.approx(-tension, rel=1e-12, abs=1e-12 * E * area)
    assert np.allclose(pull[1:], 0.0, atol=1e-12 * E * area)
    length = np.ptp(np.array([line.start, line.end])[:, 0])
    assert term.energy() == pytest.approx(0.5 * E * area * max(stretch - 1.0, 0.0) ** 2 * length, rel=1e-12, abs=1e-300)


@pytest.mark.parametrize("order", [1, 2])
@pytest.mark.parametrize("dim", [2, 3])
def test_embedded_points_are_reproduced_by_nonnegative_weights(dim, order):
    rng = np.random.default_rng(order)
    if dim == 3:
        mesh = box_with_cavity(order)
        points = rng.uniform([-1.75, -0.4, -0.4], [1.75, -0.01, 0.4], (300, 3))
        points[:4] = [[-1.75, -0.4, -0.4], [1.75, 0.4, 0.4], [0.0, 0.4, 0.1], [0.0, 0.0, 0.0]]  # corners, faces, wall
    else:
        mesh = reference_scene(max_area=0.02, order=order).geometry.mesh()
        points = rng.uniform([-1.75, -0.4], [1.75, -0.1], (300, 2))
        points[:2] = [[-1.75, -0.4], [1.75, 0.4]]
    nodes, weights = embed(mesh, points, "probe")
    assert np.all(weights >= 0) and np.allclose(weights.sum(axis=1), 1.0, rtol=0, atol=1e-15)
    assert np.abs(np.einsum("pi,pid->pd", weights, mesh.vertices[nodes]) - points).max() < 1e-12
    elements = [set(e) for e in mesh.elements]
    assert all(any(set(row) <= e for e in elements) for row in nodes[:20])  # a piece of one element


def test_the_quadratic_tetrahedron_splits_into_eight_positive_eighths():
    X = TET_P2.reference_nodes
    volumes = [np.linalg.det(X[list(p)][1:] - X[list(p)][0]) / 6 for p in TET_P2.split]
    assert np.allclose(volumes, 1 / 48, rtol=1e-14)  # the reference tetrahedron's 1/6, in eight


@pytest.mark.parametrize(
    "point, where",
    [((0.0, 0.1, 0.0), "in the chamber"), ((2.0, 0.0, 0.0), "past the right face"), ((0.0, 0.6, 0.0), "above")],
)
def test_a_fiber_point_outside_the_body_is_refused_naming_the_fiber(point, where):
    """In the chamber's middle, 0.25 and 0.2 outside the box: more than a quarter of its pieces' least height (0.1
    to 0.14) from them, so not snapped."""
    mesh = box_with_cavity()
    fiber = Fiber(Line((-1.0, -0.2, 0.0), point), 1e3, area=0.01, name="weft")
    with pytest.raises(PneumaInputError, match=r"fiber 'weft': .*outside the body.*bounding box is \[-1.75, -0.4"):
        cords(mesh, fiber)


def test_points_just_outside_the_mesh_snap_onto_it_within_a_quarter_of_its_piece():
    """1e-6 and 0.02 above the box's top face (its pieces' least height 0.1 or more): each embedded on a piece of the
    top, moved straight down onto the face; 0.2 above is refused."""
    mesh = box_with_cavity()
    points = np.array([[0.1, 0.4 + 1e-6, 0.05], [-0.6, 0.42, 0.1]])
    nodes, weights = embed(mesh, points, "thread")
    assert np.all(weights >= 0) and np.allclose(weights.sum(axis=1), 1.0)
    placed = np.einsum("pi,pid->pd", weights, mesh.vertices[nodes])
    assert np.allclose(placed[:, 1], 0.4) and np.allclose(placed[:, [0, 2]], points[:, [0, 2]], atol=1e-12)
    with pytest.raises(PneumaInputError, match=r"thread: 1 of its 1 points lie outside the body"):
        embed(mesh, [[0.0, 0.6, 0.0]], "thread")


def test_a_3d_layout_in_a_2d_body_is_refused():
    helix = Helix((0.0, 0.0, 0.0), 0.1, 2.0, "x", pitch=0.5)
    with pytest.raises(PneumaInputError, match=r"layout = 'helix' is 3D only; a 2D body takes line, polyline"):
        cords(rectangle(), Fiber(helix, 1e3, area=0.01))
    with pytest.raises(PneumaInputError, match=r"diameter = 0.1 is for a 3D body"):
        cords(rectangle(), Fiber(Line((0.1, 0.1), (1.0, 0.1)), 1e3, diameter=0.1))


@pytest.mark.parametrize("axis", ["x", "y", "z"])
@pytest.mark.parametrize("handedness", ["right", "left"])
def test_a_helix_lies_at_its_radius_advances_a_pitch_per_turn_and_turns_by_its_hand(axis, handedness):
    center, radius, pitch, turns = np.array([0.3, -0.2, 0.1]), 0.25, 0.4, 2.5
    helix = Helix(tuple(center), radius, turns, axis, pitch=pitch, handedness=handedness, phase=30.0)
    points = helix.sample(0.01) - center
    k = "xyz".index(axis)
    along, across = points[:, k], np.delete(points, k, axis=1)
    if axis == "y":  # (z, x): the plane's right-handed order about +y
        across = across[:, ::-1]
    assert np.allclose(np.linalg.norm(across, axis=1), radius, rtol=1e-14)
    assert np.all(np.diff(along) > 0) and along[0] == 0 and along[-1] == pytest.approx(turns * pitch)
    angle = np.unwrap(np.arctan2(across[:, 1], across[:, 0]))
    sense = 1 if handedness == "right" else -1  # counter-clockwise seen from +axis while advancing along +axis
    assert np.allclose(along, sense * (angle - angle[0]) / (2 * np.pi) * pitch, rtol=0, atol=1e-12)
    assert math.degrees(angle[0]) == pytest.approx(30.0)
    steps = np.linalg.norm(np.diff(points, axis=0), axis=1)
    assert steps.max() <= 0.01 and steps.sum() == pytest.approx(helix.helix_length, rel=1e-3)  # chords of its arcs


def test_a_helix_by_winding_angle_is_the_helix_of_its_pitch():
    radius, angle = 0.2, 55.0
    by_angle = Helix((0.0, 0.0, 0.0), radius, 3.0, "z", angle=angle).sample(0.05)
    by_pitch = Helix((0.0, 0.0, 0.0), radius, 3.0, "z", pitch=2 * math.pi * radius / math.tan(math.radians(angle)))
    assert np.allclose(by_angle, by_pitch.sample(0.05), rtol=0, atol=1e-14)
    crossed = Crossed((0.0, 0.0, 0.0), radius, 3.0, "z", angle=angle).curves(0.05)
    assert len(crossed) == 2 and np.allclose(crossed[0], by_angle, rtol=0, atol=1e-14)
    assert np.allclose(crossed[1][:, 2], crossed[0][:, 2]) and np.allclose(crossed[1][:, 1], -crossed[0][:, 1])


@pytest.mark.parametrize(
    "make, message",
    [
        (lambda: Helix((0, 0, 0), 0.1, 1.0, "z", pitch=0.1, angle=30.0), "give exactly one of pitch and angle"),
        (lambda: Helix((0, 0, 0), 0.1, 1.0, "w", pitch=0.1), "axis = 'w' is not one of x, y, z"),
        (lambda: Helix((0, 0, 0), 0.1, 1.0, "z", angle=90.0), r"angle = 90.0 must lie in \(0, 90\)"),
        (lambda: Helix((0, 0, 0), 0.1, 1.0, pitch=0.1, handedness="up"), "handedness = 'up' is not one of right"),
        (lambda: Polyline(((0.0, 0.0),)), "must list at least 2 points"),
        (lambda: Rings((0, 0, 0), -1.0, 2, 0.1), "radius = -1.0 must be > 0"),
        (lambda: Fiber(Line((0, 0), (1, 0)), 1e3), "give exactly one of area and diameter"),
    ],
)
def test_bad_fiber_keys_are_refused_naming_them(make, message):
    with pytest.raises(PneumaInputError, match=message):
        make()


def test_a_fiber_sampled_past_the_budget_or_the_cap_is_refused():
    line = Line((-1.7, -0.3, 0.0), (1.7, -0.3, 0.0))
    config = Configuration(box_with_cavity().vertices)
    with pytest.raises(
        PneumaInputError,
        match=r"fiber 'x' \(340 cord segments\) would hold 195840 Hessian entries: .*the limit is 100 tri",
    ):
        Fiber(line, 1e3, area=0.01, spacing=0.01, name="x").terms(config, box_with_cavity(), None, Budget(100))
    with pytest.raises(
        PneumaInputError,
        match=r"spacing 1e-05 would sample it at 3.4e\+05 points; at most 100000 are allowed",
    ):
        Fiber(line, 1e3, area=0.01, spacing=1e-5, name="x").terms(config, box_with_cavity(), None, Budget())


def test_a_rings_layout_is_closed_loops_spaced_along_its_axis():
    rings = Rings((0.0, 0.1, -0.1), 0.2, 3, 0.5, "x")
    curves = rings.curves(0.05)
    assert len(curves) == 3 and rings.closed
    for k, ring in enumerate(curves):
        assert np.allclose(ring[:, 0], 0.5 * k) and np.allclose(np.hypot(ring[:, 1] - 0.1, ring[:, 2] + 0.1), 0.2)
        gaps = np.linalg.norm(np.diff(np.vstack([ring, ring[:1]]), axis=0), axis=1)
        assert gaps.max() <= 0.05 and np.ptp(gaps) < 1e-12  # evenly round, the last point joining the first


FIBERED = """
[body]
shape = "box"
center = [0.0, 0.0, 0.0]
size = [3.5, 0.8, 0.8]
[mesh]
size = 0.4
[[chambers]]
name = "c"
shape = "box"
center = [0.0, 0.1, 0.0]
size = [2.0, 0.2, 0.3]
keyframes = [[2, 2.0]]
[schedule]
increments = 2
[[fibers]]
name = "bottom"
E = 5e4
area = 0.002
path = { layout = "polyline", points = [[-1.7, -0.3, 0.0], [1.7, -0.3, 0.0]] }
[[fibers]]
E = 2e5
diameter = 0.01
spacing = 0.05
path = { layout = "crossed", center = [-1.7, 0.0, 0.0], axis = "x", radius = 0.3, turns = 4, angle = 30.0 }
"""


def test_a_scene_with_fibers_round_trips_through_its_file():
    scene = read_scene(tomllib.loads(FIBERED), "fibered")
    assert [f.layout for f in scene.fibers] == ["polyline", "crossed"]
    assert scene.fibers[1].path == Crossed((-1.7, 0.0, 0.0), 0.3, 4.0, "x", angle=30.0)
    assert read_scene(tomllib.loads(scene.to_toml()), "fibered") == scene
    assert scene.with_value("fibers[0].E", 1e5).fibers[0].E == 1e5
    with pytest.raises(PneumaInputError, match=r"fibers\[0\].*give exactly one of area and diameter"):
        read_scene(tomllib.loads(FIBERED.replace("area = 0.002", "area = 0.002\ndiameter = 0.1")), "x")


def evaluate(built) -> None:
    """Energy, gradient and Hessian of the built scene's cords."""
    term = built.model.terms[-1]
    assert term.name == "fibers"
    term.energy(), term.gradient(), term.hessian_values()


def test_fibered_scenes_compile_no_new_kernel():
    """One kernel each for the cords' energy, gradient and Hessian, whatever the dimension, mesh and layout."""
    pressure = ChamberSchedule("pressure", ((1, 1.0),))
    line = Fiber(Line((-1.7, -0.3), (1.7, -0.3)), 1e5, area=0.01)
    helix = Fiber(Helix((-1.7, -0.2, 0.0), 0.15, 3.0, "x", pitch=1.0), 1e5, diameter=0.02)
    evaluate(dataclasses.replace(reference_scene(max_area=0.05), fibers=(line,)).build())
    evaluate(scene_of(box_with_cavity(), [pressure], 1, fibers=(helix,)).build())
    before = compiled_instances()
    assert [before[f"taichi_pneuma.terms.fibers.cord_{k}"] for k in ("energy", "gradient", "hessian")] == [1, 1, 1]
    bent = Fiber(Polyline(((-1.7, -0.3), (0.0, -0.35), (1.7, -0.2))), 1e5, area=0.01)
    evaluate(dataclasses.replace(reference_scene(max_area=0.02, order=2), fibers=(bent,)).build())
    crossed = Fiber(Crossed((-1.7, -0.2, 0.0), 0.15, 2.0, "x", angle=40.0), 1e5, area=1e-4)
    evaluate(scene_of(box_with_cavity(2), [pressure], 1, Material(1e4, 0.3), fibers=(crossed,)).build())
    assert compiled_instances() == before


def test_tip_twist_is_the_rotation_about_x_by_the_right_hand_rule():
    rng = np.random.default_rng(3)
    rest = rng.normal(size=(12, 3))
    angle = math.radians(20.0)
    rotation = np.array([[1, 0, 0], [0, math.cos(angle), -math.sin(angle)], [0, math.sin(angle), math.cos(angle)]])
    assert tip_twist(rest, rest @ rotation.T + [0.5, 0.1, -0.2]) == pytest.approx(20.0, rel=1e-12)


TUBE = """
[body]
shape = "cylinder"
center = [0.0, 0.0, 0.0]
radius = 0.3
length = 2.0
axis = "x"
[mesh]
size = 0.15
[material]
E = 1e4
nu = 0.4
[clamp]
side = "left"
[[chambers]]
name = "c"
shape = "cylinder"
center = [0.0, 0.0, 0.0]
radius = 0.15
length = 1.6
axis = "x"
control = "pressure"
keyframes = [[2, 2000.0]]
[schedule]
increments = 2
"""
WINDING = 'center = [-1.0, 0.0, 0.0], axis = "x", radius = 0.23, angle = 45.0, turns = 1.3'  # 1.9 of its 2.0 long


def tube_twist(path: str) -> float:
    """The tip twist (degrees) of the pressurised tube wound with one fibre of this path (E A = 1e6 pi 0.05^2 / 4,
    about the wall's E A, 1e4 pi (0.3^2 - 0.15^2))."""
    fiber = f"[[fibers]]\nE = 1e6\ndiameter = 0.05\npath = {{ {path}, {WINDING} }}\n"
    run = run_schedule(read_scene(tomllib.loads(TUBE + fiber), "tube").build())
    mesh, x = run.built.mesh, run.positions[-1]
    return tip_twist(mesh.vertices[mesh.tip], x[mesh.tip])


def test_a_pressurised_tube_wound_with_one_helix_twists_by_its_hand_and_a_crossed_pair_barely():
    """Inflation lengthens the tube and widens it, stretching a 45-degree fibre; the tube twists to unwind it: a
    right-handed helix (turning counter-clockwise about +x as it advances) turns the tip clockwise (negative twist),
    a left-handed one as much counter-clockwise; a crossed pair balances (measured: -12.3, +12.3, -0.4 degrees)."""
    pytest.importorskip("gmsh", reason="gmsh is not installed (pip install 'taichi-pneuma[3d]')")
    right, left = (
        tube_twist('layout = "helix", handedness = "right"'),
        tube_twist('layout = "helix", handedness = "left"'),
    )
    crossed = tube_twist('layout = "crossed"')
    assert right < -5.0 and left > 5.0 and abs(right + left) < 0.1 * abs(right)
    assert abs(crossed) < 0.1 * min(abs(right), abs(left))
