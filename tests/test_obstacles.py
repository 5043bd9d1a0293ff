"""Rigid obstacles: the shapes' signed distances against closed forms, the contact term's derivatives against finite
differences, its step bound against hand-computed hit times, and in runs: the clamp's reaction balancing the
contact and the loads, a moving obstacle pushing the tip, and bad input refused."""

import math
import tomllib
from types import SimpleNamespace

import numpy as np
import pytest
from fd import term_derivatives, term_hessian

from taichi_pneuma import runtime
from taichi_pneuma.control.inverse import Reacher
from taichi_pneuma.errors import PneumaInputError
from taichi_pneuma.io.units import FORCE_3D, MOMENT, UNITS
from taichi_pneuma.result import Result
from taichi_pneuma.scene.scenefile import read_scene
from taichi_pneuma.solve.columns import history_dimensions
from taichi_pneuma.solve.newton import NewtonOptions
from taichi_pneuma.solve.simulate import RampFailed, run_schedule
from taichi_pneuma.terms.model import Configuration
from taichi_pneuma.terms.obstacle_shapes import Box, Capsule, Cylinder, Plane, Sphere
from taichi_pneuma.terms.obstacles import ObstacleContact


def contact(points, shape, dhat=0.5, stiffness=10.0):
    """An obstacle term on free points (rest = the points, u = 0)."""
    runtime.ensure_initialised()
    config = Configuration(np.asarray(points, dtype=float))
    return ObstacleContact(config, np.arange(len(points)), shape, "o", dhat, stiffness)


def distances(points, shape):
    """The signed distance of each point (one term per point: nearest() of one vertex)."""
    return [contact([p], shape).nearest() for p in points]


def test_signed_distances_match_closed_forms():
    """Hand-computed distances: outside each shape on faces, edges, corners, rims and ends, and inside."""
    plane = Plane((0.0, 1.0), (0.0, 2.0))  # y >= 1
    assert distances([(3.0, 1.5), (0.0, 0.25)], plane) == pytest.approx([0.5, -0.75])
    sphere = Sphere((1.0, 0.0, 0.0), 0.5)
    assert distances([(4.0, 4.0, 0.0), (1.0, 0.1, 0.0)], sphere) == pytest.approx([4.5, -0.4])
    box = Box((0.0, 0.0, 0.0), (2.0, 4.0, 6.0))  # half sizes 1, 2, 3
    face, edge, corner, inside = (1.5, 0.0, 0.0), (2.0, 3.0, 0.0), (2.0, 4.0, 5.0), (0.5, 0.0, 0.0)
    assert distances([face, edge, corner, inside], box) == pytest.approx([0.5, math.sqrt(2), 3.0, -0.5])
    assert distances([(0.0, 3.0)], Box((0.0, 0.0), (2.0, 4.0))) == pytest.approx([1.0])  # 2D: no z extent
    cylinder = Cylinder((0.0, 0.0, 0.0), 1.0, 4.0, "x")  # |x| <= 2, y^2 + z^2 <= 1
    side, cap, rim = (0.5, 0.0, 3.0), (2.5, 0.3, 0.0), (5.0, 0.0, 5.0)
    assert distances([side, cap, rim], cylinder) == pytest.approx([2.0, 0.5, 5.0])
    assert distances([(3.0, 4.0)], Cylinder((0.0, 0.0), 1.0, 1.0, "z")) == pytest.approx([4.0])  # 2D: a circle
    capsule = Capsule((0.0, 0.0, 0.0), 0.5, 2.0, "y")  # segment y in [-1, 1]
    assert distances([(3.0, 0.5, 0.0), (0.0, 4.0, 4.0), (0.0, 1.2, 0.0)], capsule) == pytest.approx([2.5, 4.5, -0.3])


