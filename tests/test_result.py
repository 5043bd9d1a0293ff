"""One result type for every run: a reach's frames are a Result whose steps carry the target columns,
and what the output draws or stores for an effect (the ground line, contact forces) is asked of the
effect, not found by its name."""

import dataclasses
import re

import numpy as np
import pytest

import taichi_pneuma as tp
from taichi_pneuma import limits
from taichi_pneuma.control.inverse import Reacher, frames
from taichi_pneuma.errors import PneumaInputError
from taichi_pneuma.fem import sizing
from taichi_pneuma.render.frames import Track
from taichi_pneuma.scene.targets import Target
from taichi_pneuma.terms.effects import Gravity, Ground, SelfContact

EXTRA = ["target", "target_x", "target_y", "target_angle", "tip_x", "tip_y", "tip_error", "descent"]


@dataclasses.dataclass(frozen=True)
class Floor(Ground):
    """The ground under another name: the output must still draw and store it."""

    name = "floor"


def test_reach_frames_are_one_result_with_the_target_columns():
    built = tp.reference_scene(max_area=0.01, chamber_points=64).build()
    reacher = Reacher(built)
    tips = [reacher.settle(np.array([q])).tip.copy() for q in (2.0, 3.0)]  # reachable: solved forward
    results = reacher.follow([Target(tuple(tips[0])), Target(tuple(tips[1]), angle=None)])
    run = frames(reacher, results)
    assert isinstance(run, tp.Result) and all(r.reached for r in results)
    assert len(run.steps) == len(run.positions) == len(results[0].path) + len(results[1].path) - 1
    history = run.history
    # the tip columns are where the stored positions put the tip, and the error its distance to the target
    tip = run.positions[:, built.mesh.tip].mean(axis=1)
    assert np.abs(np.column_stack([history["tip_x"], history["tip_y"]]) - tip).max() < 1e-12
    targets = np.column_stack([history["target_x"], history["target_y"]])
    assert np.abs(history["tip_error"] - np.hypot(*(tip - targets).T)).max() < 1e-12
    assert np.array_equal(targets[history["target"] == 1], np.tile(tips[1], ((history["target"] == 1).sum(), 1)))
    assert np.all(np.isnan(history["target_angle"]))
    for k in (0, 1):  # each target's last frame is within the tolerance of it
        assert history["tip_error"][np.flatnonzero(history["target"] == k)[-1]] <= 1e-3 * 3.5
    # the ramp's columns first, the reach's last: the history CSV's header
    assert run.history_csv().splitlines()[0].split(",")[-len(EXTRA) :] == EXTRA
    assert np.array_equal(Track.from_result(run).targets, targets)  # the video's cross follows them


def test_the_ground_line_is_asked_of_the_effect(tmp_path):
    scene = dataclasses.replace(tp.reference_scene(max_area=0.01, growth=1.2, steps=2), effects=(Floor(height=-1.0),))
    result = tp.simulate(scene)
    assert result.ground_height == -1.0 and Track.from_result(result).ground == -1.0
    assert result.contact_forces.shape == result.positions.shape  # its terms report contact forces
    _, npz = result.save_history(tmp_path)
    assert float(np.load(npz)["ground_height"]) == -1.0
    plain = dataclasses.replace(scene, effects=(Gravity(density=1.0),))
    assert tp.Result(plain.build(), [], np.zeros((0, 1, 2))).ground_height is None


def memory_estimate(scene) -> float:
    """sizing.check_scene's estimate of the memory a run needs, in GB (read off its refusal)."""
    with pytest.raises(PneumaInputError) as refused:
        sizing.check_scene(scene, max_triangles=1)
    return float(re.search(r"need about ([0-9.e+-]+) GB", str(refused.value)).group(1))


def test_the_limits_count_the_contact_forces_of_every_effect_that_has_them():
    """An effect with contact stores a force per vertex and step beside the positions: twice the per-step
    memory, whatever the effect's name; one without contact adds none. Self-contact adds its pairs: each
    node of the 128-node wall with each of the 126 edges not incident to it."""
    long = tp.reference_scene(max_area=0.01, steps=2001)
    estimate = {
        name: memory_estimate(dataclasses.replace(long, effects=effects))
        for name, effects in (
            ("none", ()),
            ("gravity", (Gravity(density=1.0),)),
            ("floor", (Floor(height=-1.0),)),
            ("self_contact", (SelfContact(),)),
        )
    }
    assert estimate["gravity"] == estimate["none"]
    assert estimate["floor"] > 1.5 * estimate["none"]
    pairs = 128 * 126 * limits.BYTES_PER_PAIR / 1e9
    assert estimate["self_contact"] == pytest.approx(estimate["floor"] + pairs, abs=2e-4)
