"""The cheap scene the tests share: a short coarse reference ramp (cy = 0.15, area ratio 2 in 3 steps, max
triangle area 0.01), the mesh many tests use, so Taichi's kernel cache and the mesh cache serve it."""

import taichi_pneuma as tp

SMALL_FLAGS = ["--max-area", "0.01", "--growth", "2", "--steps", "3", "--quiet"]  # small_scene's, for the apps


def small_scene(cy: float = 0.15):
    """The reference beam with its chamber at height cy, ramped to twice its area in 3 steps on a coarse mesh."""
    return tp.reference_scene(cy=cy, growth=2.0, steps=3, max_area=0.01)


def small_run():
    """small_scene()'s ramp, run: a Result."""
    return tp.simulate(small_scene())
