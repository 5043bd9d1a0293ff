"""Interactive mode: a window with a slider for the commanded chamber area; moving it re-solves live.

Each time the slider's value changes, the equilibrium at the new commanded area is solved, warm-started
from the one on screen, and the beam panel (mesh, chamber, clamp, overlay) is redrawn. Needs a display.
"""

from __future__ import annotations

import numpy as np

from .newton import NewtonOptions, NewtonSolver
from .render import FrameRenderer, Track, open_canvas
from .scene import Scene


def explore(scene: Scene, growth: float, size: tuple[int, int], backend: str = "auto",
            options: NewtonOptions | None = None, max_frames: int | None = None) -> dict:
    """Run the window until it is closed (or for max_frames frames); return {'all_converged', 'solves'}.

    The slider commands the area ratio of the scene's first chamber (area control)."""
    built = scene.build()
    chamber = built.chambers[0]
    mesh, solver = built.mesh, NewtonSolver(built.model, options)
    canvas = open_canvas(*size, backend, show=True)
    # Fixed view: the rest beam with room for the curl of a full ramp (a third of the length up and down).
    lo, hi = mesh.vertices.min(axis=0), mesh.vertices.max(axis=0)
    reach = np.array([0.05, 0.35]) * (hi[0] - lo[0])
    bounds = (lo - reach, hi + reach)
    u, ratio, renderer = np.zeros_like(mesh.vertices), None, None
    converged, solves, frames = True, 0, 0
    print(f"interactive: drag the slider (commanded area / rest area, 1 .. {growth:g}); close the window to quit")
    while canvas.running and (max_frames is None or frames < max_frames):
        value = canvas.slider("area / rest", 1.0 if ratio is None else ratio, 1.0, growth)
        if value != ratio:
            ratio = value
            built.set_commands(np.array([ratio]))
            u, record = solver.solve(u)
            converged &= record.converged
            solves += 1
            tip = u[mesh.tip, 1].mean()
            track = Track(mesh, (mesh.vertices + u)[None], np.array([[chamber.area() / chamber.rest_area]]),
                          np.array([[chamber.pressure()]]), np.array([tip]), "interactive")
            renderer = FrameRenderer([track], trace=False, canvas=canvas, bounds=bounds)
            print(f"  area x{ratio:.3f}: p = {track.pressure[0, 0]:.2f}, tip dy = {tip:+.4f}, "
                  f"{record.iterations} Newton it, converged {record.converged}", flush=True)
        canvas.show_image(renderer.frame(0))
        canvas.show()
        frames += 1
    return {"all_converged": bool(converged), "solves": solves}
