"""taichi-pneuma: soft pneumatic actuators (hyperelastic FEM, chambers, projected Newton in Taichi).

    import taichi_pneuma as tp
    scene = tp.load_scene("bidirectional")           # a shipped scene by name or a .toml path; or tp.reference_scene()
    scene = scene.with_value("E", 2e4)                # a short name or any dotted scene-file key, validated
    result = tp.simulate(scene, progress=True)        # a progress bar while it solves
    print(result.tip_deflection, result.tip_rotation, result.history["tip_dy"])
    result.save("out"); result.video("out/run.mp4"); result.plot()
    view = tp.live("pneunet_finger")                  # in Jupyter: the scene live, sliders and all (the [web] extra)

Taichi is initialised on the CPU by the first simulate() unless tp.init("cuda"), ... chose a backend.
The names below are imported on first use, so `import taichi_pneuma` (and every app's --help) starts
without loading Taichi.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING

__version__ = "0.1.0"  # the one place the version is written: pyproject.toml reads it

from .signals import quiet_while_loading  # noqa: E402

quiet_while_loading()  # a command's Ctrl-C while its modules load: one line, no traceback

# public name -> the module that defines it
_EXPORTS = {
    "PneumaInputError": ".errors",
    "RampFailed": ".solve.simulate",
    "RampInterrupted": ".solve.simulate",
    "Result": ".api",
    "Scene": ".scene",
    "init": ".runtime",
    "live": ".realtime.web",
    "load_scene": ".api",
    "optimize": ".study.optimize",
    "reference_scene": ".scene",
    "simulate": ".api",
}
__all__ = [
    "PneumaInputError",
    "RampFailed",
    "RampInterrupted",
    "Result",
    "Scene",
    "__version__",
    "init",
    "live",
    "load_scene",
    "optimize",
    "reference_scene",
    "simulate",
]

if TYPE_CHECKING:
    from .api import Result, load_scene, simulate
    from .errors import PneumaInputError
    from .realtime.web import live
    from .runtime import init
    from .scene.build import Scene, reference_scene
    from .solve.simulate import RampFailed, RampInterrupted


def __getattr__(name: str):
    if name not in _EXPORTS:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(_EXPORTS[name], __name__), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *_EXPORTS})
