"""What the benchmark scripts that were sections of pneuma-bench share: the reference ramp timed once its kernels
are warm (timed_ramp), and the command line that runs a section and writes its table as pneuma-bench writes its
own (bench_<section>.md and .json under --out, headed with the machine, the kernels' compiler and the arch).

    python benchmarks/accuracy.py [--out benchmarks/results] [--arch cpu]     (accuracy, incompressible, scaling,
                                                                               backends, solid, compilers)
"""

import argparse
import time

from taichi_pneuma import runtime
from taichi_pneuma.apps.bench import save_section, warm_up
from taichi_pneuma.io.output import prepare_directory


def timed_ramp(max_area=0.0012, steps=36, growth=3.5, options=None, cy=0.15, **scene):
    """Build, warm the kernels up on a tiny ramp, then time the ramp; return (built, result, seconds).
    scene: further reference_scene arguments (order, refinements, nu)."""
    from taichi_pneuma.scene.build import reference_scene
    from taichi_pneuma.solve.simulate import run_schedule

    built = reference_scene(cy, growth=growth, steps=steps, max_area=max_area, **scene).build()
    warm_up(built, options)
    start = time.perf_counter()
    result = run_schedule(built, options=options)
    return built, result, time.perf_counter() - start


def main(section: str, doc: str, measure) -> None:
    """The command line of a section's script (doc: its module docstring): Taichi initialised on --arch, then
    measure(out) -> (Markdown table, data) printed and saved as bench_<section>.md and .json under --out."""
    parser = argparse.ArgumentParser(description=doc.split("\n")[0])
    parser.add_argument("--out", default="benchmarks/results", help="directory for the table, JSON (and plot)")
    parser.add_argument("--arch", default="cpu", choices=sorted(runtime.ARCHES), help="Taichi backend")
    args = parser.parse_args()
    out = prepare_directory(args.out)
    runtime.init(args.arch)
    print(f"## {section}", flush=True)
    table, data = measure(out)
    save_section(out, section, table, data, args.arch)
