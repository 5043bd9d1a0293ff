"""taichi-pneuma against NGSolve per Newton iteration, on the same tetrahedral meshes, in one run: this code builds
each case's mesh, and NGSolve is handed the same nodes and tetrahedra (netgen.meshing.Mesh: the points, the
tetrahedra's corners, boundary triangles for the clamp and the chamber wall), an H1 space of the same order on
them (quadratic tetrahedra: straight-edged in both), the same strain energy density written as an NGSolve
symbolic energy (Variation), the same quadrature (1 point on linear tetrahedra, the degree-2 rule of 4 points on
quadratic ones) and the same chamber load: the pressure as a follower load, the energy -p V(x) with V the
enclosed volume, p/3 times the integral over the chamber wall of x . cof(F) N, in both codes.

Cases: beam_p1 and beam_p2, the shipped beam_3d_ellipsoid scene on linear and on quadratic tetrahedra
(stable neo-Hookean), its volume ramp 1 -> 2x replaced by the pressures this code's volume ramp reaches at each
of its 10 increments (so that both codes ramp the same pressures); fiber_rubber, the rubber body of
fiber_bending_3d (quadratic tetrahedra, Yeoh) with no fibres and no sheet (fibers = [], layers = []), its
volumetric term at each quadrature point (volumetric = "element": NGSolve has no counterpart of the scene's
"mixed", one pressure per element), ramped to PEAK_FIBER_RUBBER kPa in 8 increments (without its threads the
body balloons long before the scene's 120 kPa).

Newton in NGSolve is a hand-written loop, as its tutorials write one: a.Apply (gradient), a.AssembleLinearization
(Hessian), the "sparsecholesky" inverse (analysed once, refactored by Update) and a backtracking line search on
a.Energy, converged when |gradient| <= tol |pressure force|; the clamp is a Dirichlet boundary (its DOFs
removed) where this code holds the same nodes by stiff springs. This code runs its own solver twice: "full
Newton" (chord_steps off: a new Hessian and factorisation every iteration, the like-for-like) and as shipped
(chord steps: some iterations reuse the factorisation held). Each code runs in its own process, 1 and 2
threads (Taichi's CPU threads and the BLAS threads; NGSolve's SetNumThreads and TaskManager), the runs
alternated, `repeats` of each; the table has the medians per Newton iteration of each phase: assembly (gradient
+ Hessian, this code's "assemble" included), factorisation + solve, line search, and the whole ramp.

    python benchmarks/ngsolve_3d.py [--cases beam_p1,beam_p2,fiber_rubber] [--repeats 3] [--out benchmarks/results]

Needs NGSolve (pip install -e .[bench]). Writes ngsolve_3d.md and .json (machine, load average, date).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from datetime import date
from pathlib import Path

import numpy as np

TOL = 1e-6
PEAK_FIBER_RUBBER = 30.0  # kPa: the rubber body alone, 8 increments
# name: (scene, overrides, how the pressures are set)
CASES = {
    "beam_p1": ("beam_3d_ellipsoid", {"mesh.order": 1}, "volume_ramp"),
    "beam_p2": ("beam_3d_ellipsoid", {}, "volume_ramp"),
    "fiber_rubber": (
        "fiber_bending_3d",
        {
            "fibers": [],
            "layers": [],
            "mesh.volumetric": "element",
            "chambers[0].keyframes": [[0, 0.0], [8, PEAK_FIBER_RUBBER]],
        },
        "scene",
    ),
}
CODES = ("taichi_full", "taichi_shipped", "ngsolve", "ngsolve_compiled")
LABELS = {
    "taichi_full": "taichi-pneuma, full Newton",
    "taichi_shipped": "taichi-pneuma, as shipped (chord steps)",
    "ngsolve": "NGSolve",
    "ngsolve_compiled": "NGSolve, energies compiled to C++",
}
PHASES = ("assembly", "factor_solve", "line_search", "ramp")


# ---- the case: this code's scene, mesh, law and pressures (in the parent) -------------------------------------------


def prepare(case: str, directory: Path) -> dict:
    """Build the case's scene in this code, write its mesh, law parameters and pressure ramp to an npz for the
    children; returns what the report says of it."""
    from taichi_pneuma import api, runtime

    runtime.ensure_initialised()
    name, overrides, load = CASES[case]
    scene = api.load_scene(name).with_values(overrides)
    if load == "volume_ramp":  # the scene's volume ramp, once: the pressure it needs at each increment
        reference = api.simulate(scene, tol=TOL)
        chamber = reference.built.chambers[0].chamber_name
        pressures = [float(p) for p in reference.history[f"{chamber}.pressure"]]
        keyframes = [[i, p] for i, p in enumerate(pressures)]
        scene = scene.with_values({"chambers[0].control": "pressure", "chambers[0].keyframes": keyframes})
    built = scene.build()
    mesh = built.mesh
    schedule = scene.schedule
    pressures = [float(schedule.commands(step)[0]) for step in range(scene.increments + 1)]
    law = built.elastic.law.name
    parameters = np.asarray(built.elastic.parameters)
    assert np.allclose(parameters, parameters[0]), "one material over the body"
    np.savez(
        directory / f"{case}.npz",
        vertices=mesh.vertices,
        elements=mesh.elements,
        wall=mesh.chambers[0],
        pinned=mesh.pinned,
        tip=mesh.tip,
        pressures=np.array(pressures),
        parameters=parameters[0],
        order=mesh.order,
    )
    (directory / f"{case}.json").write_text(json.dumps({"overrides": {**overrides, **dict(scene_overrides(scene))}}))
    return {
        "scene": name,
        "overrides": overrides,
        "law": law,
        "parameters": parameters[0].tolist(),
        "order": int(mesh.order),
        "nodes": int(mesh.n_vertices),
        "tetrahedra": int(mesh.n_elements),
        "wall_triangles": int(len(mesh.chambers[0])),
        "clamped_nodes": int(len(mesh.pinned)),
        "pressures": pressures,
        "load": load,
    }


def scene_overrides(scene) -> dict:
    """The chamber's control and keyframes as the children must set them (the pressure ramp)."""
    chamber = scene.controls[0].schedule
    return {
        "chambers[0].control": chamber.kind.name,
        "chambers[0].keyframes": [list(k) for k in chamber.keyframes],
    }


