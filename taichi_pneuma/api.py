"""The public Python API (re-exported by the package): simulate a scene, get a Result to look at.

    import taichi_pneuma as tp
    scene = tp.reference_scene(cy=0.15)          # or tp.load_scene("x.toml"), scene.with_value(key, value)
    result = tp.simulate(scene)
    result.tip_deflection, result.history["main.pressure"], result.area_ratio
    result.save("out")                           # CSV, npz, JSON, scene TOML, plot PNG, ParaView PVD/VTU
    result.video("out/x.mp4")                    # frames rendered by Taichi
    result.plot()                                # matplotlib figure with axes
"""

from __future__ import annotations

from . import runtime
from .scene import BuiltScene, Scene
from .solve.newton import NewtonOptions
from .solve.result import Result
from .solve.simulate import MAX_CUTS, run_schedule

__all__ = ["Result", "simulate"]


def simulate(scene: Scene | BuiltScene, *, tol: float = NewtonOptions.tol,
             max_iterations: int = NewtonOptions.max_iterations, max_cuts: int = MAX_CUTS,
             progress=None, stop=None) -> Result:
    """Run the scene's schedule (meshing it first unless it is already built) and return its Result.

    tol: Newton tolerance on |gradient| / force scale; max_iterations per solve; max_cuts: halvings of an
    increment that does not converge. progress(step_record, positions, contact_force) is called after
    every increment; stop() after every increment but the last, ending the run with RampInterrupted when
    it returns True. Raises RampFailed when an increment finds no equilibrium; both carry .result, the
    Result of the steps done. Initialises Taichi on the CPU unless runtime.init chose a backend."""
    runtime.ensure_initialised()
    built = scene if isinstance(scene, BuiltScene) else scene.build()
    return run_schedule(built, options=NewtonOptions(tol=tol, max_iterations=max_iterations), progress=progress,
                        max_cuts=max_cuts, stop=stop)
