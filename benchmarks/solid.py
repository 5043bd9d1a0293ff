"""3D: the cost of a Newton iteration on tetrahedra, on the pressurised octant of a thick spherical shell (layered
tetrahedra from arrays, no mesher) of growing size: time per iteration and its phases for each linear solver, and
the projected elastic Hessian with the analytic eigensystem against the Jacobi one. octant() and Meshed are the
3D bodies benchmarks/scale_3d.py and render3d.py time too.

    python benchmarks/solid.py [--out benchmarks/results]     (writes bench_solid.md and .json)
"""

import collections
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from taichi_pneuma.apps.bench import PHASES, markdown
from taichi_pneuma.scene.build import Scene

sys.path.insert(0, str(Path(__file__).resolve().parent))
from sections import main  # noqa: E402


def phase_ms(result) -> tuple[int, dict[str, float]]:
    """(the Newton iterations of a run, each phase's ms per iteration)."""
    phases = collections.Counter()
    for solve in result.solves:
        phases.update(solve.phase_seconds)
    iterations = int(result.history["iterations"].sum())
    return iterations, {p: 1e3 * phases[p] / iterations for p in PHASES}


@dataclass(frozen=True)
class Meshed:
    """A scene geometry already meshed (a tetrahedral Mesh and its one chamber), for timing 3D solves."""

    ready: object
    chambers: tuple = (("cavity", None),)

    def mesh(self, budget):
        return self.ready  # made already, in no budget


def octant(divisions: int, layers: int, order: int, increments: int = 3) -> Scene:
    """A pressurised octant of the thick spherical shell 1 <= r <= 2 (layered.py: 3 divisions^2 layers
    tetrahedra), closed by its three symmetry planes; pressure 0 -> 0.05 E in `increments` increments."""
    from taichi_pneuma.fem.layered import spherical_shell_octant
    from taichi_pneuma.fem.supports import Roller
    from taichi_pneuma.fem.tetmesh import tet_mesh
    from taichi_pneuma.scene.build import ChamberControl, Material, Scene
    from taichi_pneuma.scene.schedule import ChamberSchedule

    vertices, tets, wall = spherical_shell_octant(1.0, 2.0, divisions, layers)
    mesh = tet_mesh(
        vertices,
        tets,
        {"cavity": wall},
        order=order,
        clamp=None,
        rollers=tuple(Roller(tuple(n), (0.0, 0.0, 0.0)) for n in np.eye(3)),
    )
    return Scene(
        Meshed(mesh),
        (ChamberControl(ChamberSchedule("pressure", ((increments, 500.0),))),),
        increments,
        Material(1e4, 0.45),
    )


SOLID_MESHES = (("P1", 8, 4, 1), ("P1", 16, 6, 1), ("P1", 24, 12, 1), ("P2", 12, 6, 2))
SOLID_BACKENDS = ("taichi", "cholespy", "cholmod", "amg")


def solid() -> tuple[str, dict]:
    """3D: time per Newton iteration and its parts (the linear solve's share) on octants of growing size, linear
    and quadratic tetrahedra, Taichi's LLT, CHOLMOD and CG with multigrid (where auto's switch to it comes from);
    the elastic Hessian with the analytic eigensystem against the Jacobi one."""
    from taichi_pneuma.materials import StableNeoHookean
    from taichi_pneuma.scene.schedule import ChamberSchedule, Schedule
    from taichi_pneuma.solve.newton import NewtonOptions
    from taichi_pneuma.solve.simulate import run_schedule
    from taichi_pneuma.terms import Elasticity

    class JacobiNeoHookean(StableNeoHookean):
        """Stable neo-Hookean without its analytic eigensystem: the generic Jacobi path (timing only)."""

        analytic_dims = ()

    rows, data = [], []
    for label, divisions, layers, order in SOLID_MESHES:
        built = octant(divisions, layers, order).build()
        mesh = built.mesh
        for backend in SOLID_BACKENDS:
            options = NewtonOptions(linear_solver=backend)
            run_schedule(built, Schedule(1, (ChamberSchedule("pressure", ((1, 5.0),)),)), options)  # compile, analyse
            start = time.perf_counter()
            result = run_schedule(built, options=options)
            seconds = time.perf_counter() - start
            iterations, per = phase_ms(result)
            linear = per["factorize"] + per["solve"]
            record = {
                "elements": f"{label} tetrahedra",
                "tetrahedra": mesh.n_elements,
                "dofs": 3 * mesh.n_vertices,
                "backend": backend,
                "iterations": iterations,
                "ms_per_iteration": 1e3 * seconds / iterations,
                "phases_ms": per,
                "linear_solve_share": linear / (1e3 * seconds / iterations),
                "tip": float(result.positions[-1][:, 0].max()),
            }
            data.append(record)
            rows.append(
                [
                    f"{label}, {mesh.n_elements}",
                    3 * mesh.n_vertices,
                    backend,
                    iterations,
                    f"{record['ms_per_iteration']:.0f}",
                    *(f"{per[p]:.1f}" for p in PHASES),
                    f"{100 * record['linear_solve_share']:.0f} %",
                    f"{record['tip']:.6f}",
                ]
            )
            print(f"  solid: {record}", file=sys.stderr, flush=True)
    table = markdown(
        [
            "tetrahedra",
            "DOFs",
            "backend",
            "iterations",
            "ms / iteration",
            *(f"{p} (ms)" for p in PHASES),
            "linear solve share",
            "max x (pole)",
        ],
        rows,
    )
    eigen_rows = []
    for label, divisions, layers, order in (("P1", 24, 12, 1), ("P2", 12, 6, 2)):
        built = octant(divisions, layers, order).build()
        elastic = built.elastic
        times = {}
        for name, law in (("analytic", StableNeoHookean), ("Jacobi", JacobiNeoHookean)):
            term = Elasticity(built.model.config, built.mesh.elements, law, elastic.parameters)
            term.hessian_values(True)
            start = time.perf_counter()
            for _ in range(5):
                term.hessian_values(True)
            times[name] = (time.perf_counter() - start) / 5
        n = built.mesh.n_elements
        eigen_rows.append(
            [
                f"{label}, {n}",
                *(f"{1e3 * t:.1f} ({1e6 * t / n:.1f} us/element)" for t in times.values()),
                f"{times['Jacobi'] / times['analytic']:.1f}x",
            ]
        )
    table += "\nThe projected elastic Hessian, analytic eigensystem against Jacobi on the 9 x 9 d2psi/dF2:\n\n"
    table += markdown(["tetrahedra", "analytic (ms)", "Jacobi (ms)", "ratio"], eigen_rows)
    return table, {"runs": data}


if __name__ == "__main__":
    main("solid", __doc__, lambda out: solid())
