"""Scaling with the mesh size: time per Newton iteration and per increment of the reference beam from about 500 to
about 100k vertices, and the fitted exponent of time per iteration against the vertices.

    python benchmarks/scaling.py [--out benchmarks/results]     (writes bench_scaling.md and .json)
"""

import resource
import sys
from pathlib import Path

import numpy as np

from taichi_pneuma.apps.bench import markdown

sys.path.insert(0, str(Path(__file__).resolve().parent))
from sections import main, timed_ramp  # noqa: E402


def scaling() -> tuple[str, dict]:
    """Time per Newton iteration and per increment from ~500 to ~100k vertices (3 increments to 1.5x)."""
    rows, data = [], []
    for max_area in (0.005, 0.0012, 0.0003, 0.0001, 0.00003, 0.00002):
        built, result, seconds = timed_ramp(max_area=max_area, steps=4, growth=1.5)
        iterations = int(result.history["iterations"].sum())
        record = {
            "vertices": built.mesh.n_vertices,
            "ms_per_iteration": 1e3 * seconds / iterations,
            "ms_per_increment": 1e3 * seconds / 3,
            "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
        }
        data.append(record)
        rows.append(
            [
                record["vertices"],
                f"{record['ms_per_iteration']:.1f}",
                f"{record['ms_per_increment']:.0f}",
                f"{record['peak_rss_mb']:.0f}",
            ]
        )
        print(f"  scaling: {record}", file=sys.stderr, flush=True)
    n = np.log([r["vertices"] for r in data])
    exponent = np.polyfit(n, np.log([r["ms_per_iteration"] for r in data]), 1)[0]
    table = markdown(["vertices", "ms / Newton iteration", "ms / increment", "peak RSS (MB)"], rows)
    return table + f"\nfitted: time per iteration ~ vertices^{exponent:.2f}\n", {"runs": data, "exponent": exponent}


if __name__ == "__main__":
    main("scaling", __doc__, lambda out: scaling())
