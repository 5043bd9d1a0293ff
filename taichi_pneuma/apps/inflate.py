"""Run a scene's schedule (a scene file, or the reference beam by its flags) and report how it bends.

    python -m taichi_pneuma.apps.inflate --cy 0.15
    python -m taichi_pneuma.apps.inflate --scene assets/scenes/bidirectional.toml

Prints the mesh size, the terms built, each chamber's rest area, final area ratio and pressure,
the tip deflection and rotation and the peak chamber pressure; writes the per-step history (CSV),
the states (npz) and a summary (JSON) under --out.
"""

from __future__ import annotations

import argparse
import sys
import time

import numpy as np

from .. import runtime
from ..errors import PneumaInputError, require, require_finite
from ..newton import NewtonOptions
from ..output import prepare_directory, save_json, save_npz, save_text
from ..scene import reference_scene
from ..scenefile import load_scene
from ..simulate import MAX_CUTS, RampFailed, run_schedule


def parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="python -m taichi_pneuma.apps.inflate", description=__doc__.split("\n")[0],
                                formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    p.add_argument("--scene", help="a scene file (TOML); the reference-beam flags below are then ignored, except "
                                   "--tol, --max-cuts, --out, --arch, --quiet")
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
    if args.scene:
        scene = load_scene(args.scene)
        stem = scene.name
    else:
        scene = reference_scene(args.cy, args.cx, args.growth, args.steps, args.E, args.nu, args.k, args.max_area)
        stem = f"inflate_cy{args.cy:+.2f}"
    out = prepare_directory(args.out)
    runtime.init(args.arch)
    built = scene.build()
    mesh = built.mesh
    print(f"scene {scene.name}: mesh {mesh.n_vertices} vertices, {mesh.n_triangles} triangles; "
          f"clamp {len(mesh.pinned)} vertices; terms: {', '.join(built.model.term_names())}")
    for chamber in built.chambers:
        print(f"chamber {chamber.chamber_name}: {chamber.control} control, wall {chamber.n_wall} vertices, "
              f"rest area {chamber.rest_area:.3f}")

    def progress(step):
        if not args.quiet:
            chambers = "  ".join(f"{name}: x{c.area_ratio:5.3f} p = {c.pressure:8.2f}" for name, c in step.chambers.items())
            print(f"  step {step.step:3d}/{scene.increments}  {chambers}  tip dy = {step.tip_dy:+.4f} "
                  f"rot = {step.tip_rotation:+6.1f} deg  {step.iterations:2d} Newton it  residual {step.residual:.1e}",
                  flush=True)

    start = time.perf_counter()
    try:
        result = run_schedule(built, options=options, progress=progress, max_cuts=args.max_cuts)
    except RampFailed as failure:
        written = save_history(out, stem, built, failure.partial)
        print(f"error: {failure}; the {len(failure.partial.steps)} converged steps are saved in "
              + ", ".join(str(p) for p in written), file=sys.stderr)
        return {"all_converged": False}
    wall = time.perf_counter() - start
    final = result.steps[-1]
    iterations = result.column("iterations")[1:]
    summary = {
        "scene": scene.name, "terms": built.model.term_names(),
        "vertices": mesh.n_vertices, "triangles": mesh.n_triangles,
        "chambers": {name: {"control": c.control, "rest_area": c.area / c.area_ratio, "final_area": c.area,
                            "area_ratio": c.area_ratio, "final_pressure": c.pressure,
                            "peak_pressure": float(np.abs(result.column(f"{name}.pressure")).max())}
                     for name, c in final.chambers.items()},
        "tip_deflection": result.tip_deflection, "tip_rotation_deg": final.tip_rotation,
        "peak_pressure": result.peak_pressure, "contact": final.contact,
        "all_converged": bool(all(s.converged for s in result.steps)),
        "max_residual": float(result.column("residual").max()),
        "min_det_F": float(result.column("min_det").min()),
        "newton_iterations_total": int(iterations.sum()), "newton_iterations_max": int(iterations.max(initial=0)),
        "increment_cuts": int(result.column("cuts").sum()),
        "wall_seconds": wall,
    }
    for name, c in final.chambers.items():
        print(f"{name}: area {c.area / c.area_ratio:.3f} -> {c.area:.3f} (x{c.area_ratio:.2f}), pressure {c.pressure:.1f}")
    print(f"tip deflection (mean y displacement of the right edge): {result.tip_deflection:+.4f}; "
          f"tip rotation {final.tip_rotation:+.1f} deg")
    print(f"peak chamber pressure |p|: {result.peak_pressure:.1f}")
    for name, (fx, fy, magnitude) in final.contact.items():
        print(f"{name} contact force on the body: ({fx:+.4g}, {fy:+.4g})")
    print(f"Newton: {summary['newton_iterations_total']} iterations over {len(iterations)} solves "
          f"(max {summary['newton_iterations_max']}, {summary['increment_cuts']} increment cuts), "
          f"all converged: {summary['all_converged']}; run {wall:.2f} s")
    written = save_history(out, stem, built, result) + [save_json(out / f"{stem}_summary.json", summary)]
    print("wrote " + ", ".join(str(p) for p in written))
    return summary


def save_history(out, stem: str, built, result) -> list:
    """Write the per-step history (CSV) and the states (npz) of a run, complete or partial.

    The npz holds positions (steps, n, 2), rest, triangles, pinned, tip, boundary, chamber_names and
    one chamber_loop_<i> per chamber, command / area / pressure as (steps, chambers), and, where
    the scene has them, contact_forces (steps, n, 2) and ground_height.
    """
    mesh = built.mesh
    names = [c.chamber_name for c in built.chambers]
    arrays = dict(positions=result.states, rest=mesh.vertices, triangles=mesh.triangles, pinned=mesh.pinned,
                  tip=mesh.tip, boundary=mesh.boundary, chamber_names=np.array(names),
                  **{f"chamber_loop_{i}": loop for i, loop in enumerate(mesh.chambers)},
                  **{key: np.column_stack([result.column(f"{n}.{key}") for n in names])
                     for key in ("command", "area", "pressure")})
    if result.contact_forces is not None:
        arrays["contact_forces"] = result.contact_forces
    for effect in built.scene.effects:
        if effect.name == "ground":
            arrays["ground_height"] = np.array(effect.height)
    return [
        save_text(out / f"{stem}_history.csv", result.history_csv()),
        save_npz(out / f"{stem}_states.npz", **arrays),
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
