"""Frame rate of live inverse control (interactive.follow_mouse) while a target is dragged.

    xvfb-run -a python benchmarks/live_reach.py [--renderer gui|ggui] [--max-area 0.0012] [--frames 120] [--tol 1e-6]

bidirectional.toml re-meshed at the reference density (max area 0.0012, ~1,600 vertices). The
drag is scripted (the canvas's mouse query replaced): the cursor follows the tip points of a loop
of commands around the centre of the command box (reachable targets, solved forward beforehand),
one step per frame with the button held, as a hand would drag. Prints follow_mouse's summary: the
frames per second over the frames that re-solved a moved target (the first one, warm-up, left out).
"""

import argparse
import dataclasses
from pathlib import Path

import numpy as np

from taichi_pneuma import runtime
from taichi_pneuma.control.inverse import Reacher, command_bounds
from taichi_pneuma.realtime.interactive import fixed_view, follow_mouse
from taichi_pneuma.render.canvases import GGUICanvas, GUICanvas
from taichi_pneuma.render.frames import FrameRenderer, Track
from taichi_pneuma.scene.scenefile import load_scene
from taichi_pneuma.solve.newton import NewtonOptions

SCENE = Path(__file__).resolve().parent.parent / "taichi_pneuma" / "scenes" / "bidirectional.toml"


def drag_path(scene, frames: int, size, radius: float = 0.3) -> list[tuple[float, float]]:
    """Canvas positions (normalised) of the tip points of a loop of commands of `radius` (a fraction of
    the bounds) around the box centre, mapped as follow_mouse's window maps them."""
    built = scene.build()
    reacher = Reacher(built)
    span = reacher.hi - reacher.lo
    angles = np.linspace(0, 2 * np.pi, frames)
    tips = [reacher.settle(reacher.lo + span * (0.5 + radius * np.array([np.cos(a), np.sin(a)]))).tip for a in angles]
    track = Track(built.mesh, built.mesh.vertices[None], np.ones((1, 2)), np.zeros((1, 2)), np.zeros(1))
    view = FrameRenderer([track], *size, trace=False, backend="gui", bounds=fixed_view(built.mesh), log=lambda *_: None)
    return [tuple(view.to_canvas(0, tip)) for tip in tips]


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--renderer", default="gui", choices=["gui", "ggui"])
    p.add_argument("--max-area", type=float, default=0.0012)
    p.add_argument("--frames", type=int, default=120)
    p.add_argument("--size", default="960x384")
    p.add_argument("--tol", type=float, default=NewtonOptions.tol, help="Newton tolerance of the forward solves")
    args = p.parse_args()
    runtime.init("cpu")
    size = tuple(int(v) for v in args.size.split("x"))
    scene = load_scene(SCENE)
    scene = dataclasses.replace(scene, geometry=dataclasses.replace(scene.geometry, max_area=args.max_area))
    path = iter(drag_path(scene, args.frames, size))
    canvas = GGUICanvas if args.renderer == "ggui" else GUICanvas
    canvas.mouse = lambda self: (*next(path, (0.5, 0.5)), True)
    print(f"mesh: {scene.build().mesh.n_vertices} vertices")
    print(
        follow_mouse(
            scene,
            command_bounds(scene),
            size,
            args.renderer,
            newton=NewtonOptions(tol=args.tol),
            max_frames=args.frames,
        )
    )


if __name__ == "__main__":
    main()
