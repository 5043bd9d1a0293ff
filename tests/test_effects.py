"""The effect terms (gravity, ground contact, self-contact) and pressure control: finite-difference
derivatives, step bounds that stop before contact is crossed, and exactly the terms a scene names."""

import numpy as np
import pytest
from fd import dense_hessian, fd_hessian
from test_terms import assert_gradient_matches_finite_differences

from taichi_pneuma.fem.planar import Geometry
from taichi_pneuma.fem.shapes import Ellipse, Rectangle
from taichi_pneuma.fem.supports import PointSet
from taichi_pneuma.scene.build import ChamberControl, Scene, reference_scene
from taichi_pneuma.scene.schedule import ChamberSchedule
from taichi_pneuma.terms.effects import Gravity, Ground, SelfContact


def thin_chamber_scene(*effects, control="pressure"):
    """A small plate with a flat elliptical chamber (gap 0.02 at its middle), coarse."""
    geometry = Geometry(
        Rectangle((0.0, 0.0), (1.0, 0.3)), (("slit", Ellipse((0.0, 0.0), (0.3, 0.01), 24)),), 0.01, PointSet("left")
    )
    keyframes = ((0, 1.0), (1, 0.2)) if control == "area" else ((0, 0.0), (1, 10.0))
    return Scene(geometry, (ChamberControl(ChamberSchedule(control, keyframes)),), 1, effects=effects)


@pytest.fixture(scope="module")
def squeezed():
    """Every effect, with the walls squeezed to a gap of 0.006 < dhat and the plate 0.004 above the ground."""
    built = thin_chamber_scene(
        Gravity(1.0), Ground(-0.16, dhat=0.01, stiffness=100.0), SelfContact(dhat=0.008, stiffness=100.0)
    ).build()
    built.set_commands([5.0])
    X = built.mesh.vertices
    u = np.column_stack([np.zeros(len(X)), -0.7 * X[:, 1] - 0.111])  # y -> 0.3 y - 0.111: bottom at -0.156
    u += 1e-4 * np.random.default_rng(0).standard_normal(u.shape)
    return built, u


def test_terms_are_exactly_those_named():
    assert reference_scene().build().model.term_names() == ["elastic", "chamber:main", "clamp"]
    plain = thin_chamber_scene().build().model.term_names()
    with_gravity = thin_chamber_scene(Gravity(1.0)).build().model.term_names()
    assert with_gravity == plain + ["gravity"]
    everything = thin_chamber_scene(Gravity(1.0), Ground(-0.2), SelfContact()).build().model.term_names()
    assert everything == plain + ["gravity", "ground", "self_contact"]


@pytest.mark.parametrize("name", ["chamber:slit", "gravity", "ground", "self_contact"])
def test_gradient_matches_finite_differences(squeezed, name):
    built, u = squeezed
    assert_gradient_matches_finite_differences(built, name, u)


@pytest.mark.parametrize("name", ["chamber:slit", "ground", "self_contact"])
def test_exact_hessian_matches_finite_differences_and_psd_part_is_psd(squeezed, name):
    built, u = squeezed
    term = next(t for t in built.model.terms if t.name == name)
    built.model.set_displacements(u)
    exact = dense_hessian(built.model.n_dofs, [term], psd_only=False)
    h_fd = fd_hessian(built.model, [term], u)
    assert np.linalg.norm(exact - h_fd) / np.linalg.norm(h_fd) < 1e-5
    projected = dense_hessian(built.model.n_dofs, [term], psd_only=True)
    eigenvalues = np.linalg.eigvalsh(projected)
    assert eigenvalues.min() >= -1e-9 * max(eigenvalues.max(), 1.0)


def test_contact_step_bounds_stop_before_the_ground_and_the_opposite_wall(squeezed):
    built, u = squeezed
    model = built.model
    ground = next(t for t in model.terms if t.name == "ground")
    contact = next(t for t in model.terms if t.name == "self_contact")
    X = built.mesh.vertices
    # push the whole body down, and the walls through each other
    model.set_displacements(u)
    down = np.tile([0.0, -1.0], (len(X), 1))
    alpha = ground.max_step(down)
    lowest = (X + u)[:, 1].min()
    assert alpha == pytest.approx(lowest + 0.16, rel=1e-9)
    squeeze = np.column_stack([np.zeros(len(X)), -np.sign(X[:, 1]) * 0.05])
    alpha = contact.max_step(squeeze)
    assert 0 < alpha < 1
    model.set_displacements(u + 0.9 * alpha * squeeze)
    assert contact.min_distance() > 0 and np.isfinite(contact.energy())


def test_dynamics_step_response_overshoots_then_decays_to_the_static_shape():
    """Backward Euler with inertia: a sudden chamber inflation (1x -> 2x in one 0.02 s step, then held)
    swings the tip past the quasistatic equilibrium, then oscillates about it with decaying amplitude
    (backward Euler dissipates); the first peak comes about half a bending period in (~1 s here)."""
    import dataclasses

    from taichi_pneuma.scene.build import ChamberControl, reference_scene
    from taichi_pneuma.scene.schedule import ChamberSchedule
    from taichi_pneuma.solve.simulate import run_schedule
    from taichi_pneuma.terms.effects import Dynamics

    steps, dt = 100, 0.02
    jump = (ChamberControl(ChamberSchedule("area", ((0, 1.0), (1, 2.0), (steps, 2.0)))),)
    quasistatic = dataclasses.replace(reference_scene(cy=0.15, max_area=0.01), controls=jump, increments=steps)
    static_tip = run_schedule(quasistatic.build()).history["tip_dy"][-1]
    built = dataclasses.replace(quasistatic, effects=(Dynamics(density=1.0, dt=dt),)).build()
    assert built.model.term_names() == ["elastic", "chamber:main", "clamp", "inertia"]
    result = run_schedule(built)
    assert all(s.converged for s in result.steps)
    tip = result.history["tip_dy"]
    first_peak = int(np.argmax(tip[:50]))
    assert 0.3 < first_peak * dt < 0.8
    assert tip[first_peak] > 1.3 * static_tip  # overshoot
    assert tip[first_peak : first_peak + 30].min() < static_tip  # swings back below the static shape
    second_peak = tip[first_peak + 25 :].max()
    assert static_tip < second_peak < tip[first_peak]  # and the swing decays
