"""Train a reduced-order model of a scene (POD basis + ECSW hyper-reduction of its elasticity, fibres and sheets),
validate it against the full model on held-out commands, and save it as one .npz file.

    pneuma-reduce --scene pneunet_finger --energy 0.999999 --samples 24
    pneuma-reduce --scene reference_beam --modes 8 --set mesh.max_area=0.004

Trains on the scene's schedule and a Latin hypercube of --samples chamber commands in the schedule's range (each
solved by the full model), keeps --modes POD modes or those keeping --energy of the snapshots' energy, and samples
the pieces of each piecewise term (the elements; a fibre's segments, a sheet's cells) by ECSW to --ecsw-tol.
--workers N solves the hypercube points on N worker processes, --ray [ADDRESS] as Ray tasks (the schedule, a ramp,
is solved here first). Prints the modes and the kept energy, the pieces sampled per term, the training time, the
errors at --held-out commands (the tip displacement's as % of the body's length, the bend angle's in degrees, the
reduced state's full residual) and the time per equilibrium of the reduced and of the full model. Writes
<out>/<stem>_reduced.npz (the model: pneuma_reduce's store refuses it for a changed scene) and
<out>/<stem>_reduced.json (the figures printed). Exit codes: 0 done, 1 no equilibrium, 2 bad input (one `error:`
line).
"""

from __future__ import annotations

import argparse
import sys

import numpy as np

from .. import runtime
from ..errors import require
from ..io.output import lock_stem, prepare_directory, save_json
from .cli import (
    add_ramp_arguments,
    add_scene_arguments,
    app_parser,
    build,
    exit_code,
    newton_options,
    scene_of_flags,
)
from .stems import result_stem
from .workers import add_executor_arguments, executor_of


def parser() -> argparse.ArgumentParser:
    p = app_parser("pneuma-reduce", __doc__)
    add_scene_arguments(p)
    size = p.add_mutually_exclusive_group()
    size.add_argument("--modes", type=int, default=None, help="POD modes kept")
    size.add_argument(
        "--energy", type=float, default=None, help="keep the fewest modes holding this fraction of the energy"
    )
    p.add_argument("--samples", type=int, default=16, help="Latin hypercube points trained on, besides the schedule")
    p.add_argument("--held-out", type=int, default=4, help="held-out commands the reduced model is validated on")
    p.add_argument("--seed", type=int, default=0, help="seed of the training hypercube (the held-out one: seed + 1)")
    p.add_argument(
        "--ecsw-tol", type=float, default=1e-4, help="relative tolerance of the ECSW fit of the projected forces"
    )
    add_executor_arguments(p, "the hypercube points", "in this process")
    add_ramp_arguments(p)
    return p


def check_reduce_flags(args: argparse.Namespace) -> None:
    """Refuse bad --modes, --energy, --samples, --held-out and --ecsw-tol before any work; neither --modes nor
    --energy: --energy 1 - 1e-6."""
    if args.modes is None and args.energy is None:
        args.energy = 1 - 1e-6
    require(args.modes is None or args.modes >= 1, f"--modes = {args.modes!r} must be >= 1")
    require(args.energy is None or 0 < args.energy < 1, f"--energy = {args.energy!r} must lie in (0, 1)")
    require(args.samples >= 0, f"--samples = {args.samples!r} must be >= 0")
    require(args.held_out >= 1, f"--held-out = {args.held_out!r} must be >= 1")
    require(0 < args.ecsw_tol < 1, f"--ecsw-tol = {args.ecsw_tol!r} must lie in (0, 1)")


def where_text(where: dict) -> str:
    """An executor's describe() in words: 'process pool (workers 2)', 'this process'."""
    details = ", ".join(f"{key} {value}" for key, value in where.items() if key != "executor")
    return where["executor"] + (f" ({details})" if details else "")


