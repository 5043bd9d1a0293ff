"""Equilibrium sensitivities against central finite differences of full Newton re-solves.

Each derivative d(output)/dq_j is compared with (output(q + h e_j) - output(q - h e_j)) / 2h, both
sides solved to a relative residual of 1e-10 from the equilibrium at q. The step h balances the
truncation error (h^2 f'''/6; measured ~7e-7 relative at h = 1e-3 for area ratios, ~5e-9 at h = 0.1
for pressures) against the solver error (~tol / h): with these steps both sit well below 1e-5.
"""

from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from solid_meshes import extruded_beam, scene_of

from taichi_pneuma.fem.tip import tip_outputs
from taichi_pneuma.scene.build import reference_scene
from taichi_pneuma.scene.scenefile import load_scene
from taichi_pneuma.scene.schedule import area_ramp
from taichi_pneuma.solve.linsolve import FixedPattern
from taichi_pneuma.solve.newton import NewtonOptions, NewtonSolver
from taichi_pneuma.solve.sensitivity import command_forces, sensitivity
from taichi_pneuma.solve.simulate import settle

SCENES = Path(__file__).resolve().parent.parent / "taichi_pneuma" / "scenes"
TIGHT = NewtonOptions(tol=1e-10)
STEP = {"area": 1e-3, "pressure": 0.1}

CASES = {
    "reference": (lambda: reference_scene(max_area=0.01, chamber_points=64), [2.0]),
    "bidirectional": (lambda: load_scene(SCENES / "bidirectional.toml"), [1.8, 1.3]),
    "pneunet_finger": (lambda: load_scene(SCENES / "pneunet_finger.toml"), [300.0, 500.0, 400.0, 600.0, 200.0, 450.0]),
    # gravity, with 15 vertices inside the ground barrier's activation distance at these pressures
    "finger_on_ground": (lambda: load_scene(SCENES / "finger_on_ground.toml"), [100.0, 150.0, 120.0, 80.0, 60.0]),
    # 3D: the extruded beam (tetrahedra, its prism chamber closed by the two z planes)
    "solid": (lambda: scene_of(extruded_beam(0.05, chamber_points=32)[0], [area_ramp(2.0, 2, 1e5)], 1), [1.6]),
}


def equilibrium(built, commands, solver):
    rest = built.scene.schedule.rest_commands
    u, *_ = settle(built, solver, rest, np.zeros_like(built.mesh.vertices), np.asarray(commands, float))
    return u


def finite_differences(built, solver, commands, u):
    """Central differences of the tip outputs (dx, dy, rotation, in 3D dz) (3 or 4, m) and of every displacement
    (n, 2, m)."""
    tips, states = [], []
    for j, chamber in enumerate(built.chambers):
        h = STEP[chamber.kind.name]
        plus, minus = (
            settle(built, solver, commands, u, commands + sign * h * np.eye(len(commands))[j])[0] for sign in (1, -1)
        )
        tips.append((tip_outputs(built.mesh, plus) - tip_outputs(built.mesh, minus)) / (2 * h))
        states.append((plus - minus) / (2 * h))
    return np.column_stack(tips), np.stack(states, axis=-1)


def relative_error(approx, exact):
    """Per output row: the largest deviation over the commands, relative to the row's largest derivative."""
    approx, exact = approx.reshape(-1, approx.shape[-1]), exact.reshape(-1, exact.shape[-1])
    return np.abs(approx - exact).max(axis=1) / np.abs(exact).max(axis=1)


def errors_against_finite_differences(case):
    """Sensitivities at the case's equilibrium against central differences of re-solves: the relative
    errors of the tip rows (dx, dy, rotation), that of du/dq over the DOFs that move noticeably
    (relative to the largest derivative), the built scene, the Sensitivity and the differences."""
    make, commands = CASES[case]
    built = make().build()
    commands = np.array(commands)
    solver = NewtonSolver(built.model, TIGHT)
    u = equilibrium(built, commands, solver)
    s = sensitivity(built, commands, u)
    fd_tip, fd_u = finite_differences(built, solver, commands, u)
    fd_tip = fd_tip[:3]  # dx, dy, rotation
    moving = np.abs(fd_u).max(axis=-1) > 1e-3 * np.abs(fd_u).max()
    du_error = np.abs(s.displacements - fd_u)[moving].max() / np.abs(fd_u).max()
    return relative_error(s.tip[:3], fd_tip), du_error, built, s, fd_tip  # (3D's tip dz: test_solid_apps.py)


@pytest.mark.parametrize("case", list(CASES))
def test_sensitivities_match_finite_differences_of_resolves(case):
    tip_errors, du_error, built, s, fd_tip = errors_against_finite_differences(case)
    chambers = len(CASES[case][1])
    assert s.tip.shape == (3 + (built.mesh.dim == 3), chambers) and s.displacements.shape == (
        built.mesh.n_vertices,
        built.mesh.dim,
        chambers,
    )
    assert np.all(np.abs(fd_tip).max(axis=1) > 0)  # every tip output moves
    assert tip_errors.max() <= 1e-5  # tip dx, dy and rotation
    assert du_error <= 1e-5


def test_psd_projected_hessian_gives_wrong_sensitivities():
    """The projected Hessian (what Newton uses far from equilibrium) is not the derivative of the residual."""
    built = reference_scene(max_area=0.01, chamber_points=64).build()
    commands = np.array([2.0])
    solver = NewtonSolver(built.model, TIGHT)
    u = equilibrium(built, commands, solver)
    model = built.model
    model.set_displacements(u)
    projected = FixedPattern(*model.hessian_pattern(), model.n_dofs).matrix(model.hessian_values(psd_only=True))
    ((_, gradient, k),) = model.low_rank()
    rows = built.chambers[0].dofs
    dense = projected.toarray()
    dense[np.ix_(rows, rows)] += k * np.outer(gradient, gradient)
    du_psd = spla.spsolve(sp.csr_matrix(dense), command_forces(built)[:, 0]).reshape(-1, 2)
    fd_tip, _ = finite_differences(built, solver, commands, u)
    psd_tip_dy = du_psd[built.mesh.tip, 1].mean()
    assert abs(psd_tip_dy - fd_tip[1, 0]) > 0.1 * abs(fd_tip[1, 0])  # measured: -0.0098 vs -0.242
    assert abs(sensitivity(built, commands, u).tip[1, 0] - fd_tip[1, 0]) <= 1e-5 * abs(fd_tip[1, 0])
