"""The public Python API (re-exported by the package): load or make a scene, simulate it, get a Result.

import taichi_pneuma as tp
scene = tp.reference_scene(cy=0.15, E=2e4)   # or tp.load_scene("pneunet_finger"), scene.with_value("E", 2e4)
result = tp.simulate(scene, progress=True)
result.tip_deflection, result.tip_rotation, result.history["main.pressure"], result.area_ratio
result.save("out")                           # CSV, npz, JSON, scene TOML, plot PNG, ParaView PVD/VTU
result.video("out/x.mp4", size="480x192")    # frames rendered by Taichi
result.plot()                                # matplotlib figure with axes
"""

from __future__ import annotations

import os

from . import limits, runtime
from .result import Result
from .scene import scenefile
from .scene.build import BuiltScene, Scene
from .scene.shipped import find
from .solve.newton import NewtonOptions
from .solve.simulate import MAX_CUTS, RampStopped, run_schedule

__all__ = ["Result", "load_scene", "simulate"]


def load_scene(path: str | os.PathLike) -> Scene:
    """Read and validate a scene file: a path, or the name of a scene shipped with the package
    ("pneunet_finger", "bidirectional", "finger_on_ground", "reference_beam"; scene/shipped.py). Errors are
    one PneumaInputError naming the file and the key."""
    return scenefile.load_scene(find(path))


def simulate(
    scene: Scene | BuiltScene,
    *,
    tol: float = NewtonOptions.tol,
    max_iterations: int = NewtonOptions.max_iterations,
    max_cuts: int = MAX_CUTS,
    max_increments: int = limits.MAX_INCREMENTS,
    max_triangles: int | None = None,
    progress=None,
    stop=None,
) -> Result:
    """Run the scene's schedule (meshing it first unless it is already built) and return its Result.

    tol: Newton tolerance on |gradient| / force scale; max_iterations per solve; max_cuts: halvings of an
    increment that does not converge; max_increments: a schedule of more is refused (PneumaInputError), as
    the commands' --max-increments does; max_triangles: a mesh (or self-contact's pairs) worth more linear
    triangles is refused (PneumaInputError), the mesher stopping at it, as the commands' --max-triangles does
    (None: no limit; a BuiltScene was meshed already). progress: True shows a progress bar (tqdm) while it
    solves; a function progress(step_record, positions, contact_force) is called after every increment instead
    (positions and contact forces (n, d), d = 2 or 3, as a row of Result.positions and Result.contact_forces).
    stop() is asked after every increment but the last and before every Newton iteration, ending the run
    with tp.RampInterrupted (the increments done) when it returns True. Raises tp.RampFailed when an increment
    finds no equilibrium; both carry .result, the Result of the steps done. Initialises Taichi on the CPU unless
    tp.init chose a backend."""
    limits.check_increments(
        scene.scene.increments if isinstance(scene, BuiltScene) else scene.increments,
        max_increments,
        "simulate's max_increments",
    )
    runtime.ensure_initialised()
    built = scene if isinstance(scene, BuiltScene) else scene.build(limits.Budget(max_triangles))
    options = NewtonOptions(tol=tol, max_iterations=max_iterations)
    try:
        if progress is not True:
            return Result.of(
                run_schedule(built, options=options, progress=progress or None, max_cuts=max_cuts, stop=stop)
            )
        from tqdm import tqdm

        with tqdm(total=built.scene.increments + 1, desc=built.scene.name, unit="step", leave=False) as bar:
            return Result.of(
                run_schedule(built, options=options, progress=lambda *_: bar.update(), max_cuts=max_cuts, stop=stop)
            )
    except RampStopped as stopped:
        stopped.result = Result.of(stopped.result)
        raise
