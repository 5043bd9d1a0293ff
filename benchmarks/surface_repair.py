"""Surface repair: gmsh with the project's repair (fem/surface_import.py) against fTetWild (pytetwild) on the
shipped STL exports and on broken copies of one.

Cases: the shipped pneunet.stl (9,026 facets, six cavities) and fiber_actuator.stl (264 facets, one cavity), and
copies of pneunet.stl broken as exports and hand edits break surfaces: a third of its facets turned over and a tenth
written twice; a small hole (one facet of the bottom face left out); a self-intersecting facet pair (the top face's
vertex nearest [-1.24, 0.4, 0] pushed down to y = 0.25, through the roof of the first chamber at y = 0.35: the dented
facets cross the roof's); and all three at once.

Tools, each case in a process of its own (a time limit of TIMEOUT s, its peak resident size reported):

- gmsh: SurfaceGeometry, the repair (vertices merged, degenerate and repeated facets dropped, holes and
  non-manifold edges refused, facets turned consistent and outward) and gmsh's remesh and Delaunay fill at the
  shipped scenes' sizes (pneunet_stl: 0.3, 0.08 within 0.3 of the chambers; fiber_bending_3d's STL: 5, 4 within 4),
  quadratic tetrahedra as those scenes have (their boundary edges' midside nodes on the file's surface), each
  chamber the cavity around its point; under the default budget.
- fTetWild: pytetwild.tetrahedralize (linear tetrahedra, their surface within the envelope of the file's) on the
  file's triangles with exactly repeated vertices merged (what any STL loader does), an ideal edge length of the
  near-chamber size (fTetWild grades by its envelope, not by distance to a wall), the default envelope (1e-3 of the
  bounding box diagonal), one thread (gmsh meshes on one).

Measured: whether it runs (or the refusal or error line), the wall time, the tetrahedra, their quality (the
normalised volume 6 sqrt(2) V / l_rms^3 of the corners, 1 for the regular tetrahedron, benchmarks/cad_import.py's:
minimum and mean), the rubber volume and the cavities' (their count and total: gmsh's chamber walls; fTetWild's
inner boundary shells) against the closed forms of the solids the files were made from (pneunet: the 4 x 0.8 x 0.76
block less six rounded boxes 0.4 x 0.5 x 0.6 of radius 0.08, Steiner's formula; the fibre actuator:
tests/test_cad.py's half-round bar on its base less the half-round chamber), and the volumes the clean files' own
surfaces enclose (the facets' chords already cut 2.2 % of pneunet's air).

    python benchmarks/surface_repair.py [--tetwild-python /path/to/python] [--out benchmarks/results]

fTetWild runs where pytetwild imports (it needs pyvista; neither is a dependency of the project), in this Python or
the one --tetwild-python names (a venv made for it: python3 -m venv V && V/bin/pip install pytetwild pyvista numpy).
Writes surface_repair.md and surface_repair.json (machine, date) under --out; one progress line per run.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
SCENES = os.path.join(HERE, os.pardir, "taichi_pneuma", "scenes")
TIMEOUT = 900
STL = np.dtype([("normal", "<f4", 3), ("corners", "<f4", (3, 3)), ("attribute", "<u2")])


def rounded_box_volume(size, r: float) -> float:
    """Steiner's formula: the inner box (size - 2r) swept by a ball of radius r."""
    p, q, s = (v - 2 * r for v in size)
    return p * q * s + 2 * (p * q + q * s + s * p) * r + np.pi * (p + q + s) * r**2 + 4 / 3 * np.pi * r**3


POCKET = rounded_box_volume((0.4, 0.5, 0.6), 0.08)
BAR, CHANNEL = np.pi * 8.0**2 / 2 * 100.0 + 2.0 * 16.0 * 100.0, np.pi * 6.0**2 / 2 * 94.0  # tests/test_cad.py
BODIES = {  # the file's solid: rubber and cavities' closed forms, chamber points, gmsh's sizes, fTetWild's edge
    "pneunet": {
        "rubber": 4.0 * 0.8 * 0.76 - 6 * POCKET,
        "cavities": 6 * POCKET,
        "points": [(-1.25 + 0.5 * k, 0.1, 0.0) for k in range(6)],
        "sizes": (0.3, 0.08, 0.3),
        "edge": 0.08,
    },
    "fiber_actuator": {
        "rubber": BAR - CHANNEL,
        "cavities": CHANNEL,
        "points": [(50.0, 4.0, 0.0)],
        "sizes": (5.0, 4.0, 4.0),
        "edge": 4.0,
    },
}