SHAPES = {
    "plane": Plane((0.0, 0.0, 0.0), (1.0, 2.0, 0.5)),
    "sphere": Sphere((0.0, 0.0, 0.0), 1.0),
    "box": Box((0.0, 0.0, 0.0), (2.0, 2.0, 2.0)),
    "cylinder": Cylinder((0.0, 0.0, 0.0), 1.0, 2.0, "y"),
    "capsule": Capsule((0.0, 0.0, 0.0), 1.0, 2.0, "z"),
}
# points within dhat = 0.5 of each shape, on every kind of closest feature (face, edge, corner; side, cap, rim; end)
NEAR = {
    "plane": [(0.1, 0.1, 0.05), (0.3, -0.05, 0.0)],
    "sphere": [(1.2, 0.1, 0.05), (-0.3, 1.0, 0.4)],
    "box": [(1.2, 0.3, -0.2), (1.15, 1.2, 0.4), (-1.1, 1.25, -1.2)],
    "cylinder": [(1.1, 0.3, 0.4), (0.2, 1.3, -0.1), (0.95, -1.2, 0.5)],
    "capsule": [(1.2, 0.1, 0.4), (0.3, -0.4, 1.9)],
}


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("name", list(SHAPES))
def test_gradient_and_exact_hessian_match_finite_differences(name, dim):
    """Energy -> gradient and gradient -> exact Hessian (b'' n n^T + b' Hess d) on nodes within dhat of each shape
    (2D: the same shapes at z = 0); the PSD Hessian is positive semi-definite."""
    points = np.array(NEAR[name])[:, :dim]
    if dim == 2:
        points = np.array([p for p in points if 0 < distances([p], SHAPES[name])[0] < 0.5])
    term = contact(points, SHAPES[name])
    u = 0.01 * np.random.default_rng(1).standard_normal(points.shape)
    term.config.u[:] = u
    g_fd, h_fd = term_derivatives(term, u)
    g = term.gradient().ravel()
    assert np.linalg.norm(g) > 1.0  # the contact is active
    assert np.linalg.norm(g - g_fd) <= 1e-6 * np.linalg.norm(g)
    hessian = term_hessian(term)
    assert np.linalg.norm(hessian - h_fd) <= 1e-5 * np.linalg.norm(hessian)
    assert np.linalg.eigvalsh(term_hessian(term, psd_only=True)).min() >= -1e-9 * np.linalg.norm(hessian)


@pytest.mark.parametrize(
    ("shape", "start", "direction", "hit"),
    [
        (Plane((0.0, -1.0), (0.0, 1.0)), (0.3, 0.5), (0.5, -3.0), 0.5),  # y = 0.5 - 3 t reaches -1 at t = 0.5
        (Sphere((2.0, 0.0), 1.0), (-1.0, 0.0), (1.0, 0.0), 2.0),  # x = -1 + t reaches 1 at t = 2
        (Sphere((0.0, 0.0, 0.0), 1.0), (0.6, -3.0, 0.0), (0.0, 1.0, 0.0), 2.2),  # y = -0.8 on the sphere
        (Box((0.0, 0.0), (2.0, 1.0)), (3.0, 0.2), (-4.0, 0.0), 0.5),  # x = 3 - 4 t reaches 1 at t = 0.5
        (Box((0.0, 0.0, 0.0), (2.0, 2.0, 2.0)), (3.0, 2.5, 0.3), (-1.0, -1.0, 0.0), 2.0),  # the face x = 1 at y = 0.5
    ],
    ids=["plane", "circle", "sphere-offset", "box", "box-3d"],
)
def test_max_step_stops_a_node_just_before_the_surface(shape, start, direction, hit):
    """A node moving straight at a shape: max_step within 1e-3 of the hand-computed hit time, never past it."""
    term = contact([start], shape)
    alpha = term.max_step(np.array([direction], dtype=float))
    assert hit * (1 - 1e-3) <= alpha <= hit
    assert term.max_step(-np.array([direction], dtype=float)) == math.inf  # moving away


def beam(obstacles: str, gravity: bool = True, increments: int = 2) -> dict:
    """A clamped 2 x 0.3 cantilever (x from 0 to 2) with a closed pressure chamber at 50, sagging under gravity
    (rho g L^4 / (E h^2) ~ 0.26 at the tip), with the given [[obstacles]] TOML."""
    return tomllib.loads(beam_text(obstacles, gravity, increments))


