"""Rigid obstacles never pass through the body (the trust issue's obstacle part): an obstacle keyframed through the
tip in one step is swept, and no state it overlaps the body in is kept as an equilibrium; an obstacle placed inside
the body or cutting into its surface between the nodes is refused at rest; a keyframe offset far beyond the body, a
z offset in 2D and names that are no plain names are refused.

The overlap is measured here independently of the code under test: the obstacle's signed distance (closed forms
in NumPy) at every boundary node and at SAMPLES points along every boundary edge (2D) or over every boundary
triangle (3D), and whether its centre lies in one of the body's elements (barycentric coordinates)."""

import numpy as np
import pytest
from solid_meshes import box_with_cavity, scene_of
from test_obstacles import beam, beam_text

from taichi_pneuma.apps.inflate import main
from taichi_pneuma.errors import PneumaInputError
from taichi_pneuma.materials import Material
from taichi_pneuma.scene.scenefile import read_scene
from taichi_pneuma.scene.schedule import ChamberSchedule
from taichi_pneuma.solve.simulate import RampFailed, run_schedule
from taichi_pneuma.terms.obstacle_shapes import Box, Sphere
from taichi_pneuma.terms.obstacles import Obstacle

SAMPLES = 24  # points along each side of a boundary facet


def distance(points: np.ndarray, shape, centre) -> np.ndarray:
    """The signed distance at points (k, d) of a Box (no z extent for a size of 2 numbers) or a Sphere moved to
    centre: |max(q, 0)| + min(max_k q_k, 0), q = |x - c| - size / 2, or |x - c| - R."""
    d = points.shape[1]
    if isinstance(shape, Sphere):
        return np.linalg.norm(points - np.asarray(centre[:d]), axis=1) - shape.radius
    q = np.abs(points - np.asarray(centre[:d])) - 0.5 * np.asarray((*shape.size, np.inf)[:d])
    return np.linalg.norm(np.maximum(q, 0.0), axis=1) + np.minimum(q.max(axis=1), 0.0)


def surface_points(mesh, x: np.ndarray) -> np.ndarray:
    """Points on the body's boundary at positions x: every boundary facet's (linear) corners and the points of a
    grid of SAMPLES steps along its sides and over it."""
    facets = mesh.surface[:, : mesh.dim]
    t = np.linspace(0.0, 1.0, SAMPLES + 1)
    if mesh.dim == 2:
        a, b = x[facets[:, 0]], x[facets[:, 1]]
        return (a[:, None] + t[None, :, None] * (b - a)[:, None]).reshape(-1, 2)
    s, r = (g.ravel() for g in np.meshgrid(t, t))
    keep = s + r <= 1.0
    s, r = s[keep], r[keep]
    a, b, c = (x[facets[:, k]] for k in range(3))
    points = a[:, None] + s[None, :, None] * (b - a)[:, None] + r[None, :, None] * (c - a)[:, None]
    return points.reshape(-1, 3)


def inside_an_element(mesh, x: np.ndarray, point) -> bool:
    """Whether the point lies in one of the (corner) simplices of the body at positions x."""
    corners = x[mesh.elements[:, : mesh.dim + 1]]
    edges = np.transpose(corners[:, 1:] - corners[:, :1], (0, 2, 1))
    weights = np.linalg.solve(edges, (np.asarray(point[: mesh.dim]) - corners[:, 0])[:, :, None])[:, :, 0]
    return bool(np.any((weights >= 0).all(axis=1) & (weights.sum(axis=1) <= 1)))


def overlaps(mesh, x: np.ndarray, shape, centre) -> bool:
    """Whether the obstacle's shape moved to centre overlaps the body at positions x."""
    return bool(distance(surface_points(mesh, x), shape, centre).min() <= 0) or inside_an_element(mesh, x, centre)


def kept_states(built):
    """The run's states, and its failure's message (None: the ramp ended)."""
    try:
        return run_schedule(built), None
    except RampFailed as failure:
        return failure.result, str(failure)


def plate_2d(keyframes: str) -> str:
    return (
        '[[obstacles]]\nname = "plate"\nshape = "box"\ncenter = [1.85, 0.3]\nsize = [0.2, 0.02]\ndhat = 0.01\n'
        f"stiffness = 10.0\nkeyframes = {keyframes}\n"
    )