def read_stl(path: str) -> np.ndarray:
    """A binary STL's facets as (t, 3, 3) corners."""
    return np.fromfile(path, dtype=STL, offset=84)["corners"].astype(np.float64)


def write_stl(path: str, facets: np.ndarray) -> None:
    data = np.zeros(len(facets), dtype=STL)
    data["corners"] = facets
    with open(path, "wb") as f:
        f.write(b"surface_repair.py".ljust(80, b" ") + np.uint32(len(facets)).tobytes() + data.tobytes())


def flipped_and_repeated(facets: np.ndarray) -> np.ndarray:
    broken = facets.copy()
    broken[::3] = broken[::3, ::-1]
    return np.concatenate([broken, facets[::10], facets[1::10, ::-1]])


def holed(facets: np.ndarray) -> np.ndarray:
    centre = facets.mean(axis=1)
    return np.delete(facets, np.argmin(np.linalg.norm(centre - [0.0, -0.4, 0.0], axis=1)), axis=0)


def dented(facets: np.ndarray) -> np.ndarray:
    corners = facets.reshape(-1, 3)
    top = np.isclose(corners[:, 1], 0.4)
    target = corners[top][np.argmin(np.linalg.norm(corners[top] - [-1.24, 0.4, 0.0], axis=1))]
    moved = corners.copy()
    moved[np.all(corners == target, axis=1), 1] = 0.25
    return moved.reshape(-1, 3, 3)


CASES = {  # name: (body, how the shipped file is broken)
    "pneunet.stl": ("pneunet", None),
    "fiber_actuator.stl": ("fiber_actuator", None),
    "pneunet.stl, facets flipped and repeated": ("pneunet", flipped_and_repeated),
    "pneunet.stl, a small hole": ("pneunet", holed),
    "pneunet.stl, a self-intersecting facet pair": ("pneunet", dented),
    "pneunet.stl, all three": ("pneunet", lambda f: flipped_and_repeated(holed(dented(f)))),
}


def normalised_volumes(vertices: np.ndarray, tets: np.ndarray) -> np.ndarray:
    from cad_import import normalised_volumes as measure  # benchmarks/cad_import.py's measure

    return measure(vertices[tets[:, :4]])


def shells_volumes(vertices: np.ndarray, tets: np.ndarray) -> list[float]:
    """The signed volume each boundary shell of a tetrahedral mesh encloses (its faces oriented out of the rubber:
    the outer shell's positive, a cavity's negative); shells are the boundary's pieces joined at vertices."""
    x = vertices[tets]
    tets = np.where((np.linalg.det(x[:, 1:] - x[:, :1]) < 0)[:, None], tets[:, [0, 2, 1, 3]], tets)
    faces = tets[:, [[1, 2, 3], [0, 3, 2], [0, 1, 3], [0, 2, 1]]].reshape(-1, 3)
    _, first, counts = np.unique(np.sort(faces, axis=1), axis=0, return_index=True, return_counts=True)
    boundary = faces[first[counts == 1]]
    label = np.arange(len(vertices))
    while True:  # each vertex the least label of its faces' vertices, until nothing changes
        least = label[boundary].min(axis=1)
        new = label.copy()
        np.minimum.at(new, boundary.ravel(), np.repeat(least, 3))
        new = new[new]
        if np.array_equal(new, label):
            break
        label = new
    y = vertices[boundary]
    signed = np.einsum("ij,ij->i", y[:, 0], np.cross(y[:, 1], y[:, 2])) / 6
    shell = label[boundary[:, 0]]
    return [float(signed[shell == k].sum()) for k in np.unique(shell)]


