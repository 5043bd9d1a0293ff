"""The live views on a reduced model against the full model, on the same mesh, while the sliders are dragged.

    xvfb-run -a python benchmarks/live_reduced.py [--scenes pneunet_3d,fiber_bending_3d] [--samples 24]
        [--frames 60] [--frames-full 20] [--warmup 5] [--views page,native] [--out benchmarks/results]
        (repository root on PYTHONPATH, project venv)

Per scene (shipped, its own mesh): a reduced model trained as pneuma-reduce trains it (reduce/train.py: the schedule
and --samples Latin hypercube points, the POD basis keeping --energy, default 1 - 1e-8, of the energy; ECSW at
1e-4), its training time,
and its errors against the full model at 4 held-out commands (reduce/train.py validate: the tip's error as % of the
body's length, the bend angle's in degrees). Then, on the drag of live_page.py (every chamber's command stepped from
its slider's low end to its high end and back, one step per frame; the first --warmup frames not timed), the frames
per second of
  page:   the live page's loop without a browser (live_page.page_run: LiveSession.advance, the body published, the
          figures), full and reduced (pneuma-serve --reduced);
  native: the 3D window (live_page.native_3d: GGUI on Mesa's lavapipe under xvfb, 960 x 640), full and reduced
          (pneuma-inflate --interactive --reduced).
The full model's frames are fewer (--frames-full): one of its frames takes a second. BLAS runs on one thread (the
reduced model's r x r products are too small to share). Writes live_reduced.md and live_reduced.json (machine, date).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import sys
import tempfile
import time
from datetime import date
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # before NumPy loads
os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
from live_page import drag, native_3d, page_run  # noqa: E402

HELD_OUT = 4


def train_model(scene, samples: int, energy: float, directory: Path) -> tuple[Path, dict]:
    """Train, validate and save a reduced model of the scene; (its file, its figures)."""
    from taichi_pneuma.reduce.store import save_reduced
    from taichi_pneuma.reduce.train import train, validate

    started = time.perf_counter()
    training = train(scene.build(), energy=energy, samples=samples)
    seconds = time.perf_counter() - started
    compared = validate(training, HELD_OUT, 1)
    path = directory / f"{scene.name}_reduced.npz"
    save_reduced(path, training.model, training.singular_values)
    model = training.model
    return path, {
        "modes": model.n_modes,
        "elements": len(model.elements),
        "mesh_elements": model.built.mesh.n_elements,
        "nodes": model.built.mesh.n_vertices,
        "training_seconds": seconds,
        "tip_error_max_percent": max(c.tip_error for c in compared),
        "angle_error_max_degrees": max(c.angle_error for c in compared),
        "full_residual_max": max(c.residual for c in compared),
    }


def run_scene(name: str, args) -> dict:
    import taichi_pneuma as tp
    from taichi_pneuma.realtime.interactive import chamber_sliders

    scene = tp.load_scene(name)
    sliders = chamber_sliders(scene)
    low, high = np.array([s.low for s in sliders]), np.array([s.high for s in sliders])
    with tempfile.TemporaryDirectory() as directory:
        path, figures = train_model(scene, args.samples, args.energy, Path(directory))
        print(f"{name}: trained in {figures['training_seconds']:.0f} s: {figures}", flush=True)
        views = {}
        for view in args.views.split(","):
            for model, frames in (("full", args.frames_full), ("reduced", args.frames)):
                commands = drag(low, high, args.warmup, frames)
                reduced = path if model == "reduced" else None
                if view == "page":
                    result = page_run(scene, commands, args.warmup, reduced=reduced)
                else:
                    result = native_3d(scene, commands, args.warmup, reduced=reduced)
                views[f"{view} {model}"] = result
                print(f"  {view} {model}: {result['fps']:.1f} frames/s", flush=True)
    return {"scene": name, **figures, "views": views}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenes", default="pneunet_3d,fiber_bending_3d")
    parser.add_argument("--samples", type=int, default=24)
    parser.add_argument("--energy", type=float, default=1 - 1e-8, help="the POD energy fraction kept")
    parser.add_argument("--frames", type=int, default=60)
    parser.add_argument("--frames-full", type=int, default=20)
    parser.add_argument("--warmup", type=int, default=5)
    parser.add_argument("--views", default="page,native")
    parser.add_argument("--out", default="benchmarks/results")
    args = parser.parse_args()
    import taichi_pneuma as tp

    tp.init("cpu")
    rows = [run_scene(name, args) for name in args.scenes.split(",")]
    load = os.getloadavg()[0]
    machine = f"{platform.machine()}, {os.cpu_count()} cores, load {load:.1f}, Python {platform.python_version()}"
    record = {"date": date.today().isoformat(), "machine": machine, "samples": args.samples, "energy": args.energy}
    record["rows"] = rows
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "live_reduced.json").write_text(json.dumps(record, indent=2) + "\n")
    lines = [
        f"Machine: {machine}, {record['date']}. Written by benchmarks/live_reduced.py (its docstring says what is "
        "measured).",
        "",
        "| scene | nodes | modes | elements sampled | training s | tip error max, % length | angle error max, deg "
        "| view | full frames/s | reduced frames/s | ratio |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for row in rows:
        for view in args.views.split(","):
            full, reduced = row["views"][f"{view} full"]["fps"], row["views"][f"{view} reduced"]["fps"]
            lines.append(
                f"| {row['scene']} | {row['nodes']} | {row['modes']} | {row['elements']} of {row['mesh_elements']} "
                f"| {row['training_seconds']:.0f} | {row['tip_error_max_percent']:.2f} "
                f"| {row['angle_error_max_degrees']:.2f} | {view} | {full:.1f} | {reduced:.1f} | {reduced / full:.1f} |"
            )
    (out / "live_reduced.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
