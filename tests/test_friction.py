"""Coulomb friction (terms/friction.py): the term's derivatives against finite differences in the sticking (slip <
eps) and sliding (slip > eps) regimes, 2D and 3D; a block on an inclined plane that sticks below tan(theta) = mu
and slides above it; a frictionless scene building no friction term; bad keys refused."""

import math
import tomllib
from pathlib import Path

import numpy as np
import pytest
from fd import term_derivatives, term_hessian
from test_obstacles import contact

from taichi_pneuma.errors import PneumaInputError
from taichi_pneuma.scene import build
from taichi_pneuma.scene.scenefile import load_scene, read_scene
from taichi_pneuma.solve.simulate import RampFailed, run_schedule
from taichi_pneuma.terms.friction import ObstacleFriction, frictional
from taichi_pneuma.terms.obstacle_shapes import Plane, Sphere

EPS = 0.01
SCENES = Path(__file__).resolve().parents[1] / "taichi_pneuma" / "scenes"
SHAPES = {  # by dimension: a 2D scene's shape in its plane (a normal with no z)
    "plane": lambda dim: Plane((0.0, 0.0, 0.0)[:dim], (1.0, 2.0, 0.5)[:dim]),
    "sphere": lambda dim: Sphere((0.0, 0.0, 0.0)[:dim], 1.0),
}
NEAR = {"plane": [(0.1, 0.1, 0.05), (0.3, -0.05, 0.0)], "sphere": [(1.2, 0.1, 0.05), (-0.3, 1.0, 0.4)]}


def friction_on(points, shape, mu=0.6, eps=EPS):
    """A friction term on free points lagged at rest (each within dhat = 0.5 of the shape: lambda > 0)."""
    return ObstacleFriction(contact(points, shape), mu, eps)


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("name", list(SHAPES))
@pytest.mark.parametrize("slip", [0.3 * EPS, 3.0 * EPS], ids=["sticking", "sliding"])
def test_friction_gradient_and_hessian_match_finite_differences(name, dim, slip):
    """Energy -> gradient and gradient -> Hessian on nodes moved by `slip` along the tangent plane (and half that
    along the normal) from their lagged positions, the obstacle moved since the lag (its translation subtracted);
    the Hessian is PSD, psd_only the same; the force is tangential, mu lambda where sliding."""
    points = np.array(NEAR[name])[:, :dim]
    term = friction_on(points, SHAPES[name](dim))
    assert np.all(term.lagged[:, 0] > 0)  # every node in contact
    term.contact.set_offset(np.full(dim, 0.1 * EPS))
    n = term.lagged[:, 1 : 1 + dim]
    direction = np.random.default_rng(2).standard_normal(points.shape)
    along = direction - np.sum(direction * n, axis=1, keepdims=True) * n
    u = slip * along / np.linalg.norm(along, axis=1, keepdims=True) + 0.5 * slip * n  # the normal part is free
    term.config.u[:] = u
    g_fd, h_fd = term_derivatives(term, u)
    g = term.gradient().ravel()
    assert np.linalg.norm(g) > 0.1
    assert np.linalg.norm(g - g_fd) <= 1e-6 * np.linalg.norm(g)
    hessian, scale = term_hessian(term), np.linalg.norm(g) / slip  # scale: the size of mu lambda f1(y) / y
    assert np.linalg.norm(hessian - h_fd) <= 1e-5 * scale
    assert np.linalg.eigvalsh(hessian).min() >= -1e-12 * scale
    if dim == 2 and slip > EPS:  # a 1D tangent: kinetic friction, a constant force, has no stiffness
        assert np.linalg.norm(hessian) <= 1e-12 * scale
    assert np.array_equal(term_hessian(term, psd_only=True), hessian)
    lam, force = term.lagged[:, 0], -term.gradient()
    assert np.abs(np.sum(force * n, axis=1)) == pytest.approx(0.0, abs=1e-12)  # tangential
    if slip > EPS:
        assert np.linalg.norm(force, axis=1) == pytest.approx(term.mu * lam, rel=1e-12)


