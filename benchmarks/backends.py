"""Linear-solver backends on the reference ramp: each backend factorising and solving the same matrix (the projected
Hessian at the reference's final state, 20 times each), then each running the whole ramp.

    python benchmarks/backends.py [--out benchmarks/results]     (writes bench_backends.md and .json)
"""

import sys
import time
from pathlib import Path

import numpy as np

from taichi_pneuma.apps.bench import markdown

sys.path.insert(0, str(Path(__file__).resolve().parent))
from sections import main, timed_ramp  # noqa: E402


def backends() -> tuple[str, dict]:
    """Each backend on the same matrices (the final reference state), then each on the whole ramp."""
    from taichi_pneuma.solve.linsolve import BACKENDS, FixedPattern, make_backend
    from taichi_pneuma.solve.newton import NewtonOptions

    built, result, _ = timed_ramp()
    model = built.model
    model.set_displacements(result.positions[-1] - built.mesh.vertices)
    rows_, cols_ = model.hessian_pattern()
    matrix = FixedPattern(rows_, cols_, model.n_dofs).matrix(model.hessian_values(psd_only=True))
    rhs = np.random.default_rng(0).standard_normal(model.n_dofs)
    rows, data = [], {}
    for name in BACKENDS:
        backend = make_backend(name)
        backend.factorize(matrix)
        start = time.perf_counter()
        for _ in range(20):
            backend.factorize(matrix)
        factorize = (time.perf_counter() - start) / 20
        start = time.perf_counter()
        for _ in range(20):
            backend.solve(rhs)
        solve = (time.perf_counter() - start) / 20
        _, ramp, seconds = timed_ramp(options=NewtonOptions(linear_solver=name))
        data[name] = {
            "factorize_ms": 1e3 * factorize,
            "solve_ms": 1e3 * solve,
            "ramp_s": seconds,
            "tip_deflection": ramp.tip_deflection,
        }
        rows.append(
            [name, f"{1e3 * factorize:.2f}", f"{1e3 * solve:.3f}", f"{seconds:.2f}", f"{ramp.tip_deflection:+.5f}"]
        )
    header = ["backend", "factorise (ms)", "solve (ms)", "reference ramp (s)", "tip dy"]
    return f"matrix: {matrix.shape[0]} DOFs, {matrix.nnz} non-zeros\n\n" + markdown(header, rows), data


if __name__ == "__main__":
    main("backends", __doc__, lambda out: backends())
