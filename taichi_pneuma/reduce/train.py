"""Training a reduced model of a built scene, and validating it against the full model.

train: snapshots of the full model's equilibria (snapshots.py), the POD basis of their displacements (pod.py), the
ECSW sampling of each piecewise term on that basis (ecsw.py); the training coordinates q_s = V^T u_s, from which reduced
solves start.

validate: held-out commands (a Latin hypercube of another seed in the training box), each solved by the full model
(settle, from the nearest training equilibrium) and by the reduced one (from the nearest training coordinates). Its
errors are those of the tip (fem/tip.py): the distance between the two tip displacements as a percentage of the body's
length (its rest extent along x), and the difference of the tip rotations (the bend angle) in degrees; and the
seconds per equilibrium of each.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from ..fem.tip import tip_measures
from ..scene.build import BuiltScene
from ..solve.newton import NewtonOptions, NewtonSolver
from ..solve.simulate import settle
from .ecsw import Sampling, sample_terms
from .model import ReducedModel, require_elementwise
from .pod import pod_basis
from .snapshots import Snapshots, command_box, hypercube, nearest, solve_snapshots
from .solve import equilibrium, indicator

ECSW_TOL = 1e-4  # the default relative tolerance of the ECSW fit of the projected snapshot forces


@dataclass
class Training:
    """A trained reduced model and how it was made: the snapshots, all singular values, the kept energy fraction, the
    ECSW sampling of each piecewise term (by label) and the seconds of each phase (snapshots, pod, ecsw)."""

    model: ReducedModel
    snapshots: Snapshots
    singular_values: np.ndarray
    kept_energy: float
    sampling: dict[str, Sampling]
    seconds: dict[str, float]


def train(
    built: BuiltScene,
    modes: int | None = None,
    energy: float | None = None,
    samples: int = 16,
    seed: int = 0,
    options: NewtonOptions | None = None,
    ecsw_tol: float = ECSW_TOL,
    snapshots: Snapshots | None = None,
    executor=None,
) -> Training:
    """Train a reduced model of the built scene (the module docstring) with `modes` modes or those keeping the energy
    fraction `energy`, on the schedule and `samples` hypercube points (seed: the hypercube's), or on the snapshots
    given (then samples and seed are not used); the hypercube points solved on the executor's workers where one is
    given (snapshots.py)."""
    require_elementwise(built)  # before the full solves
    snapshots = snapshots or solve_snapshots(built, samples, seed, options, executor)
    started = time.perf_counter()
    basis, sigma, kept = pod_basis(snapshots.displacements, modes, energy)
    pod_seconds = time.perf_counter() - started
    started = time.perf_counter()
    sampling = sample_terms(built.model.terms, basis, snapshots.displacements, ecsw_tol)
    ecsw_seconds = time.perf_counter() - started
    sampled = {label: (s.pieces, s.weights) for label, s in sampling.items()}
    model = ReducedModel(built, basis, sampled, (snapshots.commands, snapshots.displacements @ basis))
    seconds = {"snapshots": snapshots.seconds, "pod": pod_seconds, "ecsw": ecsw_seconds}
    return Training(model, snapshots, sigma, kept, sampling, seconds)


@dataclass
class Comparison:
    """One held-out command: the tip error (% of body length), the bend angle error (degrees), the indicator's full
    residual and whether the command is inside the training box, and the seconds of the full and reduced solves."""

    commands: np.ndarray
    tip_error: float
    angle_error: float
    residual: float
    inside: bool
    full_seconds: float
    reduced_seconds: float


def body_length(built: BuiltScene) -> float:
    """The body's rest extent along x."""
    x = built.mesh.vertices[:, 0]
    return float(x.max() - x.min())


def compare(training: Training, commands: np.ndarray, solver: NewtonSolver) -> Comparison:
    """The reduced and the full equilibrium at `commands`, each from the nearest training equilibrium (the full one
    from its snapshot u_s, the reduced one from q_s = V^T u_s)."""
    model, built = training.model, training.model.built
    snapshots = training.snapshots
    low, high = snapshots.commands.min(axis=0), snapshots.commands.max(axis=0)
    i = nearest(snapshots.commands, commands, low, high)
    started = time.perf_counter()
    built.set_commands(snapshots.commands[i])
    u_start = snapshots.displacements[i].reshape(built.mesh.vertices.shape)
    u_full, *_ = settle(built, solver, snapshots.commands[i], u_start, commands)
    full_seconds = time.perf_counter() - started
    reduced = equilibrium(model, commands, (snapshots.commands[i], snapshots.displacements[i] @ model.basis))
    u_reduced = model.displacements(reduced.q)
    check = indicator(model, commands, reduced.q)
    (tip_full, angle_full), (tip_reduced, angle_reduced) = (tip_measures(built.mesh, u) for u in (u_full, u_reduced))
    return Comparison(
        np.asarray(commands),
        100.0 * float(np.linalg.norm(tip_full - tip_reduced)) / body_length(built),
        abs(angle_full - angle_reduced),
        check.residual,
        check.inside,
        full_seconds,
        reduced.seconds,
    )


def validate(training: Training, held_out: int, seed: int, options: NewtonOptions | None = None) -> list[Comparison]:
    """Compare the reduced and the full model at `held_out` hypercube points of the training box (seed: another one
    than the training's)."""
    low, high = command_box(training.model.built)
    solver = NewtonSolver(training.model.model, options)
    return [compare(training, c, solver) for c in hypercube(low, high, held_out, seed)]