def test_the_smoothed_friction_force_rises_to_mu_lambda_over_eps():
    """One node on the plane y >= 0 slipping y along x: force mu lambda (2 y / eps - y^2 / eps^2) below eps, mu
    lambda beyond; energy mu lambda f0(y) (eps / 3 at 0, C1 at eps)."""
    term = friction_on([(0.0, 0.2)], Plane((0.0, 0.0), (0.0, 1.0)), mu=0.5)
    lam = term.lagged[0, 0]
    for y, f1, f0 in ((0.0, 0.0, EPS / 3), (0.5 * EPS, 0.75, EPS * (1 / 3 + 1 / 4 - 1 / 24)), (2 * EPS, 1.0, 2 * EPS)):
        term.config.u[:] = [[y, 0.3]]  # the normal motion is free
        assert -term.gradient()[0] == pytest.approx([-0.5 * lam * f1, 0.0], abs=1e-12)
        assert term.energy() == pytest.approx(0.5 * lam * f0, rel=1e-12)


def test_no_friction_no_term():
    """friction = 0 adds no term: the contact alone."""
    term = contact([(0.0, 0.2)], Plane((0.0, 0.0), (0.0, 1.0)))
    assert frictional(term, 0.0, None) == [term]
    pair = frictional(term, 0.4, None)
    assert pair[0] is term and pair[1].eps == pytest.approx(term.dhat / 10) and pair[1].name == "o.friction"
    assert math.isfinite(pair[1].energy())


MU, DHAT, SLIP = 0.5, 0.01, 0.002


def incline(ratio: float, dim: int, increments: int = 3):
    """(scene, t, n): a 0.4 x 0.2 block (0.2 deep in 3D; E = 1e4, density 1, g = 9.81, an empty chamber in it, as a
    scene has one) on the plane through the origin tilted by theta = atan(ratio mu) (unit tangent t up the slope,
    normal n), its bottom 0.3 dhat from it (the rest state's lagged normal forces hold it at step 0; from step 1 on
    they are the weight's)."""
    theta = math.atan(ratio * MU)
    t, n = np.array([math.cos(theta), math.sin(theta)]), np.array([-math.sin(theta), math.cos(theta)])
    w, h, gap = 0.4, 0.2, 0.3 * DHAT
    corners = [(gap * n + a * t + b * n).tolist() for a, b in ((-w / 2, 0), (w / 2, 0), (w / 2, h), (-w / 2, h))]
    points = ", ".join(f"[{x!r}, {y!r}]" for x, y in corners)
    c, n_ = ((gap + h / 2) * n).tolist(), n.tolist()
    z = ", 0.0" if dim == 3 else ""
    if dim == 2:
        body = f'shape = "polygon"\npoints = [{points}]\n[mesh]\nmax_area = 0.004'
        hole = f'shape = "ellipse"\ncenter = [{c[0]!r}, {c[1]!r}]\nsemi_axes = [0.04, 0.03]\npoints = 12'
    else:
        profile = f'{{ shape = "polygon", points = [{points}] }}'
        body = f'shape = "extrusion"\ndepth = 0.2\nprofile = {profile}\n[mesh]\nsize = 0.08'
        hole = f'shape = "ellipsoid"\ncenter = [{c[0]!r}, {c[1]!r}, 0.0]\nsemi_axes = [0.04, 0.04, 0.04]'
    text = f"""
[body]
{body}
[material]
E = 1e4
nu = 0.3
[[chambers]]
name = "hole"
{hole}
control = "pressure"
keyframes = [[{increments}, 0.0]]
[effects.gravity]
density = 1.0
[[obstacles]]
name = "slope"
shape = "plane"
point = [0.0, 0.0{z}]
normal = [{n_[0]!r}, {n_[1]!r}{z}]
dhat = {DHAT}
stiffness = 1e3
friction = {MU}
friction_slip = {SLIP}
[schedule]
increments = {increments}
"""
    return read_scene(tomllib.loads(text), "incline"), t, n