def beam_text(obstacles: str, gravity: bool = True, increments: int = 2) -> str:
    """beam's scene file."""
    weight = "[effects.gravity]\ndensity = 1.0\n" if gravity else ""
    text = f"""
[body]
shape = "rectangle"
center = [1.0, 0.0]
size = [2.0, 0.3]
[mesh]
max_area = 0.006
[material]
E = 1e4
nu = 0.3
[clamp]
side = "left"
{weight}
[[chambers]]
name = "main"
shape = "ellipse"
center = [0.6, 0.0]
semi_axes = [0.3, 0.06]
points = 24
control = "pressure"
keyframes = [[{increments}, 50.0]]
[schedule]
increments = {increments}
{obstacles}
"""
    return text


POST = """
[[obstacles]]
name = "post"
shape = "sphere"
center = [1.8, -0.45]
radius = 0.2
dhat = 0.05
stiffness = 10.0
"""


def moment(arm: np.ndarray, force: np.ndarray) -> float:
    return float(np.sum(arm[:, 0] * force[:, 1] - arm[:, 1] * force[:, 0]))


def test_the_clamp_reaction_balances_the_contact_the_pressure_and_the_weight():
    """Every converged step: clamp reaction + obstacle force + pressure resultant + weight = 0, and their moments
    about the clamp's rest centroid, within the solver's residual (tol x force scale); the contact is active."""
    built = read_scene(beam(POST), "sag").build()
    run = Result.of(run_schedule(built))
    mesh, tol = built.mesh, NewtonOptions().tol
    centre = mesh.vertices[mesh.pinned].mean(axis=0)
    loads = [t for t in built.model.terms if t.reported_as not in ("post", "clamp") and t is not built.elastic]
    assert sorted(t.name for t in loads) == ["chamber:main", "gravity"]
    history = run.history
    for i, step in enumerate(run.steps):
        built.model.set_displacements(run.displacements[i])
        built.set_commands(built.scene.schedule.commands(i))
        forces = [-t.gradient() for t in loads]
        arm = run.positions[i] - centre
        obstacle = np.array([history["post.fx"][i], history["post.fy"][i]])
        post = -sum(t.gradient() for t in built.model.terms if t.reported_as == "post")  # nodes and edges
        assert obstacle == pytest.approx(post.sum(axis=0), abs=1e-12)
        total = sum(f.sum(axis=0) for f in forces) + obstacle + [history["clamp.fx"][i], history["clamp.fy"][i]]
        turning = sum(moment(arm, f) for f in forces) + moment(arm, post) + history["clamp.mz"][i]
        scale = built.model.gradient()[1]
        assert step.converged
        assert np.linalg.norm(total) <= tol * scale * math.sqrt(mesh.n_vertices)
        assert abs(turning) <= 2.0 * tol * scale * math.sqrt(mesh.n_vertices)
        assert history["post.fy"][i] > 0.01 * history["clamp.fy"][i] > 0  # the post carries part of the weight
    weight = 9.81 * mesh.measure  # rho g x the body's area (the chamber's hole excluded), carried by post and clamp
    assert history["post.fy"][-1] + history["clamp.fy"][-1] == pytest.approx(weight, rel=1e-6)
    assert built.obstacles[0].nearest() > 0
    assert set(run.summary()["clamp"]) == {"fx", "fy", "mz"}
    header = run.history_csv().splitlines()[0].split(",")
    assert {"post.fx", "post.fy", "post.magnitude", "clamp.fx", "clamp.fy", "clamp.mz"} <= set(header)


def test_a_moving_obstacle_pushes_the_tip_harder_as_it_advances(tmp_path):
    """A disc under the tip rising 0.15 over 3 steps (keyframes): its upward force on the body grows step by step,
    the tip rises, and no boundary node ends inside it; the per-node contact forces (ParaView's contact_force)
    sum to its force, and the states npz has its centre per step."""
    rising = POST.replace("center = [1.8, -0.45]", "center = [1.9, -0.4]") + "keyframes = [[3, [0.0, 0.15, 0.0]]]\n"
    built = read_scene(beam(rising, gravity=False, increments=3), "push").build()
    run = run_schedule(built)
    lift = run.history["post.fy"]
    assert np.all(np.diff(lift[1:]) > 0) and lift[-1] > 0
    assert run.steps[-1].tip_dy > 0.0
    assert built.obstacles[0].offset == pytest.approx([0.0, 0.15, 0.0])
    assert built.obstacles[0].nearest() > 0
    assert run.contact_forces[-1].sum(axis=0) == pytest.approx([run.history["post.fx"][-1], lift[-1]], rel=1e-12)
    _, npz = Result.of(run).save_history(tmp_path)
    with np.load(npz) as states:
        assert states["obstacle_names"].tolist() == ["post"]
        assert states["obstacle_positions"][:, 0, 1] == pytest.approx([-0.4, -0.35, -0.3, -0.25])


