"""Inflate the chamber of the reference beam and report how it bends.

    python -m taichi_pneuma.apps.inflate --cy 0.15

Prints the mesh size, the chamber's rest area, the final area ratio, the tip deflection and the
peak chamber pressure; writes the per-step history (CSV), the states (npz) and a summary (JSON)
under --out.
"""

from __future__ import annotations

import argparse
import sys
import time

import numpy as np

from .. import runtime
from ..errors import PneumaInputError, require, require_finite
from ..geometry import BeamGeometry
from ..newton import NewtonOptions
from ..output import prepare_directory, save_json, save_npz, save_text
from ..scene import BeamScene, Material
from ..simulate import MAX_CUTS, RampFailed, area_ramp, run_ramp


def parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="python -m taichi_pneuma.apps.inflate", description=__doc__.split("\n")[0],
                                formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    p.add_argument("--cy", type=float, default=0.15, help="chamber centre height (above the neutral axis curls down)")
    p.add_argument("--cx", type=float, default=0.0, help="chamber centre along the beam")
    p.add_argument("--growth", type=float, default=3.5, help="final commanded area / rest area")
    p.add_argument("--steps", type=int, default=36, help="commanded areas in the ramp, rest included")
    p.add_argument("--E", type=float, default=1e4, help="Young's modulus")
    p.add_argument("--nu", type=float, default=0.45, help="Poisson's ratio, in (-1, 0.5)")
    p.add_argument("--k", type=float, default=1e5, help="chamber stiffness (area control penalty)")
    p.add_argument("--max-area", type=float, default=0.0012, help="Triangle's maximum triangle area")
    p.add_argument("--tol", type=float, default=1e-8, help="Newton tolerance on |gradient| / force scale")
    p.add_argument("--max-cuts", type=int, default=MAX_CUTS,
                   help="times a non-converging increment may be halved before the run stops")
    p.add_argument("--out", default="out", help="directory for the history (CSV), states (npz) and summary (JSON)")
    p.add_argument("--arch", default="cpu", choices=sorted(runtime.ARCHES), help="Taichi backend")
    p.add_argument("--quiet", action="store_true", help="no per-step progress lines")
    return p


def run(args: argparse.Namespace) -> dict:
    for name in ("cy", "cx", "growth", "E", "nu", "k", "max_area", "tol"):
        require_finite(f"--{name.replace('_', '-')}", getattr(args, name))
    options = NewtonOptions(tol=args.tol)
    require(args.max_cuts >= 0, f"--max-cuts = {args.max_cuts!r} must be >= 0")
    scene = BeamScene(BeamGeometry(cx=args.cx, cy=args.cy, max_area=args.max_area),
                      Material(args.E, args.nu), chamber_stiffness=args.k)
    ratios = area_ramp(1.0, args.growth, args.steps)  # commanded area / rest area; validated before any work
    out = prepare_directory(args.out)
    runtime.init(args.arch)
    built = scene.build()
    mesh = built.mesh
    print(f"mesh: {mesh.n_vertices} vertices, {mesh.n_triangles} triangles; chamber wall {len(mesh.chamber_loop)} "
          f"vertices, clamp {len(mesh.pinned)} vertices")
    print(f"chamber rest area: {built.rest_area:.3f}")

    def progress(step):
        if not args.quiet:
            print(f"  step {step.step:3d}/{len(ratios) - 1}  area x{step.area_ratio:5.3f}  "
                  f"p = {step.pressure:8.2f}  tip dy = {step.tip_dy:+.4f}  {step.iterations:2d} Newton it  "
                  f"residual {step.residual:.1e}", flush=True)

    start = time.perf_counter()
    stem = f"inflate_cy{args.cy:+.2f}"
    try:
        result = run_ramp(built, ratios * built.rest_area, options, progress, args.max_cuts)
    except RampFailed as failure:
        written = save_history(out, stem, built, failure.partial)
        print(f"error: {failure}; the {len(failure.partial.steps)} converged steps are saved in "
              + ", ".join(str(p) for p in written), file=sys.stderr)
        return {"all_converged": False}
    wall = time.perf_counter() - start
    final = result.steps[-1]
    iterations = result.column("iterations")[1:]
    summary = {
        "cx": args.cx, "cy": args.cy, "vertices": mesh.n_vertices, "triangles": mesh.n_triangles,
        "rest_area": built.rest_area, "final_area": final.area, "area_ratio": final.area_ratio,
        "tip_deflection": result.tip_deflection, "peak_pressure": result.peak_pressure,
        "all_converged": bool(all(s.converged for s in result.steps)),
        "max_residual": float(result.column("residual").max()),
        "min_det_F": float(result.column("min_det").min()),
        "newton_iterations_total": int(iterations.sum()), "newton_iterations_max": int(iterations.max()),
        "increment_cuts": int(result.column("cuts").sum()),
        "wall_seconds": wall,
    }
    print(f"area: {built.rest_area:.3f} -> {final.area:.3f} (x{final.area_ratio:.2f})")
    print(f"tip deflection (mean y displacement of the right edge): {result.tip_deflection:+.4f}")
    print(f"peak chamber pressure |p|: {result.peak_pressure:.1f}")
    print(f"Newton: {summary['newton_iterations_total']} iterations over {len(iterations)} solves "
          f"(max {summary['newton_iterations_max']}, {summary['increment_cuts']} increment cuts), "
          f"all converged: {summary['all_converged']}; ramp {wall:.2f} s")
    written = save_history(out, stem, built, result) + [save_json(out / f"{stem}_summary.json", summary)]
    print("wrote " + ", ".join(str(p) for p in written))
    return summary


def save_history(out, stem: str, built, result) -> list:
    """Write the per-step history (CSV) and the states (npz) of a ramp, complete or partial."""
    mesh = built.mesh
    return [
        save_text(out / f"{stem}_history.csv", result.history_csv()),
        save_npz(out / f"{stem}_states.npz", positions=result.states, rest=mesh.vertices, triangles=mesh.triangles,
                 chamber_loop=mesh.chamber_loop, pinned=mesh.pinned, tip=mesh.tip,
                 target_area=result.column("target_area"), area=result.column("area"),
                 pressure=result.column("pressure")),
    ]


def main(argv: list[str] | None = None) -> int:
    args = parser().parse_args(argv)
    try:
        summary = run(args)
    except PneumaInputError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    return 0 if summary["all_converged"] else 1


if __name__ == "__main__":
    sys.exit(main())
