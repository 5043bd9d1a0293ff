"""An optimisation's pictures (matplotlib Figures, no pyplot): the trace (each evaluation's objective and the best
feasible so far against the evaluation) and, for two objectives, the evaluations in the objectives' plane with the
Pareto front (the feasible evaluations no other feasible one dominates) drawn through.
"""

from __future__ import annotations

import numpy as np


def dominates(a: list[float], b: list[float], signs: list[float]) -> bool:
    """a is at least as good as b in every objective and better in one (signs: +1 minimise, -1 maximise)."""
    better = [s * x <= s * y for x, y, s in zip(a, b, signs)]
    strictly = [s * x < s * y for x, y, s in zip(a, b, signs)]
    return all(better) and any(strictly)


def objectives(row: dict, n: int) -> list[float]:
    return [row[f"objective_{i}"] for i in range(n)]


def pareto_front(rows: list[dict], directions: list[str]) -> list[dict]:
    """The rows no other row dominates, by the first objective."""
    signs = [1.0 if d == "minimize" else -1.0 for d in directions]
    n = len(directions)
    front = [r for r in rows if not any(dominates(objectives(o, n), objectives(r, n), signs) for o in rows)]
    return sorted(front, key=lambda r: r["objective_0"])


def trace_figure(rows: list[dict], labels: list[str], directions: list[str]):
    """Each objective against the evaluation (infeasible ones hollow, failed ones as ticks at the bottom) and, for
    one objective, the best feasible so far as a step line."""
    from matplotlib.figure import Figure

    figure = Figure(figsize=(6.5, 3.2 * len(labels)), layout="constrained")
    axes = np.atleast_1d(figure.subplots(len(labels), 1, sharex=True))
    order = np.arange(1, len(rows) + 1)
    for i, (ax, label, direction) in enumerate(zip(axes, labels, directions)):
        key = f"objective_{i}"
        done = [(n, r) for n, r in zip(order, rows) if r.get(key) is not None]
        feasible = [(n, r[key]) for n, r in done if r["feasible"]]
        other = [(n, r[key]) for n, r in done if not r["feasible"]]
        if feasible:
            ax.plot(*zip(*feasible), "o", ms=4, color="C0", label="feasible")
        if other:
            ax.plot(*zip(*other), "o", ms=4, mfc="none", color="C3", label="violates a constraint")
        if len(labels) == 1 and feasible:
            pick = np.minimum if direction == "minimize" else np.maximum
            best, line = None, []
            for r in rows:
                if r["feasible"]:
                    best = r[key] if best is None else float(pick(best, r[key]))
                line.append(np.nan if best is None else best)
            ax.step(order, line, where="post", color="k", lw=1.5, label="best so far")
        failed = [n for n, r in zip(order, rows) if r.get("error") is not None]
        if failed:
            ax.plot(failed, np.zeros(len(failed)), "|", color="0.5", transform=ax.get_xaxis_transform(), ms=12)
        ax.set_title(f"{direction} {label}", fontsize=9)
        ax.legend(fontsize=8)
    axes[-1].set(xlabel="evaluation")
    failed_count = sum(r.get("error") is not None for r in rows)
    figure.suptitle(f"{len(rows)} evaluations" + (f", {failed_count} failed (ticks)" if failed_count else ""))
    return figure


def pareto_figure(rows: list[dict], labels: list[str], directions: list[str]):
    """The evaluations in the plane of the two objectives, the Pareto front of the feasible ones joined."""
    from matplotlib.figure import Figure

    figure = Figure(figsize=(6.0, 4.8), layout="constrained")
    ax = figure.add_subplot()
    done = [r for r in rows if r.get("objective_1") is not None]
    for feasible, colour, face in ((True, "C0", "C0"), (False, "C3", "none")):
        points = [objectives(r, 2) for r in done if r["feasible"] is feasible]
        if points:
            label = "feasible" if feasible else "violates a constraint"
            ax.plot(*zip(*points), "o", ms=4, color=colour, mfc=face, label=label)
    front = pareto_front([r for r in done if r["feasible"]], directions)
    if front:
        ax.plot(*zip(*[objectives(r, 2) for r in front]), "-s", color="k", ms=5, label="Pareto front")
    ax.set_xlabel(f"{labels[0]} ({directions[0]})", fontsize=8)
    ax.set_ylabel(f"{labels[1]} ({directions[1]})", fontsize=8)
    ax.legend(fontsize=8)
    return figure
