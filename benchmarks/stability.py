"""The hard cases of tests/test_hard_cases.py as a table: what the solver did with each.

    python benchmarks/stability.py [--out benchmarks/results]

Prints a Markdown table (converged / Newton iterations / increment cuts / tip deflection /
area error / wall time) and writes it with the machine and date to stability.md and stability.json.
"""

import argparse
import platform
import time
from datetime import date
from pathlib import Path

from taichi_pneuma import runtime
from taichi_pneuma.io.output import prepare_directory, save_json, save_text
from taichi_pneuma.scene.build import reference_scene
from taichi_pneuma.solve.simulate import RampFailed, run_schedule

CASES = [
    ("reference ramp (3.5x, 35 increments)", {}, {}),
    ("growth 6x (60 increments)", {}, dict(growth=6.0, steps=61)),
    ("growth 8x (80 increments)", {}, dict(growth=8.0, steps=81)),
    ("nu = 0.49", dict(nu=0.49), {}),
    ("nu = 0.499", dict(nu=0.499), {}),
    ("thin wall (chamber 0.01 below the top)", dict(cy=0.17), {}),
    ("single increment 1x -> 3.5x", {}, dict(steps=2)),
    ("chamber k = 1e8", dict(k=1e8), {}),
    ("chamber k = 1e3", dict(k=1e3), {}),
    ("coarse mesh (max area 0.01)", dict(max_area=0.01), {}),
    ("fine mesh (max area 0.0002)", dict(max_area=0.0002), {}),
    ("stiff material E = 1e7", dict(E=1e7), {}),
    ("deflation to 0.5x (no self-contact)", {}, dict(growth=0.5, steps=11)),
]


def run_case(cy=0.15, nu=0.45, k=1e5, E=1e4, max_area=0.0012, growth=3.5, steps=36) -> dict:
    built = reference_scene(
        cy, growth=growth, steps=steps, youngs_modulus=E, poisson_ratio=nu, chamber_stiffness=k, max_area=max_area
    ).build()
    start = time.perf_counter()
    try:
        result = run_schedule(built)
    except RampFailed as failure:
        return {"outcome": f"refused: {failure}", "seconds": time.perf_counter() - start}
    final = result.steps[-1].chambers["main"]
    iterations = result.history["iterations"][1:]
    return {
        "outcome": "converged" if all(s.converged for s in result.steps) else "not converged",
        "vertices": built.mesh.n_vertices,
        "iterations_mean": float(iterations.mean()),
        "iterations_max": int(iterations.max()),
        "cuts": int(result.history["cuts"].sum()),
        "tip_deflection": result.tip_deflection,
        "area_ratio": final.area_ratio,
        "area_error": final.area_ratio / final.command - 1,
        "peak_pressure": result.peak_pressure,
        "min_det_F": float(result.history["min_det"].min()),
        "seconds": time.perf_counter() - start,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--out", default="benchmarks/results")
    out = prepare_directory(parser.parse_args().out)
    runtime.init("cpu")
    header = (
        "| case | outcome | Newton it. per increment (mean / max) | cuts | tip dy | A/A* - 1 | peak abs(p) "
        "| min det F | s |\n|---|---|---|---|---|---|---|---|---|"
    )
    rows, records = [], {}
    for name, scene_args, ramp_args in CASES:
        r = records[name] = run_case(**scene_args, **ramp_args)
        if r["outcome"] == "converged":
            rows.append(
                f"| {name} | converged | {r['iterations_mean']:.1f} / {r['iterations_max']} | {r['cuts']} "
                f"| {r['tip_deflection']:+.4f} | {r['area_error']:+.1e} | {r['peak_pressure']:.4g} "
                f"| {r['min_det_F']:.3f} | {r['seconds']:.1f} |"
            )
        else:
            rows.append(f"| {name} | {r['outcome']} | | | | | | | {r['seconds']:.1f} |")
        print(rows[-1], flush=True)
    machine = f"{platform.node()} ({platform.machine()}, {platform.processor() or 'cpu'}), {date.today()}"
    table = f"Machine: {machine}\n\n{header}\n" + "\n".join(rows) + "\n"
    print(table)
    save_text(Path(out) / "stability.md", table)
    save_json(Path(out) / "stability.json", {"machine": machine, "cases": records})


if __name__ == "__main__":
    main()