def run_incline(ratio, dim, monkeypatch):
    """The incline's run (max_cuts 1). The build's support check counts no obstacle as a support (a free body on
    one is refused): lifted here, friction holding the block."""
    monkeypatch.setattr(build, "require_held", lambda *args: None)
    scene, t, n = incline(ratio, dim)
    built = scene.build()
    return built, t, n, lambda: run_schedule(built, max_cuts=1)


@pytest.mark.parametrize("dim", [2, 3])
def test_a_block_on_a_slope_below_the_friction_angle_sticks(dim, monkeypatch):
    """tan(theta) = 0.8 mu: every increment finds equilibrium; the friction force balances the weight's component
    along the slope, W sin(theta), and the normal force W cos(theta) (to the solver's tolerance); the block creeps
    by the slip y at which the smoothed friction carries it, mu N f1(y) = W sin(theta): y = (1 - sqrt(1 - 0.8)) eps
    = 0.553 eps per increment (quasistatic friction acts on each increment's displacement)."""
    built, t, n, run = run_incline(0.8, dim, monkeypatch)
    result = run()
    theta = math.atan(0.8 * MU)
    weight = 9.81 * built.mesh.measure
    history = {key: np.array([step.row()[key] for step in result.steps]) for key in result.steps[0].row()}
    assert history["converged"].all() and len(result.steps) == 4
    friction = np.stack([history["slope.friction.fx"], history["slope.friction.fy"]], axis=1)
    normal = np.stack([history["slope.fx"], history["slope.fy"]], axis=1)
    assert friction @ t == pytest.approx(weight * math.sin(theta), rel=1e-4)
    assert friction @ n == pytest.approx(0.0, abs=1e-9 * weight)
    assert normal @ n == pytest.approx(weight * math.cos(theta), rel=1e-4)
    creep = np.diff((result.positions - result.positions[0]).mean(axis=1)[:, :2] @ t)
    assert creep[1:] / SLIP == pytest.approx(-(1 - math.sqrt(0.2)), rel=1e-3)


@pytest.mark.parametrize("dim", [2, 3])
def test_a_block_on_a_slope_past_the_friction_angle_slides(dim, monkeypatch):
    """tan(theta) = 1.25 mu: held at step 0 by the rest state's larger lagged normal forces, the block finds no
    equilibrium at step 1, its friction at mu N = mu W cos(theta) < W sin(theta): the ramp stops, naming the slide."""
    built, _, _, run = run_incline(1.25, dim, monkeypatch)
    with pytest.raises(RampFailed, match=r"step 1: .*\(the body slides on 'slope'") as failure:
        run()
    assert len(failure.value.result.steps) == 1
    weight = 9.81 * built.mesh.measure
    assert f"mu N = {MU * weight * math.cos(math.atan(1.25 * MU)):.4g}" in str(failure.value)


def gripper(pull: float) -> tuple:
    """gripper_2d_friction (mu = 0.8; dhat 0.5 mm, so eps = 0.05 mm) on a coarse linear mesh, its cylinder pulled
    down `pull` mm over steps 12 to 20 after the fingers close: (history columns, steps of the pull)."""
    scene = load_scene(SCENES / "gripper_2d_friction.toml").with_values(
        {"mesh.max_area": 4.0, "mesh.order": 1, "obstacles[0].keyframes": [[12, [0.0, 0.0]], [20, [0.0, -pull]]]}
    )
    run = run_schedule(scene.build())
    assert all(step.converged for step in run.steps) and len(run.steps) == 21
    return {key: np.array([step.row()[key] for step in run.steps]) for key in run.steps[0].row()}, slice(13, 21)


def test_a_gripper_pulled_fast_slides_at_mu_times_its_grip():
    """The cylinder pulled 0.5 mm a step (10 eps): every contact node slides, so the friction on the fingers is mu
    times the normal force lagged from the step before (exactly, to round-off), within 10 % of mu times the step's
    own after the first step of the pull; it drags the fingers down (friction.fy < 0)."""
    history, pull = gripper(4.0)
    friction, normal = history["object.friction.magnitude"], history["object.magnitude"]
    assert normal[12] > 10.0  # the fingers hold it (kPa mm = N/m)
    assert friction[pull] == pytest.approx(0.8 * normal[12:20], rel=1e-9)
    later = slice(14, 21)  # the first step of the pull presses the cylinder onto the fingertips: N rises 25 %
    assert np.all(np.abs(friction[later] - 0.8 * normal[later]) <= 0.1 * 0.8 * normal[later])
    assert np.all(history["object.friction.fy"][pull] < -0.9 * friction[pull])


