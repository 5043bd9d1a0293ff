"""The cheap scene the tests share: a short coarse reference ramp (cy = 0.15, area ratio 2 in 3 steps, max
triangle area 0.01), the mesh many tests use, so Taichi's kernel cache and the mesh cache serve it."""

import taichi_pneuma as tp

SMALL_FLAGS = ["--max-area", "0.01", "--growth", "2", "--steps", "3", "--quiet"]  # small_scene's, for the apps


def small_scene(cy: float = 0.15):
    """The reference beam with its chamber at height cy, ramped to twice its area in 3 steps on a coarse mesh."""
    return tp.reference_scene(cy=cy, growth=2.0, steps=3, max_area=0.01)


def grounded_beam(order: int, max_area: float, seed: int):
    """A coarse beam of this element order on the ground under gravity (16 chamber points), its chamber commanded to
    1.5x, in a random state (fd.random_state of scale 0.01): (the built scene, the state u) for derivative tests."""
    from fd import random_state

    from taichi_pneuma.scene.build import Scene
    from taichi_pneuma.terms.effects import Gravity, Ground

    scene = tp.reference_scene(cy=0.15, chamber_points=16, max_area=max_area, order=order)
    effects = (Gravity(2.0), Ground(-0.45, dhat=0.06, stiffness=50.0))
    built = Scene(
        geometry=scene.geometry,
        controls=scene.controls,
        increments=scene.increments,
        material=scene.material,
        effects=effects,
    ).build()
    built.set_commands([1.5])
    return built, random_state(built, scale=0.01, seed=seed)


def small_run():
    """small_scene()'s ramp, run: a Result."""
    return tp.simulate(small_scene())