# ---- the children: one ramp of one code at a thread count, in a fresh process ---------------------------------------


def taichi_child(case: str, directory: Path, threads: int, chord: bool) -> dict:
    from taichi_pneuma import api, runtime
    from taichi_pneuma.solve.newton import NewtonOptions, NewtonSolver
    from taichi_pneuma.solve.simulate import run_schedule

    runtime.init("cpu", cpu_threads=threads)
    name, overrides, _ = CASES[case]
    overrides = {**overrides, **json.loads((directory / f"{case}.json").read_text())["overrides"]}
    scene = api.load_scene(name).with_values(overrides)
    options = NewtonOptions(tol=TOL, chord_steps=chord)
    # warm-up: the first increment alone, which compiles (or loads) every kernel the ramp runs
    pressures = np.load(directory / f"{case}.npz")["pressures"]
    first = scene.with_values({"schedule.increments": 1, "chambers[0].keyframes": [[0, 0.0], [1, float(pressures[1])]]})
    run_schedule(first.build(), options=options)
    built = scene.build()
    start = time.perf_counter()
    run = run_schedule(built, options=options)
    ramp = time.perf_counter() - start
    phases = dict(run.newton["phase_seconds"])
    iterations = int(np.sum(run.history["iterations"]))
    factorizations = iterations - int(run.newton["chord_steps"])
    data = np.load(directory / f"{case}.npz")
    u = np.asarray(run.displacements[-1])
    return {
        "iterations": iterations,
        "factorizations": factorizations,
        "assembly": phases.get("gradient", 0.0) + phases.get("hessian", 0.0) + phases.get("assemble", 0.0),
        "factor_solve": phases.get("factorize", 0.0) + phases.get("solve", 0.0),
        "line_search": phases.get("line_search", 0.0),
        "ramp": ramp,
        "phases": phases,
        "dofs": int(built.model.n_dofs),
        "nnz": int(NewtonSolver(built.model, options).pattern.nnz),
        "linear_solver": run.newton["linear_solver"],
        "tip": float(u[data["tip"], 1].mean()),
        "u": u.tolist(),
    }


