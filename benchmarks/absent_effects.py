"""Absent effects cost nothing: time the reference ramp and list the terms it builds.

    python -m benchmarks.absent_effects [--repeat 3]      (from the repository root)

Run it on two commits (before and after the effects existed) on the same machine and compare the
per-iteration times; the reference scene builds elastic + chamber + clamp only, so no kernel of
gravity, ground or self-contact is compiled or launched.
"""

import argparse
import time

from taichi_pneuma import runtime
from taichi_pneuma.scene.build import reference_scene
from taichi_pneuma.solve.simulate import run_schedule


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    runtime.init("cpu")
    built = reference_scene(cy=0.15).build()
    print("terms:", ", ".join(built.model.term_names()))
    run_schedule(built)  # compile every kernel once
    for _ in range(args.repeat):
        start = time.perf_counter()
        result = run_schedule(built)
        wall = time.perf_counter() - start
        iterations = int(result.history["iterations"].sum())
        print(
            f"reference ramp: {wall:.2f} s, {iterations} Newton iterations, "
            f"{1e3 * wall / iterations:.1f} ms/iteration, tip {result.tip_deflection:+.4f}"
        )


if __name__ == "__main__":
    main()