def test_a_plate_moved_through_the_tip_in_one_step_never_ends_inside_the_2d_body():
    """The plate (0.02 thick, thinner than the elements) moved 0.3 down in one step, from 0.15 above the beam's top
    to its middle: at 0141107 the ramp converged with the plate wholly inside. Now its motion is swept: every kept
    state has the plate clear of the body's surface and not inside it, and a ramp that cannot go on names it."""
    built = read_scene(beam(plate_2d("[[1, [0.0, -0.3]]]"), gravity=False), "plate").build()
    run, failure = kept_states(built)
    spec = built.scene.obstacles[0]
    for step, x in zip(run.steps, run.positions):
        centre = np.add(spec.shape.center, spec.offset(step.step)[:2])
        assert not overlaps(built.mesh, x, spec.shape, centre)
    assert failure is None or "obstacle 'plate' overlaps the body" in failure
    assert failure is not None or run.steps[-1].step == 2


def test_a_plate_moved_through_the_tip_in_one_step_never_ends_inside_the_3d_body():
    """The 3D form: a box body (elements 0.5 x 0.2 x 0.2), a plate 0.05 thick moved from 0.35 above its top to its
    mid-plane in one step, where no node lies inside it."""
    size = (0.3, 0.05, 0.3)
    plate = Obstacle("plate", Box((1.5, 0.75, 0.0), size), 0.05, 10.0, ((1, (0.0, -0.75, 0.0)),))
    schedule = ChamberSchedule("pressure", ((1, 0.0),))
    built = scene_of(box_with_cavity(), (schedule,), 1, Material(1e4, 0.3), obstacles=(plate,)).build()
    run, failure = kept_states(built)
    for step, x in zip(run.steps, run.positions):
        centre = np.add((1.5, 0.75, 0.0), plate.offset(step.step))
        assert not overlaps(built.mesh, x, plate.shape, centre)
    assert failure is None or "obstacle 'plate' overlaps the body" in failure


def test_a_plate_moved_across_the_whole_tip_in_one_step_does_not_jump_over_it():
    """A plate 0.6 wide over the tip (x from 1.7 to 2.3) moved in one step from 0.09 above the beam's top to 0.19
    below its bottom: both ends clear of the body, so only its motion can tell that it passed through the tip
    (0141107 kept step 1 with the tip above it). Swept, it pushes the tip down ahead of it or the ramp stops: no
    kept state has a point of the body under the plate's x-range above its bottom face."""
    table = plate_2d("[[1, [0.0, -0.6]]]").replace("[1.85, 0.3]", "[2.0, 0.25]").replace("[0.2, 0.02]", "[0.6, 0.02]")
    built = read_scene(beam(table, gravity=False, increments=1), "across").build()
    run, failure = kept_states(built)
    spec = built.scene.obstacles[0]
    for step, x in zip(run.steps, run.positions):
        bottom = spec.shape.center[1] + spec.offset(step.step)[1] - 0.01
        under = surface_points(built.mesh, x)
        under = under[np.abs(under[:, 0] - 2.0) < 0.3]
        assert len(under) and under[:, 1].max() < bottom
    assert failure is None or "obstacle 'plate' overlaps the body" in failure


def test_a_resting_and_a_moving_obstacle_stay_clear_of_the_body_at_every_equilibrium():
    """The sagging beam on a disc (its weight partly on it) and a disc rising 0.15 under the tip over 3 steps: every
    converged state has each disc clear of every point of the body's surface, pressed on it (a contact force)."""
    post = '[[obstacles]]\nname = "post"\nshape = "sphere"\ncenter = [1.8, -0.45]\nradius = 0.2\ndhat = 0.05\n'
    rising = post.replace("[1.8, -0.45]", "[1.9, -0.4]") + "keyframes = [[3, [0.0, 0.15, 0.0]]]\n"
    for table, gravity, increments in ((post, True, 2), (rising, False, 3)):
        built = read_scene(beam(table + "stiffness = 10.0\n", gravity, increments), "post").build()
        run = run_schedule(built)
        spec = built.scene.obstacles[0]
        for step, x in zip(run.steps, run.positions):
            centre = np.add(spec.shape.center, spec.offset(step.step)[:2])
            assert not overlaps(built.mesh, x, spec.shape, centre)
        assert abs(run.history["post.fy"][-1]) > 0


def tip_gap(mesh) -> tuple[float, float]:
    """(y, gap): the middle and length of the longest side between neighbouring nodes of the 2D beam's tip x = 2."""
    ys = np.sort(mesh.vertices[np.isclose(mesh.vertices[:, 0], 2.0), 1])
    k = int(np.argmax(np.diff(ys)))
    return 0.5 * (ys[k] + ys[k + 1]), float(ys[k + 1] - ys[k])


def pebble(centre, radius) -> str:
    """A sphere's [[obstacles]] table."""
    centre = [float(c) for c in centre]
    return f'[[obstacles]]\nname = "pebble"\nshape = "sphere"\ncenter = {centre}\nradius = {float(radius)}\n'


