"""taichi-pneuma: soft pneumatic actuators in 2D (neo-Hookean FEM, chambers, projected Newton in Taichi).

    import taichi_pneuma as tp
    scene = tp.load_scene("assets/scenes/bidirectional.toml")    # or tp.reference_scene(cy=0.15)
    scene = scene.with_value("material.E", 2e4)                   # any dotted scene-file key, validated
    result = tp.simulate(scene)
    print(result.tip_deflection, result.history["tip_dy"])
    result.save("out"); result.video("out/run.mp4"); result.plot()

Taichi is initialised on the CPU by the first simulate() unless tp.init("cuda"), ... chose a backend.
"""

from .signals import quiet_while_loading

quiet_while_loading()  # a command's Ctrl-C while the modules below load: one line, no traceback

from .api import Result, simulate
from .errors import PneumaInputError
from .io.scenefile import load_scene
from .runtime import init
from .scene import Scene, reference_scene
from .solve.simulate import RampFailed

__all__ = ["PneumaInputError", "RampFailed", "Result", "Scene", "init", "load_scene", "reference_scene", "simulate"]
