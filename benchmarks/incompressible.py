"""Near-incompressible rubber: the reference beam's tip deflection on P1 and P2 meshes refined uniformly, at Poisson
ratios from 0.45 to 0.4999, with the observed order of convergence (linear triangles lock, quadratic ones do not).

    python benchmarks/incompressible.py [--out benchmarks/results]     (writes bench_incompressible.md and .json)
"""

import sys
from pathlib import Path

import numpy as np

from taichi_pneuma.apps.bench import markdown

sys.path.insert(0, str(Path(__file__).resolve().parent))
from sections import main, timed_ramp  # noqa: E402

LOCKING_NU = (0.45, 0.49, 0.499, 0.4999)
LOCKING_BASE = {1: 0.005, 2: 0.02}


def incompressible() -> tuple[str, dict]:
    """Near incompressibility: the tip deflection of P1 (base max area 0.005) and P2 (base 0.02) meshes
    refined uniformly 0, 1, 2 times (10 increments to 3.5x), at nu = 0.45 ... 0.4999, with the observed
    order p = log2(|f0 - f1| / |f1 - f2|) and the change between the two finest levels."""
    rows, data = [], []
    for nu in LOCKING_NU:
        for order, max_area in LOCKING_BASE.items():
            runs = [
                timed_ramp(max_area=max_area, steps=11, order=order, refinements=level, nu=nu) for level in range(3)
            ]
            tips = [result.tip_deflection for _, result, _ in runs]
            nodes = [built.mesh.n_vertices for built, _, _ in runs]
            p = float(np.log2(abs(tips[0] - tips[1]) / abs(tips[1] - tips[2])))
            record = {
                "nu": nu,
                "order": order,
                "nodes": nodes,
                "tips": tips,
                "observed_order": p,
                "last_change": abs(tips[2] / tips[1] - 1),
                "seconds": [s for _, _, s in runs],
            }
            data.append(record)
            print(f"  incompressible: {record}", file=sys.stderr, flush=True)
            rows.append(
                [
                    nu,
                    f"P{order}",
                    " / ".join(f"{t:+.4f} ({n})" for t, n in zip(tips, nodes)),
                    f"{p:.2f}",
                    f"{100 * record['last_change']:.2f} %",
                ]
            )
    header = ["nu", "elements", "tip dy, levels 0 / 1 / 2 (nodes)", "observed order", "change level 1 -> 2"]
    return markdown(header, rows), {"runs": data}


if __name__ == "__main__":
    main("incompressible", __doc__, lambda out: incompressible())