def run_gmsh(path: str, body: dict) -> dict:
    from taichi_pneuma.errors import PneumaInputError
    from taichi_pneuma.fem.gmsh_mesher import MeshSizes
    from taichi_pneuma.fem.supports import PointSet
    from taichi_pneuma.fem.surface_import import Cavity, SurfaceBody, SurfaceGeometry
    from taichi_pneuma.limits import MAX_TRIANGLES, Budget
    from taichi_pneuma.scene.build import ChamberControl, Scene
    from taichi_pneuma.scene.schedule import area_ramp

    chambers = tuple((f"c{k + 1}", Cavity(p)) for k, p in enumerate(body["points"]))
    started = time.perf_counter()
    try:
        sizes, left = MeshSizes(*body["sizes"]), PointSet("left")  # a clamp: the chambers' volumes need a built scene
        geometry = SurfaceGeometry(SurfaceBody(path, 1.0), chambers, sizes, order=2, clamp=left)
        mesh = geometry.mesh(Budget(MAX_TRIANGLES))
    except PneumaInputError as exc:
        return {"outcome": "refused: " + str(exc).replace(path, os.path.basename(path))}
    seconds = time.perf_counter() - started
    controls = tuple(ChamberControl(area_ramp(1.5, 2, 1.0)) for _ in chambers)
    cavities = [chamber.rest_area for chamber in Scene(geometry, controls, 1).build().chambers]  # quadratic walls'
    return {"outcome": "meshed", "s": seconds, **measures(mesh.vertices, mesh.elements, float(mesh.measure), cavities)}


def run_tetwild(path: str, body: dict) -> dict:
    import pytetwild

    facets = read_stl(path)
    vertices, faces = np.unique(facets.reshape(-1, 3), axis=0, return_inverse=True)
    started = time.perf_counter()
    try:
        points, tets = pytetwild.tetrahedralize(
            vertices, faces.reshape(-1, 3).astype(np.int32), edge_length_abs=body["edge"], num_threads=1, quiet=True
        )
    except Exception as exc:  # fTetWild's own failure, reported as the outcome
        return {"outcome": f"failed: {type(exc).__name__}: {exc}"}
    seconds = time.perf_counter() - started
    tets = np.asarray(tets, dtype=np.int64)
    points = np.asarray(points, dtype=np.float64)
    if len(tets) == 0:
        return {"outcome": "failed: no tetrahedra", "s": seconds}
    volumes = shells_volumes(points, tets)
    rubber = float(np.abs(np.linalg.det(points[tets[:, 1:]] - points[tets[:, :1]])).sum() / 6)
    return {"outcome": "meshed", "s": seconds, **measures(points, tets, rubber, [-v for v in volumes if v < 0])}


def measures(vertices: np.ndarray, tets: np.ndarray, rubber: float, cavities: list[float]) -> dict:
    q = normalised_volumes(vertices, tets)
    return {
        "tetrahedra": len(tets),
        "quality_min": float(q.min()),
        "quality_mean": float(q.mean()),
        "rubber": rubber,
        "cavity_count": len(cavities),
        "cavities": float(sum(cavities)),
    }