def test_a_disc_inside_the_body_or_cutting_its_tip_between_the_nodes_is_refused_at_rest():
    """No node lies inside either disc (so a check of the nodes passes it, as 0141107's did): one wholly inside the
    beam between its nodes, one cutting half its radius into the tip face between two tip nodes."""
    mesh = read_scene(beam(""), "bare").build().mesh
    y, gap = tip_gap(mesh)
    radius = 0.3 * gap
    for disc, where in (
        (Sphere((1.5, 0.0), 0.01), "it lies inside"),
        (Sphere((2.0 + radius / 2, y), radius), "reaches"),
    ):
        assert distance(mesh.vertices, disc, disc.center).min() > 0  # clear of every node
        assert overlaps(mesh, mesh.vertices, disc, disc.center)
        with pytest.raises(PneumaInputError, match=f"obstacle 'pebble' overlaps the body: .*{where}.* at rest"):
            read_scene(beam(pebble(disc.center, disc.radius)), "pebble").build()


def test_an_obstacle_keyframed_into_the_body_at_step_0_is_refused_at_rest():
    """A keyframe at step 0 places the obstacle before the first solve: the rest check takes it there."""
    table = pebble((1.5, 0.6), 0.05) + "keyframes = [[0, [0.0, -0.6]], [1, [0.0, 0.0]]]\n"
    with pytest.raises(PneumaInputError, match=r"it lies inside the body .*at its offset \[0.0, -0.6, 0.0\] at rest"):
        read_scene(beam(table), "placed").build()


def test_a_ball_inside_the_3d_body_or_cutting_its_end_between_the_nodes_is_refused_at_rest():
    """The 3D form, on the box body (nodes every 0.5 along x, 0.2 along y and z; its end face x = 1.75)."""
    mesh = box_with_cavity()
    schedule = ChamberSchedule("pressure", ((1, 0.0),))
    for ball, where in ((Sphere((1.5, 0.1, 0.1), 0.05), "it lies inside"), (Sphere((1.78, 0.1, 0.1), 0.06), "reaches")):
        assert distance(mesh.vertices, ball, ball.center).min() > 0
        assert overlaps(mesh, mesh.vertices, ball, ball.center)
        obstacle = Obstacle("ball", ball, 0.01, 10.0)
        with pytest.raises(PneumaInputError, match=f"obstacle 'ball' overlaps the body: .*{where}"):
            scene_of(mesh, (schedule,), 1, Material(1e4, 0.3), obstacles=(obstacle,)).build()


FAR = pebble((1.85, 0.5), 0.05)


@pytest.mark.parametrize(
    ("table", "message"),
    [
        (
            FAR + "keyframes = [[1, [0.0, 1e308]]]",
            r"keyframes offset \[0.0, 1e\+308\] at step 1 must lie within \+-20.22 in each component",
        ),
        (FAR + "keyframes = [[1, [0.0, 0.0, 0.3]]]", r"moves it along z; a 2D scene's obstacle moves in its plane"),
        (FAR + "keyframes = [[1, [0.0, -15.0]]]", r"moves 15 in one increment: at most 1000 sweeps of 0.005"),
        (FAR.replace('"pebble"', '"x/../../escaped"'), r"obstacle name = 'x/../../escaped' must be 1 to 100 letters"),
        (FAR.replace('"pebble"', '"\\tpebble"'), r"obstacle name '\\tpebble' cannot start with = \+ - @, a tab"),
        (FAR.replace('"pebble"', '"=1+2"'), r"obstacle name '=1\+2' cannot start with = \+ - @, a tab"),
    ],
    ids=["offset-1e308", "z-offset-2d", "too-far-per-increment", "path-name", "tab-name", "formula-name"],
)
def test_bad_obstacle_input_is_one_error_naming_it(table, message):
    """The body is 2 x 0.3 (its size 2.02); the pebble's default dhat 0.01 and the median boundary side (0.1)
    make its sweep 0.005."""
    with pytest.raises(PneumaInputError, match=message):
        read_scene(beam(table), "bad").build()


def test_an_obstacle_named_as_a_path_exits_2_and_writes_nothing(tmp_path, capsys):
    """pneuma-inflate: one error line, exit 2, no file written inside or above --out."""
    scene = tmp_path / "scene.toml"
    scene.write_text(beam_text(FAR.replace('"pebble"', '"x/../../escaped"')))
    out = tmp_path / "a" / "b"
    assert main(["--scene", str(scene), "--out", str(out), "--no-video", "--quiet"]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error:") and "x/../../escaped" in lines[0]
    assert sorted(p.name for p in tmp_path.rglob("*")) == ["scene.toml"]
