"""A held object ([[obstacles]] weight and release: terms/held_object.py): from its release step the obstacle is free
to move along y under its weight, held by the grip's contact and friction alone. The lift: gripper_2d_friction's
fingers close on the cylinder (60 kPa), the cylinder is released with a weight W, and the pressure falls 1 kPa a step:
the grip holds it, its weight balanced by the normal and friction forces at every step, until it can no longer and
the cylinder slips out (the held object's slip, or the friction's slide where the Newton solve of the slide stalls).
The hand calculation: two symmetric contacts, each pressing with N / 2 at an angle to the horizontal whose sine is
Ny / N (N the grip force, object.magnitude; Ny the normal forces' upward part, -object.fy), hold at most
Ny + mu sqrt(N^2 - Ny^2) when they slide (mu N along the surface); the grip of the last step held carries the weight
within 10 % of it. And the energy with the object's height eliminated: its gradient and Hessian (the
terms' blocks with the rank-1 Schur complement of the height) against finite differences."""

import math
import tomllib

import numpy as np
import pytest

from taichi_pneuma.scene.scenefile import read_scene
from taichi_pneuma.scene.shipped import find
from taichi_pneuma.solve.linsolve import FixedPattern
from taichi_pneuma.solve.newton import NewtonOptions
from taichi_pneuma.solve.simulate import RampFailed, run_schedule

MU, WEIGHT, RELEASE = 0.8, 20.0, 13  # the scene's friction; a weight (kPa mm: per mm of depth); released at 60 kPa
PULL = "keyframes = [[12, [0.0, 0.0]], [20, [0.0, -4.0]]]"


def lift(weight: float, steps: int = 32):
    """gripper_2d_friction on a coarse linear mesh, its cylinder released at step RELEASE with the weight, the
    pressure 0 -> 60 kPa over 12 steps, then down 1 kPa a step."""
    text = find("gripper_2d_friction").read_text()
    assert PULL in text
    scene = read_scene(tomllib.loads(text.replace(PULL, f"weight = {weight}\nrelease = {RELEASE}")), "lift")
    values = {"mesh.max_area": 4.0, "mesh.order": 1, "schedule.increments": steps}
    for i in range(len(scene.controls)):
        values[f"chambers[{i}].keyframes"] = [[0, 0.0], [12, 60.0], [steps, 72.0 - steps]]
    return scene.with_values(values)


def test_a_grip_holds_its_object_until_its_friction_cannot_then_drops_it():
    with pytest.raises(RampFailed, match="'object' slips out of the grip|the body slides on 'object'") as failure:
        run_schedule(lift(WEIGHT).build(), options=NewtonOptions(max_iterations=20), max_cuts=3)
    steps = failure.value.result.steps
    rows = [step.row() for step in steps]
    held = [row for row in rows if row["step"] >= RELEASE]
    assert len(held) >= 3  # held at 59, 58, 57 kPa at least
    for row in held:  # the object's balance: its weight carried by the normal and friction forces on it
        assert -(row["object.fy"] + row["object.friction.fy"]) == pytest.approx(WEIGHT, rel=1e-4)
    pressure = held[-1]["l1.pressure"]
    assert 45.0 < pressure < 59.0  # it drops on the way down, not at once
    last = held[-1]
    grip, lift_part = last["object.magnitude"], -last["object.fy"]
    holds = lift_part + MU * math.sqrt(grip**2 - lift_part**2)
    assert holds == pytest.approx(WEIGHT, rel=0.1)


def test_the_energy_with_the_height_eliminated_matches_finite_differences():
    """Near a held state (the run to 58 kPa, every node then moved by up to 1e-3: no equilibrium, the friction
    slipping), the gradient of E(x) = min_o phi(x, o) against central differences of E along random directions v,
    and its Hessian (sparse part plus the low-rank Schur complement of the height) times v against those of the
    gradient."""
    built = lift(WEIGHT, steps=14).build()
    run = run_schedule(built)
    model = built.model
    held = next(t for t in model.terms if t.name == "object.weight")
    rng = np.random.default_rng(0)
    u = run.positions[-1] - built.mesh.vertices + 1e-3 * rng.uniform(-1, 1, built.mesh.vertices.shape)
    model.set_displacements(u)
    assert held.free and not held.slipped and held.columns()["object.dy"] < 0
    pattern = FixedPattern(*model.hessian_pattern(), model.n_dofs)
    matrix = model.assemble(pattern, model.hessian_parts(False))
    g = model.gradient()[0]
    h = 1e-6
    for _ in range(3):
        v = rng.standard_normal(u.size)
        v *= 1e-2 / np.abs(v).max()  # directions small against the contact's dhat (0.5)
        hv = matrix @ v + sum(
            c * part @ v[dofs] * np.bincount(dofs, part, u.size) for dofs, part, c in model.low_rank()
        )
        model.set_displacements(u.ravel() + h * v)
        e_plus, g_plus = model.energy(), model.gradient()[0]
        model.set_displacements(u.ravel() - h * v)
        e_minus, g_minus = model.energy(), model.gradient()[0]
        model.set_displacements(u)
        assert (e_plus - e_minus) / (2 * h) == pytest.approx(g @ v, rel=1e-5)
        np.testing.assert_allclose((g_plus - g_minus) / (2 * h), hv, rtol=0, atol=1e-5 * np.abs(hv).max())
