"""Interactive mode: a window with a slider for the commanded chamber area; moving it re-solves live.

Each time the slider's value changes, the equilibrium at the new commanded area is solved, warm-started
from the one on screen, and the beam panel (mesh, chamber, clamp, overlay) is redrawn. Needs a display.
follow_mouse is inverse control live: drag the target, the chambers follow.
"""

from __future__ import annotations

import dataclasses
import time

import numpy as np

from ..limits import Budget
from ..render.canvases import open_canvas
from ..render.frames import FrameRenderer, Track
from ..scene.build import Scene
from ..solve.newton import NewtonOptions, NewtonSolver
from .equilibrium import LIVE_TOL, LiveEquilibrium


def fixed_view(mesh) -> tuple[np.ndarray, np.ndarray]:
    """The world box a live window shows: the rest body with room for the curl of a full ramp
    (a third of the length up and down)."""
    lo, hi = mesh.vertices.min(axis=0), mesh.vertices.max(axis=0)
    room = np.array([0.05, 0.35]) * (hi[0] - lo[0])
    return lo - room, hi + room


def explore(
    scene: Scene,
    growth: float,
    size: tuple[int, int],
    backend: str = "auto",
    options: NewtonOptions | None = None,
    max_frames: int | None = None,
    budget: Budget = Budget(),
) -> dict:
    """Run the window until it is closed (or for max_frames frames); return {'all_converged', 'solves'}.

    The slider commands the area ratio of the scene's first chamber (area control); the scene is built in the
    budget (limits.Budget)."""
    built = scene.build(budget)
    chamber = built.chambers[0]
    mesh, solver = built.mesh, NewtonSolver(built.model, options)
    canvas = open_canvas(*size, backend, show=True)
    bounds = fixed_view(mesh)
    u, ratio = np.zeros_like(mesh.vertices), None
    renderer: FrameRenderer | None = None
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
            track = Track(
                mesh,
                (mesh.vertices + u)[None],
                np.array([[chamber.area() / chamber.rest_area]]),
                np.array([[chamber.pressure()]]),
                np.array([tip]),
                "interactive",
            )
            renderer = FrameRenderer([track], trace=False, canvas=canvas, bounds=bounds)
            print(
                f"  area x{ratio:.3f}: p = {track.pressure[0, 0]:.2f}, tip dy = {tip:+.4f}, "
                f"{record.iterations} Newton it, converged {record.converged}",
                flush=True,
            )
        if renderer is not None:  # (the first frame has solved)
            canvas.show_image(renderer.frame(0))
        canvas.show()
        frames += 1
    return {"all_converged": bool(converged), "solves": solves}


def follow_mouse(
    scene: Scene,
    bounds,
    size: tuple[int, int],
    backend: str = "auto",
    options=None,
    newton: NewtonOptions | None = None,
    target=None,
    max_frames: int | None = None,
    budget: Budget = Budget(),
) -> dict:
    """Inverse control live: drag the target (a red cross) with the left mouse button and the chambers
    follow, re-solved (inverse.Reacher.reach, warm-started, without restarts: an unreachable target
    leaves the closest pose near the last one) on every move; a slider per chamber (bottom rows)
    commands it directly. Runs until the window is closed (or for max_frames frames); the scene is built in the
    budget (limits.Budget).

    Returns {'all_converged': every reach reached its target, 'reaches', 'direct', 'frames',
    'drag_fps': frames per second over the frames that re-solved a moved target, after the first
    (warm-up), 'ms_per_reach', 'forward_solves_per_reach'}."""
    from ..control.inverse import Reacher, ReachOptions
    from ..scene.targets import Target

    built = scene.build(budget)
    # a drag follows the closest pose nearby; one factorisation per frame
    options = dataclasses.replace(options or ReachOptions(), restarts=0, reuse_factor=True)
    reacher = Reacher(built, bounds, options, newton or NewtonOptions(tol=LIVE_TOL))
    mesh = built.mesh
    canvas = open_canvas(*size, backend, show=True)
    target = np.array(target.tip if target is not None else reacher.pose.tip, float)
    track = Track(
        mesh,
        (mesh.vertices + reacher.pose.u)[None],
        np.ones((1, len(built.chambers))),
        np.zeros((1, len(built.chambers))),
        np.zeros(1),
        "drag the red cross",
        targets=target[None].copy(),
    )
    renderer = FrameRenderer([track], trace=False, canvas=canvas, bounds=fixed_view(mesh))
    strip = len(built.chambers) * canvas.slider_row_px / canvas.height  # the sliders' rows at the bottom
    reached, reaches, direct, frames, drag_seconds, solves = True, [], 0, 0, [], 0
    print(
        f"interactive: drag the target with the left mouse button; {len(built.chambers)} sliders below; "
        f"close the window to quit"
    )

    def show(pose):
        track.states[0] = mesh.vertices + pose.u
        track.targets[0] = target
        for j, chamber in enumerate(built.chambers):
            track.area_ratio[0, j], track.pressure[0, j] = chamber.area() / chamber.rest_area, chamber.pressure()
        track.tip_dy[0] = pose.tip[1] - mesh.vertices[mesh.tip, 1].mean()

    show(reacher.pose)
    while canvas.running and (max_frames is None or frames < max_frames):
        start = time.perf_counter()
        q = reacher.pose.commands
        moved = np.array(
            [
                canvas.slider(name, value, low, high, row=j)
                for j, (name, value, low, high) in enumerate(zip(reacher.names, q, reacher.lo, reacher.hi))
            ]
        )
        x, y, pressed = canvas.mouse()
        pointed = renderer.to_world(0, np.array([x, y]))
        dragged = pressed and y > strip and not np.array_equal(pointed, target)
        if np.any(np.abs(moved - q) > 1e-6 * (reacher.hi - reacher.lo)):  # sliders hold float32 values
            show(reacher.settle(moved))
            direct += 1
        elif dragged:
            target = pointed
            result = reacher.reach(Target(tuple(target)))
            reached &= result.reached
            solves += result.forward_solves
            reaches.append(result.seconds)
            show(result.pose)
        canvas.show_image(renderer.frame(0))  # shapes, then the text drawn onto the read-back image
        canvas.show()
        frames += 1
        if dragged and len(reaches) > 1:  # a frame that re-solved a moved target, after the first (warm-up)
            drag_seconds.append(time.perf_counter() - start)
    summary = {
        "all_converged": bool(reached),
        "reaches": len(reaches),
        "direct": direct,
        "frames": frames,
        "commands": reacher.pose.commands.tolist(),
        "tip": reacher.pose.tip.tolist(),
        "target": target.tolist(),
        "drag_fps": 1 / float(np.mean(drag_seconds)) if drag_seconds else None,
        "ms_per_reach": 1000 * float(np.mean(reaches)) if reaches else None,
        "forward_solves_per_reach": solves / len(reaches) if reaches else None,
    }
    print(
        f"interactive: {summary['reaches']} reaches, {direct} direct commands, {frames} frames; "
        + (
            f"while dragging {summary['drag_fps']:.1f} frames/s, {summary['ms_per_reach']:.1f} ms and "
            f"{summary['forward_solves_per_reach']:.2f} forward solves per reach"
            if drag_seconds
            else "no drag"
        )
    )
    return summary