def ngsolve_energy(law: str, p: np.ndarray, F):
    """The law's strain energy density per unit rest volume, as an NGSolve coefficient function of F."""
    import ngsolve as ng

    J = ng.Det(F)
    if law == "stable_neo_hookean":
        mu, lam = p
        return mu * (1 - J) + lam / 2 * (1 - J) ** 2 + mu / 2 * (ng.InnerProduct(F, F) - 3)
    C10, C01, C20, C30, K = p  # materials/isochoric.py
    assert C01 == 0, "Mooney-Rivlin's I2 term is not written here"
    a = J ** (-2 / 3) * ng.InnerProduct(F, F) - 3
    return C10 * a + C20 * a * a + C30 * a * a * a + K / 2 * (J - 1) ** 2


def boundary_faces(tets: np.ndarray) -> np.ndarray:
    """The triangles (corners) that bound the tetrahedra's union: the faces of one tetrahedron only."""
    faces = np.vstack([tets[:, [1, 2, 3]], tets[:, [0, 3, 2]], tets[:, [0, 1, 3]], tets[:, [0, 2, 1]]])
    _, index, counts = np.unique(np.sort(faces, axis=1), axis=0, return_index=True, return_counts=True)
    return faces[index[counts == 1]]


def netgen_mesh(vertices, tets, wall, pinned):
    """The same nodes and tetrahedra (corners) as a netgen mesh, its boundary triangles in three regions: "clamp"
    (every corner clamped), "chamber" (the chamber wall's) and "outer"."""
    import netgen.meshing as nm
    import ngsolve as ng

    mesh = nm.Mesh(dim=3)
    mesh.AddPoints(np.ascontiguousarray(vertices, dtype=np.float64))
    region = mesh.AddRegion("rubber", dim=3)
    mesh.AddElements(dim=3, index=region, data=np.ascontiguousarray(tets, dtype=np.int32), base=0)
    faces = boundary_faces(tets)
    walls = {tuple(sorted(f)) for f in wall.tolist()}
    on_wall = np.array([tuple(sorted(f)) in walls for f in faces.tolist()])
    clamped = np.zeros(len(vertices), dtype=bool)
    clamped[pinned] = True
    on_clamp = clamped[faces].all(axis=1) & ~on_wall
    for bc, (name, chosen) in enumerate(
        (("clamp", on_clamp), ("chamber", on_wall), ("outer", ~on_clamp & ~on_wall)), 1
    ):
        descriptor = mesh.Add(nm.FaceDescriptor(bc=bc, domin=1, domout=0, surfnr=bc))
        mesh.SetBCName(bc - 1, name)
        mesh.AddElements(dim=2, index=descriptor, data=np.ascontiguousarray(faces[chosen], dtype=np.int32), base=0)
    return ng.Mesh(mesh)


