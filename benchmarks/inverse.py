"""Inverse control, measured: finite-difference errors of the sensitivities, and twin reaches.

    python benchmarks/inverse.py [--reaches 5]

1. For each scene of tests/test_sensitivity.py, the largest relative error of the tip Jacobian
   (dx, dy, rotation) and of du/dq against central differences of full re-solves (the test's steps).
2. For each shipped multi-purpose scene at its own mesh (reference_beam.toml: the reference mesh,
   1632 vertices), `--reaches` twin targets: commands drawn at random inside the bounds, solved
   forward, the tip they produce reached by a fresh Reacher (which starts at the box centre, solved
   once, not counted) with the default tolerance (1e-3 of the body length). Prints forward solves,
   Newton iterations and seconds per reach, and the tip errors.
"""

import argparse
import sys
from pathlib import Path

import numpy as np

from taichi_pneuma import runtime
from taichi_pneuma.control.inverse import Reacher, body_length
from taichi_pneuma.scene.scenefile import load_scene
from taichi_pneuma.scene.targets import Target

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tests"))
from test_sensitivity import CASES, errors_against_finite_differences  # noqa: E402


def fd_errors() -> None:
    print("| scene | vertices | chambers | tip dx | tip dy | tip rotation | du/dq (moving DOFs) |")
    print("|---|---|---|---|---|---|---|")
    for name, (_, commands) in CASES.items():
        tip, du, built, _, _ = errors_against_finite_differences(name)
        print(
            f"| {name} | {built.mesh.n_vertices} | {len(commands)} | {tip[0]:.1e} | {tip[1]:.1e} | {tip[2]:.1e} "
            f"| {du:.1e} |"
        )


def twin_reaches(count: int) -> None:
    print(
        "| scene | vertices | reached | forward solves / reach | Newton it. / reach | s / reach | worst tip error / L |"
    )
    print("|---|---|---|---|---|---|---|")
    rng = np.random.default_rng(0)
    for name in ("reference_beam", "bidirectional", "pneunet_finger"):
        built = load_scene(ROOT / "taichi_pneuma" / "scenes" / f"{name}.toml").build()
        probe = Reacher(built)
        results = []
        for _ in range(count):
            commands = probe.lo + rng.uniform(0.05, 0.95, len(probe.lo)) * (probe.hi - probe.lo)
            target = Target(tuple(probe.settle(commands).tip))
            results.append(Reacher(built).reach(target))
        length = body_length(built)
        print(
            f"| {name} | {built.mesh.n_vertices} | {sum(r.reached for r in results)}/{count} "
            f"| {np.mean([r.forward_solves for r in results]):.1f} "
            f"| {np.mean([r.newton_iterations for r in results]):.1f} | {np.mean([r.seconds for r in results]):.3f} "
            f"| {max(r.error for r in results) / length:.1e} |"
        )


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--reaches", type=int, default=5, help="twin targets per scene")
    args = p.parse_args()
    runtime.init("cpu")
    fd_errors()
    print()
    twin_reaches(args.reaches)


if __name__ == "__main__":
    main()