def chamber_sliders(scene: Scene) -> list:
    """A slider per chamber over the commands its schedule drives (ChamberControl.bounds when given, else the
    kind's default_bounds: the rest command and every keyframe value), starting at the rest command."""
    from .interactive3d import Slider

    sliders = []
    for name, control in zip(scene.chamber_names, scene.controls):
        kind = control.kind
        low, high = control.bounds or kind.default_bounds([v for _, v in control.schedule.keyframes])
        if high <= low:  # a chamber held at one command: a slider from there to twice as far from zero
            high = low + max(abs(low), 1.0)
        sliders.append(Slider(name, low, high, min(max(kind.rest, low), high)))
    return sliders


def explore_solid(
    scene: Scene,
    size: tuple[int, int],
    options: NewtonOptions | None = None,
    spin: float = 0.0,
    max_frames: int | None = None,
    budget: Budget = Budget(),
    reduced=None,
) -> dict:
    """The live window of a 3D scene (interactive3d.explore_3d): a slider per chamber (chamber_sliders); each
    frame takes a Newton step toward the equilibrium at the commands on screen (LiveEquilibrium; the panel
    shows the residual; with `reduced`, the file of a reduced model of the scene, reduced.ReducedOrFull: a reduced
    step inside its training range, the panel naming the model and the full residual of each settled state); the
    camera orbits by mouse drag (and `spin` degrees per frame). Returns explore_3d's summary with 'all_converged'
    (the state shown last is the equilibrium at the last commands) and 'residual'. The scene is built in the budget
    (limits.Budget)."""
    from ..reduce.store import load_reduced
    from ..render.frames3d import surface_triangles
    from .interactive3d import explore_3d
    from .reduced import ReducedOrFull

    built = scene.build(budget)
    mesh = built.mesh
    live = LiveEquilibrium(built, options) if reduced is None else ReducedOrFull(load_reduced(reduced, built), options)
    outer, walls, _ = surface_triangles(mesh)

    def solve(commands):
        live.frame(commands)
        volumes = ", ".join(f"x{ratio:.2f}" for ratio in live.measures())
        tip = live.u[mesh.tip].mean(axis=0)
        lines = [
            f"volume {volumes}",
            f"tip dy {tip[1]:+.4f} dz {tip[2]:+.4f}",
            f"residual {live.residual:.1e} ({live.state}, {live.iterations} Newton it)",
        ]
        return mesh.vertices + live.u, lines + ([live.model_line] if isinstance(live, ReducedOrFull) else [])

    summary = explore_3d(
        solve, chamber_sliders(scene), mesh.vertices, outer, walls, size, spin=spin, max_frames=max_frames
    )
    return {**summary, "all_converged": live.converged, "residual": live.residual}
