"""What accuracy costs in 2D: the reference beam's tip error against wall time for linear and quadratic triangles at
several mesh densities (against a converged P2 reference), and for the Newton tolerance and the number of
increments; the error against time plotted log-log.

    python benchmarks/accuracy.py [--out benchmarks/results]     (writes bench_accuracy.md, .json and .png)
"""

import collections
import sys
from pathlib import Path

import numpy as np

from taichi_pneuma.apps.bench import markdown
from taichi_pneuma.io.output import write_atomic

sys.path.insert(0, str(Path(__file__).resolve().parent))
from sections import main, timed_ramp  # noqa: E402

MESHES = {1: (0.005, 0.0025, 0.0012, 0.0006, 0.0003, 0.00015), 2: (0.02, 0.01, 0.005, 0.0025, 0.0012)}
STUDY_NU = (0.45, 0.499)


def converged_tip(poisson_ratio: float, levels: int = 3) -> dict:
    """The reference: P2 on the reference mesh (max area 0.0012) refined uniformly 0 .. levels-1 times, with
    10 increments (the area-controlled equilibrium does not depend on the path: see the knobs below).
    Returns the tips per level, the observed order p = log2(|f0 - f1| / |f1 - f2|) and the finest tip."""
    tips, nodes = [], []
    for level in range(levels):
        built, result, _ = timed_ramp(steps=11, order=2, refinements=level, nu=poisson_ratio)
        tips.append(result.tip_deflection)
        nodes.append(built.mesh.n_vertices)
        print(
            f"  reference nu={poisson_ratio}: level {level}, {nodes[-1]} nodes, tip {tips[-1]:+.6f}",
            file=sys.stderr,
            flush=True,
        )
    order = float(np.log2(abs(tips[0] - tips[1]) / abs(tips[1] - tips[2])))
    return {
        "tips": tips,
        "nodes": nodes,
        "observed_order": order,
        "tip": tips[-1],
        "remaining_error_estimate": abs(tips[2] - tips[1]) / (2**order - 1) / abs(tips[-1]),
    }


def accuracy(out: Path) -> tuple[str, dict]:
    """What accuracy costs: linear (P1) and quadratic (P2) triangles at several mesh densities, nu = 0.45
    and 0.499, error of the tip deflection against a converged P2 reference (converged_tip) and wall time
    of the 35-increment ramp; then the Newton tolerance and the number of increments on the default P1
    mesh, against the same mesh solved tightly (tol 1e-9, 100 increments). Plots error against time."""
    from taichi_pneuma.solve.newton import NewtonOptions

    rows, data = [], {"elements": collections.defaultdict(list), "references": {}}
    for nu in STUDY_NU:
        reference = converged_tip(nu)
        data["references"][nu] = reference
        for order, areas in MESHES.items():
            for max_area in areas:
                built, result, seconds = timed_ramp(max_area=max_area, order=order, nu=nu)
                error = abs(result.tip_deflection / reference["tip"] - 1)
                data["elements"][f"P{order}, nu = {nu}"].append(
                    {"value": max_area, "nodes": built.mesh.n_vertices, "seconds": seconds, "tip": error}
                )
                rows.append(
                    [
                        f"P{order}, nu = {nu}",
                        f"{max_area:g}",
                        built.mesh.n_vertices,
                        f"{1e3 * seconds:.0f}",
                        f"{result.tip_deflection:+.5f}",
                        f"{100 * error:.2f} %",
                    ]
                )
    table = markdown(["elements", "max area", "nodes", "ramp (ms)", "tip dy", "tip error"], rows)
    table += "\n" + markdown(
        ["nu", "P2 reference tips, levels 0 / 1 / 2 (nodes)", "observed order", "estimated error of the finest"],
        [
            [
                nu,
                " / ".join(f"{t:+.5f} ({n})" for t, n in zip(r["tips"], r["nodes"])),
                f"{r['observed_order']:.2f}",
                f"{100 * r['remaining_error_estimate']:.3f} %",
            ]
            for nu, r in data["references"].items()
        ],
    )
    knobs = {
        "Newton tolerance": [(t, dict(options=NewtonOptions(tol=t))) for t in (1e-2, 1e-4, 1e-6, 1e-9)],
        "ramp increments": [(n, dict(steps=n + 1)) for n in (5, 10, 35, 100)],
    }
    tight = timed_ramp(steps=101, options=NewtonOptions(tol=1e-9))[1].tip_deflection
    rows = []
    for knob, runs in knobs.items():
        for value, kwargs in runs:
            _, result, seconds = timed_ramp(**kwargs)
            rows.append([knob, f"{value:g}", f"{1e3 * seconds:.0f}", f"{abs(result.tip_deflection / tight - 1):.1e}"])
    table += "\n" + markdown(["knob (P1, max area 0.0012)", "value", "ramp (ms)", "tip error vs tight solve"], rows)
    plot_accuracy(data["elements"], out / "bench_accuracy.png")
    return table, {"elements": dict(data["elements"]), "references": data["references"]}


def plot_accuracy(data: dict, path: Path) -> None:
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        import matplotlib.ticker
    except ImportError:
        print("matplotlib is not installed (pip install .[bench]): no accuracy plot", file=sys.stderr)
        return
    fig, ax = plt.subplots(figsize=(6.4, 4.2), dpi=100)
    for knob, runs in data.items():
        times, errors = [r["seconds"] for r in runs], [max(r["tip"], 1e-12) for r in runs]
        ax.loglog(times, errors, "o-" if knob.startswith("P2") else "s--", label=knob)  # points labelled by max area
        for r, t, e in zip(runs, times, errors):
            ax.annotate(f"{r['value']:g}", (t, e), textcoords="offset points", xytext=(4, 3), fontsize=7)
    ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
    ax.axhline(0.01, color="grey", lw=0.8, ls="--")
    ax.set_xlabel("wall time of the 35-increment ramp (s)")
    ax.set_ylabel("relative tip-deflection error")
    ax.set_title("Tip error versus time: linear and quadratic triangles (cy = +0.15, CPU)")
    ax.legend()
    fig.tight_layout()
    write_atomic(path, lambda tmp: fig.savefig(tmp, format="png"))
    plt.close(fig)


if __name__ == "__main__":
    main("accuracy", __doc__, accuracy)
