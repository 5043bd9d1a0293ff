"""A scene template: a Python file whose function `scene(**parameters)` returns the Scene of one design, so that an
optimisation varies what no scene key holds: a CAD part's dimensions (the function writes the part, a STEP or STL
file, and returns the scene that reads it), a generated shape, several keys tied together.

    # part.py
    import taichi_pneuma as tp

    def scene(wall=2.0, pitch=4.0):
        path = write_my_part(wall)          # e.g. build123d or gmsh's OpenCASCADE, exporting a STEP file
        return tp.load_scene("fiber_bending_step.toml").with_values({"body.file": path, ...})

    pneuma-optimize --template part.py --vary wall=1.5:3 --vary pitch=3:8 --minimize ...

The varied names are the function's keyword parameters, each with a default: scene() with no argument is the base
design (the goals' names are checked against it, and it is built here once before any design runs). The file's
text travels with each design (Task.template), so a worker process or a Ray node elsewhere runs it without the file:
whatever files it writes are written there, by the template, where it says (name them by the parameters, so that
designs do not overwrite each other's; a design's recorded scene.toml names them). `edits` (pneuma-optimize's
--set) are set on every design it returns: a coarser mesh for a trial run, say.

Running a template runs its code, as `python part.py` would: give only files you would run.
"""

from __future__ import annotations

import hashlib
import inspect
import os
from dataclasses import dataclass

from ..errors import PneumaInputError, require
from ..io.inputs import read_input

MAX_TEMPLATE_BYTES = 1_000_000


def function_of(source: str, name: str):
    """The `scene` function the template's source defines, run in a namespace of its own."""
    namespace: dict = {"__name__": "pneuma_template", "__file__": name}
    try:
        exec(compile(source, name, "exec"), namespace)  # noqa: S102 -- the user's own file, as `python part.py`
    except Exception as exc:  # noqa: BLE001 -- any failure of the user's code is one line
        raise PneumaInputError(f"--template {name}: running it failed: {type(exc).__name__}: {exc}") from None
    function = namespace.get("scene")
    require(callable(function), f"--template {name}: it defines no function scene(**parameters)")
    return function


def build(source: str, name: str, values: dict):
    """The Scene the template's scene(**values) returns (refused, in one line, if it is none)."""
    from ..scene.build import Scene

    function = function_of(source, name)
    try:
        scene = function(**values)
    except PneumaInputError:
        raise
    except Exception as exc:  # noqa: BLE001 -- a design the template cannot make is the design's error
        raise PneumaInputError(f"the template's scene({values}) failed: {type(exc).__name__}: {exc}") from None
    require(
        isinstance(scene, Scene), f"the template's scene() returned {type(scene).__name__}, not a taichi_pneuma Scene"
    )
    return scene


@dataclass(frozen=True)
class SceneTemplate:
    """A template file read (its text, name and SHA-256) and checked: it defines scene(), every parameter of which
    has a default."""

    source: str
    name: str  # the file's absolute path: the template's __file__
    edits: tuple = ()  # (dotted key, value) pairs set on every design it returns (pneuma-optimize's --set)

    @classmethod
    def read(cls, path: str | os.PathLike, edits: dict | None = None) -> SceneTemplate:
        """The template in the file at path; edits: {dotted key: value} set on each design."""
        name = os.fspath(path)
        require(name.endswith(".py"), f"--template {name}: a template is a Python file (.py)")
        source = read_input(name, MAX_TEMPLATE_BYTES, "--template").decode("utf-8", errors="replace")
        template = cls(source, os.path.abspath(name), tuple((edits or {}).items()))
        template.parameters()  # refuses a file without scene() or with a parameter without a default
        return template

    @property
    def sha256(self) -> str:
        return hashlib.sha256(self.source.encode()).hexdigest()

    def parameters(self) -> dict:
        """scene()'s keyword parameters and their defaults."""
        signature = inspect.signature(function_of(self.source, self.name))
        parameters = {}
        for p in signature.parameters.values():
            require(
                p.kind in (p.POSITIONAL_OR_KEYWORD, p.KEYWORD_ONLY) and p.default is not p.empty,
                f"--template {self.name}: scene()'s parameter {p.name!r} needs a default (scene() is the base design)",
            )
            parameters[p.name] = p.default
        return parameters

    def check(self, keys: list[str]) -> None:
        """Refuses a varied name that is not one of scene()'s parameters."""
        known = self.parameters()
        for key in keys:
            require(
                key in known,
                f"--vary {key}: the template's scene() has no parameter {key!r} (it has {', '.join(known) or 'none'})",
            )

    def build(self, values: dict):
        """The design of these parameter values: scene(**values), with the edits set."""
        scene = build(self.source, self.name, values)
        return scene.with_values(dict(self.edits)) if self.edits else scene
