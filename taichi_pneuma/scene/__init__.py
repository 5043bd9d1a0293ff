"""scene: a scene as data and what reads and writes it. build.py (the Scene, its validation, and its builder into an
energy model), region.py (material regions), schedule.py (the chambers' command ramps and controls), targets.py (tip
targets of a reach); the scene file: fileformat.py (a format declared as a tree of entries: reading, writing, the key
reference), dotted_edits.py (editing by dotted keys), scene_keys.py, shape_keys.py, material_keys.py,
obstacle_keys.py and reinforcement_keys.py (the scene's key tables, their units and checks), scenefile.py (reading
and writing a file), shipped.py (the scenes that come with the package)."""

from .build import BuiltScene, Material, Region, Scene, reference_scene

__all__ = ["BuiltScene", "Material", "Region", "Scene", "reference_scene"]
