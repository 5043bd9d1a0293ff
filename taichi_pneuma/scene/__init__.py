"""scene: a scene as data and what reads and writes it. build.py (the Scene, its validation, and its builder into an
energy model), schedule.py (the chambers' command ramps), targets.py (tip targets of a reach), schema.py and
sceneformat.py (the TOML keys, their units and checks), scenefile.py (reading a file), shipped.py (the scenes that
come with the package)."""

from .build import BuiltScene, Material, Region, Scene, reference_scene

__all__ = ["BuiltScene", "Material", "Region", "Scene", "reference_scene"]