def ngsolve_child(case: str, directory: Path, threads: int, compiled: bool = False) -> dict:
    import ngsolve as ng

    data = np.load(directory / f"{case}.npz")
    order = int(data["order"])
    law = prepare_law(directory, case)
    vertices, elements = data["vertices"], data["elements"]
    mesh = netgen_mesh(vertices, elements[:, :4], data["wall"][:, :3], data["pinned"])
    fes = ng.VectorH1(mesh, order=order, dirichlet="clamp")
    u, v = fes.TnT()
    F = ng.Id(3) + ng.Grad(u)
    # the same quadrature as this code's: 1 point (linear), the degree-2 rule (quadratic); the wall's integrand
    # x . cof F N is of degree 1 (linear) and 4 (quadratic): integrated exactly, as this code does
    dx = ng.dx(intrules={ng.TET: ng.IntegrationRule(ng.TET, 1 if order == 1 else 2)})
    ds = ng.ds("chamber", intrules={ng.TRIG: ng.IntegrationRule(ng.TRIG, 2 if order == 1 else 4)})
    normal = ng.specialcf.normal(3)
    position = ng.CF((ng.x, ng.y, ng.z))
    # on the wall Grad(u.Trace()) is the surface gradient (grad u) P, P = I - N N^T: cof(I + grad u P) N = F t1 x F t2
    # (t1, t2 tangent, t1 x t2 = N) = cof(F) N, Nanson's n da / dA
    sign = (
        1.0 if ng.Integrate(ng.InnerProduct(position, normal), mesh, definedon=mesh.Boundaries("chamber")) > 0 else -1.0
    )
    pressure = ng.Parameter(0.0)
    trace = u.Trace()
    volume = sign / 3 * ng.InnerProduct(position + trace, ng.Cof(ng.Id(3) + ng.Grad(trace)) * normal)
    a = ng.BilinearForm(fes, symmetric=True)
    a += ng.Variation(ngsolve_energy(law[0], law[1], F).Compile(realcompile=compiled, wait=True) * dx)
    a += ng.Variation((-pressure * volume).Compile(realcompile=compiled, wait=True) * ds)
    load = ng.BilinearForm(fes, symmetric=True)  # the pressure's force alone: the convergence test's scale
    load += ng.Variation((-pressure * volume).Compile(realcompile=compiled, wait=True) * ds)
    free = fes.FreeDofs()
    gfu, trial = ng.GridFunction(fes), ng.GridFunction(fes)
    res, du, force = gfu.vec.CreateVector(), gfu.vec.CreateVector(), gfu.vec.CreateVector()
    ng.SetNumThreads(threads)
    seconds = dict.fromkeys(("gradient", "hessian", "factorize", "solve", "line_search", "check"), 0.0)
    inverse = None
    iterations = 0

    def norm(vector) -> float:
        values = vector.FV().NumPy()
        return float(np.linalg.norm(values[np.array(free, dtype=bool)]))

    with ng.TaskManager():
        start = time.perf_counter()
        for p in data["pressures"][1:]:
            pressure.Set(float(p))
            clock = time.perf_counter()
            energy = a.Energy(gfu.vec)
            seconds["line_search"] += time.perf_counter() - clock
            for _ in range(60):
                clock = time.perf_counter()
                a.Apply(gfu.vec, res)
                seconds["gradient"] += time.perf_counter() - clock
                clock = time.perf_counter()
                load.Apply(gfu.vec, force)
                done = norm(res) <= TOL * norm(force)
                seconds["check"] += time.perf_counter() - clock
                if done:
                    break
                clock = time.perf_counter()
                a.AssembleLinearization(gfu.vec)
                seconds["hessian"] += time.perf_counter() - clock
                clock = time.perf_counter()
                if inverse is None:
                    inverse = a.mat.Inverse(free, inverse="sparsecholesky")
                else:
                    inverse.Update()
                seconds["factorize"] += time.perf_counter() - clock
                clock = time.perf_counter()
                du.data = inverse * res
                seconds["solve"] += time.perf_counter() - clock
                clock = time.perf_counter()
                slope = -ng.InnerProduct(du, res)
                alpha = 1.0
                for _ in range(30):
                    trial.vec.data = gfu.vec - alpha * du
                    value = a.Energy(trial.vec)
                    if np.isfinite(value) and value <= energy + 1e-4 * alpha * slope:
                        break
                    alpha *= 0.5
                gfu.vec.data = trial.vec
                energy = value
                seconds["line_search"] += time.perf_counter() - clock
                iterations += 1
            else:
                raise RuntimeError(f"NGSolve: no convergence at p = {p}")
        ramp = time.perf_counter() - start
    points = mesh(vertices[:, 0], vertices[:, 1], vertices[:, 2])
    u_nodes = np.asarray(gfu(points)).reshape(len(vertices), 3)
    return {
        "iterations": iterations,
        "factorizations": iterations,
        "assembly": seconds["gradient"] + seconds["hessian"],
        "factor_solve": seconds["factorize"] + seconds["solve"],
        "line_search": seconds["line_search"],
        "ramp": ramp,
        "phases": seconds,
        "dofs": int(sum(free)),
        "nnz": int(2 * a.mat.nze - fes.ndof),  # the symmetric matrix's lower triangle is stored
        "linear_solver": "sparsecholesky",
        "tip": float(u_nodes[data["tip"], 1].mean()),
        "u": u_nodes.tolist(),
    }