def test_an_obstacle_scene_reads_back_from_its_toml():
    moving = POST + "keyframes = [[1, [0.0, 0.1, 0.0]], [2, [0.1, 0.1, 0.0]]]\n"
    plane = '\n[[obstacles]]\nname = "floor"\nshape = "plane"\npoint = [0.0, -0.5]\nnormal = [0.0, 1.0]\n'
    capsule = '\n[[obstacles]]\nname = "bar"\nshape = "capsule"\ncenter = [1.0, 0.6]\nradius = 0.1\nlength = 1.0\n'
    capsule += 'axis = "x"\n'
    scene = read_scene(beam(moving + plane + capsule), "many")
    assert [type(o.shape).__name__ for o in scene.obstacles] == ["Sphere", "Plane", "Capsule"]
    assert read_scene(tomllib.loads(scene.to_toml()), "many") == scene
    assert scene.schedule.commands(1.5)[1:] == pytest.approx([0.05, 0.1, 0.0])


@pytest.mark.parametrize(
    ("table", "message"),
    [
        ('name = "in"\nshape = "sphere"\ncenter = [1.0, 0.0]\nradius = 0.1', "obstacle 'in' overlaps the body"),
        ('name = "odd"\nshape = "cone"\ncenter = [1.0, 0.0]', "shape = 'cone' is not one of plane, box"),
        ('name = "k"\nshape = "sphere"\ncenter = [1.0, -1.0]\nradius = 0.1\nkeyframes = [[1, 0.5]]', "keyframes"),
        ('name = "main"\nshape = "sphere"\ncenter = [1.0, -1.0]\nradius = 0.1', "obstacle name 'main'"),
    ],
    ids=["overlapping", "unknown-shape", "bad-keyframe", "chamber-name"],
)
def test_bad_obstacles_are_refused_naming_them(table, message):
    with pytest.raises(PneumaInputError, match=message):
        read_scene(beam(f"[[obstacles]]\n{table}\n"), "bad").build()


def test_an_obstacle_moved_through_the_body_ends_the_ramp_naming_it():
    """A disc raised 0.6 in one step (its top 0.5 into the beam's rest position) still overlaps the body when the
    one cut-back allowed halves the motion: RampFailed names it, its residual not finite."""
    raised = POST + "keyframes = [[1, [0.0, 0.6, 0.0]]]\n"
    built = read_scene(beam(raised, increments=1), "raised").build()
    with pytest.raises(
        RampFailed, match="after 1 cuts; residual nan .a side or face of the body's surface touches 'post'"
    ) as failure:
        run_schedule(built, max_cuts=1)
    assert len(failure.value.result.steps) == 1  # the rest state