def test_a_gripper_pulled_slowly_holds_below_mu_times_its_grip():
    """The cylinder pulled 0.01 mm a step (0.2 eps): below the kinetic limit, the friction is the smoothed static
    branch, mu N f1(y) with y the slip of the step; the fingers, softer than the friction's spring (2 mu N / eps),
    barely follow, so y is about the pull per step and the friction settles at mu N f1(0.2 eps) = 0.36 mu N (within
    10 %): quasistatic friction acts on each increment's slip, holding a slow pull with less than mu N."""
    history, pull = gripper(0.08)
    friction, normal = history["object.friction.magnitude"], history["object.magnitude"]
    f1 = 2 * 0.2 - 0.2**2
    assert np.all(friction[pull] < 0.5 * 0.8 * normal[12:20])
    assert friction[17:21] == pytest.approx(f1 * 0.8 * normal[16:20], rel=0.1)
    assert np.all(history["object.friction.fy"][pull] < 0)


@pytest.mark.parametrize(
    ("key", "value", "message"),
    [
        ("friction", -0.1, r"friction = -0.1 must be >= 0 \(0: frictionless\)"),
        ("friction", "high", "friction = 'high' must be a number"),
        ("friction_slip", 0.0, r"friction_slip = 0.0 must be > 0 \(a length"),
    ],
)
def test_bad_friction_is_refused_naming_it(key, value, message):
    data = tomllib.loads(incline(0.8, 2)[0].to_toml())
    data["obstacles"][0][key] = value
    with pytest.raises(PneumaInputError, match=message):
        read_scene(data, "bad")


def test_a_friction_scene_reads_back_from_its_toml_and_a_frictionless_one_has_no_friction(monkeypatch):
    monkeypatch.setattr(build, "require_held", lambda *args: None)  # as run_incline
    scene, _, _ = incline(0.8, 3)
    assert read_scene(tomllib.loads(scene.to_toml()), "incline") == scene
    frictionless = scene.with_value("obstacles[0].friction", 0.0)
    assert "friction = " not in frictionless.to_toml()
    assert [t.name for t in frictionless.build().contact_terms()] == ["slope"]
    assert [t.name for t in scene.build().contact_terms()] == ["slope", "slope.friction"]


def test_a_ground_with_friction_holds_a_free_block_and_its_weight():
    """A free block on the ground under gravity: refused frictionless (the sliding is free), built with friction (the
    support check counts static friction), and at rest on it, the ground's friction column beside its normal one."""
    text = """
[body]
shape = "rectangle"
center = [0.0, 0.1]
size = [0.4, 0.2]
[mesh]
max_area = 0.004
[material]
E = 1e4
nu = 0.3
[[chambers]]
name = "hole"
shape = "ellipse"
center = [0.0, 0.1]
semi_axes = [0.04, 0.03]
points = 12
control = "pressure"
keyframes = [[1, 0.0]]
[effects.gravity]
density = 1.0
[effects.ground]
height = -0.003
friction = 0.5
[schedule]
increments = 1
"""
    data = tomllib.loads(text)
    run = run_schedule(read_scene(data, "block").build())
    row = run.steps[-1].row()
    assert row["ground.fy"] == pytest.approx(9.81 * 0.4 * 0.2 - 9.81 * math.pi * 0.04 * 0.03, rel=0.02)
    assert row["ground.friction.fx"] == pytest.approx(0.0, abs=1e-9)
    data["effects"]["ground"]["friction"] = 0.0
    with pytest.raises(PneumaInputError, match="leave free: translation along x"):
        read_scene(data, "block").build()
