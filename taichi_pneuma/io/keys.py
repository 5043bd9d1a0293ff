"""Short names of the scene-file keys the reference beam's flags set, accepted wherever a dotted key is
(Scene.with_value(s), --set, the sweep's --vary): `scene.with_value("E", 2e4)` is
`scene.with_value("material.E", 2e4)`. Plain data: the apps' --help imports it without loading Taichi."""

SHORT_KEYS = {
    "cy": "chambers[0].center[1]",
    "cx": "chambers[0].center[0]",
    "E": "material.E",
    "nu": "material.nu",
    "k": "chambers[0].stiffness",
    "max_area": "mesh.max_area",
}


def dotted(key: str) -> str:
    """The dotted scene-file key a short name stands for (any other key as it is)."""
    return SHORT_KEYS.get(key, key)