def prepare_law(directory: Path, case: str) -> tuple[str, np.ndarray]:
    data = np.load(directory / f"{case}.npz")
    law = json.loads((directory / "laws.json").read_text())[case]
    return law, data["parameters"]


def child(code: str, case: str, directory: Path, threads: int) -> None:
    if code.startswith("ngsolve"):
        record = ngsolve_child(case, directory, threads, compiled=code == "ngsolve_compiled")
    else:
        record = taichi_child(case, directory, threads, chord=code == "taichi_shipped")
    print(json.dumps(record))


def run_once(code: str, case: str, directory: Path, threads: int) -> dict:
    env = {**os.environ, "OPENBLAS_NUM_THREADS": str(threads), "OMP_NUM_THREADS": str(threads)}
    env["PATH"] = f"{Path(sys.executable).parent}{os.pathsep}{env.get('PATH', '')}"  # NGSolve's ngscxx
    load = os.getloadavg()[0]
    proc = subprocess.run(
        [sys.executable, __file__, "--child", code, case, str(directory), str(threads)],
        env=env,
        capture_output=True,
        text=True,
    )
    if proc.returncode != 0:
        raise RuntimeError(f"{code} {case} {threads} threads failed:\n{proc.stderr[-3000:]}")
    record = json.loads(proc.stdout.strip().splitlines()[-1])
    record["load_before"] = load
    return record


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--cases", default=",".join(CASES))
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--threads", default="1,2")
    parser.add_argument("--out", default="benchmarks/results")
    parser.add_argument("--child", nargs=4, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        code, case, directory, threads = args.child
        child(code, case, Path(directory), int(threads))
        return
    from taichi_pneuma.io.output import prepare_directory, save_json, save_text

    out = prepare_directory(args.out)
    cases = args.cases.split(",")
    thread_counts = [int(t) for t in args.threads.split(",")]
    directory = Path(tempfile.mkdtemp(prefix="ngsolve_3d_"))
    records: dict = {}
    laws = {}
    for case in cases:
        records[case] = {"case": prepare(case, directory), "runs": {}}
        laws[case] = records[case]["case"]["law"]
        print(f"{case}: {records[case]['case']}", flush=True)
    (directory / "laws.json").write_text(json.dumps(laws))
    for case in cases:
        runs = records[case]["runs"]
        for repeat in range(args.repeats):
            for threads in thread_counts:
                codes = CODES if repeat % 2 == 0 else CODES[::-1]
                for code in codes:
                    record = run_once(code, case, directory, threads)
                    runs.setdefault(f"{code}/{threads}", []).append(record)
                    print(
                        f"{case} {code} {threads} thread(s): {record['iterations']} iterations "
                        f"({record['factorizations']} factorisations), ramp {record['ramp']:.2f} s, "
                        f"assembly {record['assembly']:.2f} s, factor+solve {record['factor_solve']:.2f} s, "
                        f"tip {record['tip']:+.6f}, load {record['load_before']:.2f}",
                        flush=True,
                    )
    text, summary = report(records, thread_counts, args.repeats)
    print(text)
    save_text(out / "ngsolve_3d.md", text)
    save_json(out / "ngsolve_3d.json", summary)


def report(records: dict, thread_counts: list[int], repeats: int) -> tuple[str, dict]:
    import ngsolve

    machine = machine_line()
    summary: dict = {
        "machine": machine,
        "load_average": os.getloadavg(),
        "date": str(date.today()),
        "ngsolve": ngsolve.__version__,
        "tol": TOL,
        "repeats": repeats,
        "cases": {},
    }
    lines = [
        f"Machine: {machine}; {summary['date']}; NGSolve {ngsolve.__version__}. Median of {repeats} runs of each "
        f"code and thread count, alternated; seconds per Newton iteration (ms), tol {TOL:g}.",
        "",
    ]
    for case, record in records.items():
        info = record["case"]
        first = {key: runs[0] for key, runs in record["runs"].items()}
        ours, theirs = first[f"taichi_full/{thread_counts[0]}"], first[f"ngsolve/{thread_counts[0]}"]
        u_ours, u_theirs = np.array(ours["u"]), np.array(theirs["u"])
        gap = float(np.abs(u_ours - u_theirs).max() / np.abs(u_theirs).max())
        medians = {}
        for key, runs in record["runs"].items():
            iterations = runs[0]["iterations"]
            medians[key] = {
                "iterations": iterations,
                "factorizations": runs[0]["factorizations"],
                **{phase: statistics.median(r[phase] for r in runs) / iterations for phase in PHASES},
                "ramp_s": statistics.median(r["ramp"] for r in runs),
                "load_before": [r["load_before"] for r in runs],
                "dofs": runs[0]["dofs"],
                "nnz": runs[0]["nnz"],
                "linear_solver": runs[0]["linear_solver"],
                "tip": runs[0]["tip"],
            }
        summary["cases"][case] = {
            **info,
            "medians": medians,
            "runs": {k: [{kk: vv for kk, vv in r.items() if kk != "u"} for r in v] for k, v in record["runs"].items()},
            "max_displacement_gap": gap,
        }
        kind = "linear" if info["order"] == 1 else "quadratic"
        lines += [
            f"**{case}**: {info['scene']} {json.dumps(info['overrides']) if info['overrides'] else '(as shipped)'}; "
            f"{info['tetrahedra']} {kind} tetrahedra, {info['nodes']} nodes, law {info['law']}, pressure ramp "
            f"{', '.join(f'{p:.4g}' for p in info['pressures'][1:])}"
            + (" (the scene's volume ramp's pressures)" if info["load"] == "volume_ramp" else "")
            + ".",
            "",
            "| code | threads | DOFs | nnz | iterations (factorisations) | assembly ms/it | factor+solve ms/it | "
            "line search ms/it | ramp ms/it | ramp s |",
            "|---|---|---|---|---|---|---|---|---|---|",
        ]
        for threads in thread_counts:
            for code in CODES:
                m = medians[f"{code}/{threads}"]
                lines.append(
                    f"| {LABELS[code]} | {threads} | {m['dofs']} | {m['nnz']} | {m['iterations']} "
                    f"({m['factorizations']}) | {1e3 * m['assembly']:.1f} | {1e3 * m['factor_solve']:.1f} | "
                    f"{1e3 * m['line_search']:.1f} | {1e3 * m['ramp']:.1f} | {m['ramp_s']:.2f} |"
                )
        lines.append("")
        for threads in thread_counts:
            full, shipped = medians[f"taichi_full/{threads}"], medians[f"taichi_shipped/{threads}"]
            for code in ("ngsolve", "ngsolve_compiled"):
                theirs_m = medians[f"{code}/{threads}"]
                lines.append(
                    f"{LABELS[code]} / taichi-pneuma (full Newton) per iteration, {threads} thread(s): assembly "
                    f"{theirs_m['assembly'] / full['assembly']:.1f}x, factor+solve "
                    f"{theirs_m['factor_solve'] / full['factor_solve']:.1f}x, whole ramp "
                    f"{theirs_m['ramp'] / full['ramp']:.1f}x (against as shipped: "
                    f"{theirs_m['ramp'] / shipped['ramp']:.1f}x per iteration, "
                    f"{theirs_m['ramp_s'] / shipped['ramp_s']:.1f}x per ramp)."
                )
                summary["cases"][case].setdefault("ratios", {})[f"{code}/{threads}"] = {
                    phase: theirs_m[phase] / full[phase] for phase in PHASES
                }
        lines += [
            "",
            f"Tips (mean y displacement of the tip nodes): taichi-pneuma {ours['tip']:+.6f}, NGSolve "
            f"{theirs['tip']:+.6f}; largest nodal displacement difference {gap:.1e} of the largest displacement.",
            "",
        ]
    return "\n".join(lines), summary


def machine_line() -> str:
    cpu = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    load = ", ".join(f"{x:.2f}" for x in os.getloadavg())
    return f"{platform.node()}, {cpu}, {os.cpu_count()} CPUs, load average {load} at the end"


if __name__ == "__main__":
    main()
