"""What surface contact costs: the IPC Toolkit (ipctk, what terms/surface_contact.py calls) against this project's
own Taichi kernels for the same barrier (terms/contact.py, 2D chamber walls), and a whole 3D ramp with and without
contact.

Sections:
- kernels_2d: pneunet_finger (2D, six chambers) deformed to its peak (900 Pa, the shipped ramp's step 10), then each
  contact term's energy, gradient, Hessian (exact) and step bound (along the displacement of the next increment,
  scaled to 10 % of it) timed on that state, median of REPEATS, the two terms alternated. The Taichi term
  ([effects.self_contact]) holds every point-edge pair of each chamber wall, a fixed list (O(k^2) per wall of k
  nodes); the ipctk term ([effects.surface_contact]) covers the body's whole surface (outer boundary and walls),
  finding its pairs by a bounding-volume hierarchy at every new state.
- ramp_3d: the shipped pneunet_3d (quadratic tetrahedra, 13.6k nodes) ramped as shipped (no two pieces of its
  surface come within dhat: contact never acts), with and without [effects.surface_contact], one ramp each in
  this process after compiling the kernels: Newton iterations, wall and Newton seconds, and their ratio (the
  contact issue's goal: at most 1.5x where no facets are near each other).

    python benchmarks/contact.py [--sections kernels_2d,ramp_3d] [--out benchmarks/results]

Writes contact.md and contact.json (machine, date) under --out.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time

import numpy as np

REPEATS = 20
DHAT = 0.008  # both terms': finger_curl's (1e-3 of its body's diagonal), at which its tip and base are in contact
STIFFNESS = {"self_contact": 1e4, "surface_contact": 1e4}  # the 2D term's default; finger_curl's
STATES_2D = {"pneunet_finger": 10, "finger_curl": 30}  # 900 Pa; the end, its base pressing on its tip
SECTIONS = ("kernels_2d", "ramp_3d")
CALLS = ("energy", "gradient", "hessian", "max_step")


def timed(term, dx: np.ndarray) -> dict:
    """Seconds of one call of each of the term's duties, in the solver's order, at its current state."""
    times = {}
    for call, duty in zip(CALLS, (term.energy, term.gradient, term.hessian_values, lambda: term.max_step(dx))):
        start = time.perf_counter()
        duty()
        times[call] = time.perf_counter() - start
    return times


def kernels_2d() -> dict:
    """Per scene of STATES_2D: the two terms timed at the state of the step given, along 10 % of the next
    increment's displacement."""
    import taichi_pneuma as tp

    records = {}
    for scene_name, step in STATES_2D.items():
        scene = tp.load_scene(scene_name)
        result = tp.simulate(scene)
        u, following = result.displacements[step], result.displacements[min(step + 1, len(result.steps) - 1)]
        terms = {}
        for name, effect in (("taichi", "self_contact"), ("ipctk", "surface_contact")):
            built = scene.with_values({"effects": {effect: {"dhat": DHAT, "stiffness": STIFFNESS[effect]}}}).build()
            terms[name] = next(t for t in built.model.terms if t.reports_contact)
        dx = 0.1 * (following - u)
        samples: dict = {name: {call: [] for call in CALLS} for name in terms}
        rng = np.random.default_rng(0)
        for repeat in range(REPEATS + 1):  # the first: compiling and warming
            state = u + 1e-9 * rng.standard_normal(u.shape)  # a new state each time (no term answers from a cache)
            for name, term in terms.items():
                term.config.u[:] = state
                for call, seconds in timed(term, dx).items():
                    if repeat:
                        samples[name][call].append(seconds)
        record: dict = {
            name: {call: statistics.median(values) for call, values in calls.items()} for name, calls in samples.items()
        }
        taichi, ipctk = terms["taichi"], terms["ipctk"]
        record["pairs"] = {"taichi": int(len(taichi.pairs)), "ipctk_active": ipctk.pairs()}
        record["surface_nodes"] = int(len(ipctk.surface))
        record["step"] = step
        records[scene_name] = record
    return records


def ramp_3d() -> dict:
    import taichi_pneuma as tp
    from taichi_pneuma.solve.simulate import run_schedule

    record = {}
    for name, overrides in (("without", {}), ("with", {"effects.surface_contact": {}})):
        built = tp.load_scene("pneunet_3d").with_values(overrides).build()
        model = built.model
        model.energy(), model.gradient(), model.hessian_parts(True), model.hessian_parts(False)  # compile
        start = time.perf_counter()
        run = run_schedule(built)
        seconds = time.perf_counter() - start
        record[name] = {
            "iterations": sum(step.iterations for step in run.steps),
            "ramp_s": seconds,
            "newton_s": float(sum(run.newton["phase_seconds"].values())),
            "tip": float(run.history["tip_dy"][10]),
        }
        print(f"ramp_3d {name}: {record[name]}", file=sys.stderr, flush=True)
    record["ratio"] = record["with"]["ramp_s"] / record["without"]["ramp_s"]
    return record


def report(records: dict, machine: str) -> str:
    from taichi_pneuma.apps.bench import markdown

    lines = [f"Machine: {machine}.", ""]
    if "kernels_2d" in records:
        lines += [
            "## The same barrier: ipctk against this project's Taichi kernels (2D)",
            "",
            "The Taichi term holds a fixed list of every point-edge pair of each chamber wall; ipctk covers the whole "
            f"surface and finds its pairs within dhat by a BVH at each new state. Median of {REPEATS} new states, "
            "each call in the solver's order (energy, gradient, Hessian at one state: ipctk builds its pairs at the "
            "first call and keeps them), in ms:",
            "",
        ]
        for scene_name, k in records["kernels_2d"].items():
            lines += [
                f"{scene_name} at step {k['step']}: Taichi {k['pairs']['taichi']} pairs; ipctk "
                f"{k['surface_nodes']} surface nodes, {k['pairs']['ipctk_active']} pairs within dhat.",
                "",
                markdown(
                    ["call", "Taichi (walls)", "ipctk (whole surface)"],
                    [[call, f"{1e3 * k['taichi'][call]:.3f}", f"{1e3 * k['ipctk'][call]:.3f}"] for call in CALLS],
                ),
                "",
            ]
    if "ramp_3d" in records:
        r = records["ramp_3d"]
        lines += [
            "## pneunet_3d as shipped, with and without surface contact",
            "",
            markdown(
                ["case", "Newton iterations", "ramp s", "Newton s", "tip dy at 900 Pa"],
                [
                    [
                        name,
                        r[name]["iterations"],
                        f"{r[name]['ramp_s']:.1f}",
                        f"{r[name]['newton_s']:.1f}",
                        f"{r[name]['tip']:.5f}",
                    ]
                    for name in ("without", "with")
                ],
            ),
            "",
            f"With contact / without: {r['ratio']:.2f}x.",
            "",
        ]
    return "\n".join(lines)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--sections", default=",".join(SECTIONS))
    p.add_argument("--out", default="benchmarks/results")
    args = p.parse_args()
    from taichi_pneuma import runtime
    from taichi_pneuma.apps.bench import machine
    from taichi_pneuma.io.output import prepare_directory, save_json, save_text

    runtime.ensure_initialised()
    out = prepare_directory(args.out)
    records = {section: globals()[section]() for section in args.sections.split(",")}
    save_json(out / "contact.json", {"machine": machine(), "records": records})
    save_text(out / "contact.md", report(records, machine()))
    print(report(records, machine()))


if __name__ == "__main__":
    main()
