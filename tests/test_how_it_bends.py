"""The reference beam's tip first rises, then curls down (docs: How an actuator bends): the thin wall over the chamber
bulges and draws the top face's ends together before it stretches. Checked on the reference mesh."""

import numpy as np
import pytest

import taichi_pneuma as tp


def end_to_end(result, y: float) -> np.ndarray:
    """Per step: the distance between the end corners of the face at rest height y, over its rest value."""
    rest = result.mesh.vertices
    ids = np.flatnonzero(np.isclose(rest[:, 1], y))
    left, right = ids[np.argmin(rest[ids, 0])], ids[np.argmax(rest[ids, 0])]
    length = np.linalg.norm(result.positions[:, right] - result.positions[:, left], axis=1)
    return length / length[0]


@pytest.fixture(scope="module")
def high():
    return tp.simulate(tp.reference_scene(cy=0.15))


def test_the_high_chambers_tip_rises_first_then_ends_at_the_reference_figure(high):
    tip = high.history["tip_dy"]
    top = int(np.argmax(tip))
    assert tip[top] > 0.2 and 5 <= top <= 15  # a rise of most of the final curl's size, early in the ramp
    assert np.all(np.diff(tip[: top + 1]) > 0) and np.all(np.diff(tip[top:]) < 0)  # up, then down, no wobble
    assert tip[-1] == pytest.approx(-0.2790, abs=0.003)  # SPEC's figure


def test_the_tip_is_highest_when_the_top_face_is_shortest_and_level_when_both_faces_are_equal(high):
    tip, top, bottom = high.history["tip_dy"], end_to_end(high, 0.4), end_to_end(high, -0.4)
    shortest = int(np.argmin(top))
    assert top[shortest] < 0.98 and bottom[shortest] > 1.0  # the top face shortened, the bottom lengthened
    assert abs(shortest - int(np.argmax(tip))) <= 1
    equal = shortest + int(np.argmax(top[shortest:] >= bottom[shortest:]))
    level = int(np.argmax(tip < 0))  # the first step below the start
    assert abs(equal - level) <= 1
    assert top[-1] - bottom[-1] > 0.02  # at the end the top is the longer side: the beam curls down