def worker(tool: str, case: str, path: str) -> None:
    """One run, its result a JSON line on stdout (with the process's peak resident size)."""
    sys.path.insert(0, HERE)
    body = BODIES[CASES[case][0]]
    result = (run_gmsh if tool == "gmsh" else run_tetwild)(path, body)
    result["peak_mb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e3
    print("RESULT " + json.dumps(result), flush=True)


def launch(python: str, tool: str, case: str, path: str, folder: str) -> dict:
    """Run one case in a process of its own, in `folder` (fTetWild writes __tracked_surface.stl where it runs)."""
    command = [python, os.path.abspath(__file__), "--worker", tool, case, os.path.abspath(path)]
    try:
        done = subprocess.run(command, capture_output=True, text=True, timeout=TIMEOUT, cwd=folder)
    except subprocess.TimeoutExpired:
        return {"outcome": f"did not finish in {TIMEOUT} s"}
    lines = [line for line in done.stdout.splitlines() if line.startswith("RESULT ")]
    if not lines:
        tail = (done.stderr.strip().splitlines() or ["no output"])[-1]
        return {"outcome": f"crashed (exit {done.returncode}): {tail}"}
    return json.loads(lines[-1][len("RESULT ") :])


def file_volumes(path: str) -> dict:
    """The file's own rubber and cavities: the signed volumes its repaired shells enclose (fem/surface_import.py's
    repair; sum x0 . (x1 x x2) / 6 over each shell's facets)."""
    from taichi_pneuma.fem.surface_import import repaired

    facets = read_stl(path)
    shells = repaired(facets.reshape(-1, 3), np.arange(3 * len(facets)).reshape(-1, 3), path)
    x = shells.vertices[shells.triangles]
    signed = np.einsum("ij,ij->i", x[:, 0], np.cross(x[:, 1], x[:, 2])) / 6
    volumes = [float(signed[shells.shell == k].sum()) for k in range(shells.count)]  # cavities' negative
    return {
        "outcome": "its own surface",
        "rubber": sum(volumes),
        "cavity_count": shells.count - 1,
        "cavities": -sum(volumes[1:]),
    }


def cell(row: dict, body: dict) -> list[str]:
    if "rubber" not in row:
        return [row["outcome"]] + [""] * 6
    meshed = "tetrahedra" in row
    return [
        row["outcome"],
        f"{row['s']:.2f}" if meshed else "",
        f"{row['tetrahedra']}" if meshed else "",
        f"{row['quality_min']:.3f} / {row['quality_mean']:.3f}" if meshed else "",
        f"{row['rubber']:.6g} ({100 * (row['rubber'] / body['rubber'] - 1):+.2f} %)",
        f"{row['cavity_count']}: {row['cavities']:.6g} ({100 * (row['cavities'] / body['cavities'] - 1):+.2f} %)",
        f"{row['peak_mb']:.0f}" if meshed else "",
    ]


def markdown(results: dict, machine: str) -> str:
    lines = [
        f"Machine: {machine}. Written by `python benchmarks/surface_repair.py` (its docstring says what is "
        "measured); one run each, one thread each.",
        "",
        "| surface | tool | outcome | s | tetrahedra | quality min / mean | rubber (from the closed form) | "
        "cavities: count, volume (from the closed form) | peak MB |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for case, rows in results.items():
        body = BODIES[CASES[case][0]]
        for tool, row in rows.items():
            lines.append("| " + " | ".join([case, tool, *cell(row, body)]) + " |")
    return "\n".join(lines) + "\n"


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--out", default="benchmarks/results")
    p.add_argument("--tetwild-python", default=None, help="a Python with pytetwild (default: this one, if it has it)")
    p.add_argument("--worker", nargs=3, metavar=("TOOL", "CASE", "PATH"), help=argparse.SUPPRESS)
    args = p.parse_args()
    if args.worker:
        worker(*args.worker)
        return 0
    from taichi_pneuma.apps.bench import machine
    from taichi_pneuma.io.output import prepare_directory, save_json, save_text

    tetwild = args.tetwild_python or sys.executable
    found = subprocess.run([tetwild, "-c", "import pytetwild"], capture_output=True).returncode == 0
    results: dict = {}
    with tempfile.TemporaryDirectory() as folder:
        for case, (name, broken) in CASES.items():
            path = os.path.join(SCENES, f"{name}.stl")
            results[case] = {} if broken else {"the file": file_volumes(path)}
            if broken is not None:
                path = os.path.join(folder, f"{len(results)}.stl")
                write_stl(path, broken(read_stl(os.path.join(SCENES, f"{name}.stl"))))
            results[case]["gmsh"] = launch(sys.executable, "gmsh", case, path, folder)
            print(f"{case}, gmsh: {results[case]['gmsh']}", flush=True)
            if found:
                results[case]["fTetWild"] = launch(tetwild, "fTetWild", case, path, folder)
                print(f"{case}, fTetWild: {results[case]['fTetWild']}", flush=True)
    if not found:
        print(f"pytetwild does not import in {tetwild}: fTetWild left out (--tetwild-python names one that has it)")
    out = prepare_directory(args.out)
    day = time.strftime("%Y-%m-%d")
    save_json(out / "surface_repair.json", {"machine": machine(), "date": day, "cases": results})
    save_text(out / "surface_repair.md", markdown(results, machine()))
    print(f"wrote {out / 'surface_repair.md'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