def test_a_disc_smaller_than_an_edge_pressed_between_two_nodes_stays_out_of_the_face():
    """A disc of radius 0.02, a fifth of the beam's bottom edges, raised 0.08 under the middle of one of them (its
    top 0.02 below it at rest) over 4 steps: every step converges with the disc clear of every piece of the surface
    (overlap, written apart from the barriers), the face pushed up by it and the disc still under that edge; its
    force is carried by the edge barrier (the nodes are too far from it to hold it)."""
    mesh = read_scene(beam("", gravity=False), "probe").build().mesh
    x = mesh.vertices
    bottom = [(a, b) for a, b in mesh.surface if abs(x[a, 1] + 0.15) < 1e-9 and abs(x[b, 1] + 0.15) < 1e-9]
    a, b = min(bottom, key=lambda e: abs(x[e[0], 0] + x[e[1], 0] - 3.0))  # the bottom edge nearest x = 1.5
    middle = 0.5 * (x[a, 0] + x[b, 0])
    assert np.linalg.norm(x[a] - x[b]) > 0.1  # five times the radius
    disc = f"""
[[obstacles]]
name = "post"
shape = "sphere"
center = [{middle}, -0.19]
radius = 0.02
dhat = 0.005
stiffness = 10.0
keyframes = [[4, [0.0, 0.08]]]
"""
    built = read_scene(beam(disc, gravity=False, increments=4), "probe").build()
    run = Result.of(run_schedule(built))
    assert len(run.steps) == 5 and all(step.converged for step in run.steps)
    for i in range(5):
        built.model.set_displacements(run.displacements[i])
        built.set_commands(built.scene.schedule.commands(i))
        assert built.obstacle_overlap() is None
    edges = next(t for t in built.model.terms if t.name == "post.edges")
    assert run.history["post.fy"][-1] > 0  # it pushes the face up
    assert -edges.gradient()[:, 1].sum() > 0.9 * run.history["post.fy"][-1]  # through the edge barrier
    assert built.obstacles[0].nearest() > 0.01  # its nodes stay farther than 2 dhat
    ends = run.positions[-1][[a, b], 0] - middle
    assert ends.min() < -0.04 and ends.max() > 0.04  # the edge's nodes still two radii or more either side


def test_inverse_control_refuses_a_moving_obstacle():
    built = read_scene(beam(POST + "keyframes = [[1, [0.0, 0.1, 0.0]]]\n"), "reach").build()
    with pytest.raises(PneumaInputError, match="obstacle 'post' moves"):
        Reacher(built)


def test_the_force_and_moment_columns_carry_their_units():
    """mm-kPa: a 2D force is per unit depth (kPa mm = N/m), its moment kPa mm^2; in 3D a force is kPa mm^2, named
    mN, and a moment kPa mm^3 = mN mm; in mm-MPa and m-Pa a 3D force is N."""
    units, scene = UNITS["mm-kPa"], SimpleNamespace(chamber_names=[], controls=[], obstacles=())
    for dim, force, turning in ((2, "kPa mm", "kPa mm^2"), (3, "mN", "mN mm")):
        dimensions = history_dimensions(scene, ["post"], dim)
        assert units.label("post.fy", dimensions["post.fy"]) == f"post.fy [{force}]"
        assert units.label("clamp.fx", dimensions["clamp.fx"]) == f"clamp.fx [{force}]"
        assert units.label("clamp.mz", dimensions["clamp.mz"]) == f"clamp.mz [{turning}]"
    assert units.factor(MOMENT, 2) == pytest.approx(1e-3)  # 1 kPa mm^2 = 1e3 Pa x 1e-6 m^2 (N m per m)
    assert units.factor(FORCE_3D, 3) == pytest.approx(1e-3)  # 1 kPa mm^2 = 1e3 Pa x 1e-6 m^2 = 1 mN
    assert UNITS["mm-MPa"].factor(FORCE_3D, 3) == UNITS["m-Pa"].factor(FORCE_3D, 3) == pytest.approx(1.0)  # N
    assert [UNITS[name].symbol(FORCE_3D) for name in ("mm-MPa", "m-Pa")] == ["N", "N"]


def test_the_obstacle_kernels_compile_once_for_every_shape_and_dimension():
    """Shape kinds and parameters are runtime values, and one kernel serves 2D and 3D: one compiled instance each."""
    from taichi_pneuma import backend
    from taichi_pneuma.terms import obstacles

    for points, shape in (([(0.0, 1.5)], SHAPES["sphere"]), ([(0.0, 1.2, 0.0)], SHAPES["capsule"])):
        term = contact(points, shape)
        term.energy(), term.hessian_values(), term.max_step(np.ones((1, len(points[0]))))
    store = {"taichi": "compiled_kernels", "quadrants": "materialized_kernels"}[backend.NAME]
    for kernel in (obstacles.obstacle_energy, obstacles.obstacle_derivatives, obstacles.obstacle_step):
        assert len(getattr(kernel._primal, store)) == 1