def run(args: argparse.Namespace) -> dict:
    from ..reduce.ecsw import piecewise_terms
    from ..reduce.store import save_reduced
    from ..reduce.train import train, validate

    check_reduce_flags(args)
    scene = scene_of_flags(args)
    stem = result_stem(scene.name if args.scene else f"reduce_cy{args.cy:+.2f}", args, scene) + "_reduced"
    out = prepare_directory(args.out)
    runtime.init(args.arch)
    with lock_stem(out, stem):
        built = build(scene, args)
        options = newton_options(args)
        with executor_of(args, here=True) as executor:
            where = executor.describe() if executor is not None else {"executor": "this process"}
            training = train(
                built, args.modes, args.energy, args.samples, args.seed, options, args.ecsw_tol, executor=executor
            )
        model, snapshots = training.model, training.snapshots
        sizes = {label: term.n_pieces for label, term in piecewise_terms(built.model.terms).items()}
        sampled = {
            label: {"pieces": len(s.pieces), "of": sizes[label], "fit_error": s.error}
            for label, s in training.sampling.items()
        }
        trained_seconds = sum(training.seconds.values())
        print(
            f"training: {len(snapshots.commands)} equilibria ({built.scene.increments + 1} of the schedule, "
            f"{len(snapshots.commands) - built.scene.increments - 1} of {args.samples} hypercube points; "
            f"{snapshots.failed} found none; hypercube points solved in {where_text(where)}) "
            f"in {trained_seconds:.1f} s "
            f"(full solves {training.seconds['snapshots']:.1f} s, POD {training.seconds['pod']:.2f} s, "
            f"ECSW {training.seconds['ecsw']:.2f} s)"
        )
        print(
            f"basis: {model.n_modes} modes keep {training.kept_energy:.10f} of the snapshots' energy "
            f"(1 - {1 - training.kept_energy:.2e})"
        )
        for label, s in sampled.items():
            print(
                f"ECSW {label}: {s['pieces']} of {s['of']} pieces ({100 * s['pieces'] / max(s['of'], 1):.1f} %), "
                f"projected force fit error {s['fit_error']:.2e} (tolerance {args.ecsw_tol:g})"
            )
        compared = validate(training, args.held_out, args.seed + 1, options)
        tip = np.array([c.tip_error for c in compared])
        angle = np.array([c.angle_error for c in compared])
        residual = np.array([c.residual for c in compared])
        full_ms = 1000 * float(np.mean([c.full_seconds for c in compared]))
        reduced_ms = 1000 * float(np.mean([c.reduced_seconds for c in compared]))
        print(
            f"validation on {len(compared)} held-out commands: tip error max {tip.max():.3g} % of the body's length "
            f"(mean {tip.mean():.3g} %), bend angle error max {angle.max():.3g} deg (mean {angle.mean():.3g} deg), "
            f"full residual of the reduced states max {residual.max():.2e}"
        )
        print(
            f"time per equilibrium (from the nearest training state): reduced {reduced_ms:.1f} ms, full "
            f"{full_ms:.1f} ms ({full_ms / reduced_ms:.1f}x)"
        )
        path = out / f"{stem}.npz"
        save_reduced(path, model, training.singular_values)
        summary = {
            "scene": scene.name,
            "modes": model.n_modes,
            "kept_energy": training.kept_energy,
            "sampled": sampled,
            "snapshots": len(snapshots.commands),
            "failed_samples": snapshots.failed,
            "training_seconds": training.seconds,
            "training_executor": where,
            "held_out": [
                {
                    "commands": c.commands.tolist(),
                    "tip_error_percent": c.tip_error,
                    "angle_error_deg": c.angle_error,
                    "full_residual": c.residual,
                    "full_ms": 1000 * c.full_seconds,
                    "reduced_ms": 1000 * c.reduced_seconds,
                }
                for c in compared
            ],
            "full_ms_per_equilibrium": full_ms,
            "reduced_ms_per_equilibrium": reduced_ms,
            "all_converged": True,
        }
        summary_path = save_json(out / f"{stem}.json", summary)
    print(f"wrote {path}, {summary_path}")
    return summary


def main(argv: list[str] | None = None) -> int:
    return exit_code(run, parser().parse_args(argv))


if __name__ == "__main__":
    sys.exit(main())
