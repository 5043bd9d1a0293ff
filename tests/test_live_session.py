"""The live state behind the browser page (realtime/session.py LiveSession), without a page: playing a scene's
schedule live ends where the ramp (tp.simulate) ends, a dragged target is reached by the chambers, the fields shown
are those of the state, and the save button's files hold the equilibria kept."""

import numpy as np
import pytest

import taichi_pneuma as tp
from taichi_pneuma.errors import PneumaInputError
from taichi_pneuma.realtime.session import NO_EQUILIBRIUM, LiveSession

SCENE = "pneunet_finger"  # 641 nodes, six pressure chambers, a schedule out to 900 and back over 18 increments


@pytest.fixture(scope="module")
def scene():
    tp.init("cpu")
    return tp.load_scene(SCENE)


def settle(session, max_frames=400):
    """Frames until the session stops changing (its state an equilibrium at its commands, or stuck)."""
    for _ in range(max_frames):
        if not session.advance() and not session.playing and session.equilibrium.converged:
            return
    raise AssertionError(f"no rest after {max_frames} frames: {session.figures()}")


def test_playing_the_schedule_live_reaches_the_ramps_peak_and_ends_where_the_ramp_ends(scene):
    ramp = tp.simulate(scene)
    session = LiveSession(scene)
    session.play(True)
    peak = None
    for _ in range(3000):
        session.advance()
        if session.schedule_step == 10 and session.equilibrium.converged and peak is None:
            peak = session.figures()["tip"]
        if not session.playing and session.equilibrium.converged:
            break
    assert session.schedule_step == scene.schedule.increments
    length = np.ptp(session.mesh.vertices[:, 0])
    # the ramp's step 10 is its peak pressure (900 in every chamber); live and ramp settle to the same tolerance
    assert np.allclose(peak, ramp.steps[10].tip, atol=1e-4 * length), (peak, ramp.steps[10].tip)
    assert np.allclose(session.figures()["tip"], ramp.steps[-1].tip, atol=1e-4 * length)
    assert session.figures()["pressures"] == pytest.approx(np.zeros(6), abs=1e-6)
    # every quarter increment played was kept as a settled equilibrium (rest first), but for the hold at the peak
    # (steps 10 to 12): its 8 quarter increments repeat the peak's commands, kept once
    assert len(session.steps) == 4 * scene.schedule.increments + 1 - 8


def test_a_target_dragged_to_where_known_commands_put_the_tip_is_reached(scene):
    commands = np.array([600.0, 600.0, 600.0, 300.0, 300.0, 300.0])
    known = LiveSession(scene)
    for j, value in enumerate(commands):
        known.command(j, value)
    settle(known)
    tip = known.mesh.vertices[known.mesh.tip].mean(axis=0) + known.figures()["tip"]
    session = LiveSession(scene)
    settle(session)
    session.aim(tip)
    session.advance()
    length = np.ptp(session.mesh.vertices[:, 0])
    reached = session.mesh.vertices[session.mesh.tip].mean(axis=0) + session.figures()["tip"]
    assert np.linalg.norm(reached - tip) < 2e-3 * length
    assert session.reached is not None and session.reached < 2e-3 * length
    # the page's sliders now show the commands the reach found, and the state is an equilibrium at them
    assert session.equilibrium.converged and np.array_equal(session.commands, session.equilibrium.commands)


def test_the_fields_shown_at_rest_are_those_of_an_undeformed_body_and_grow_with_pressure(scene):
    session = LiveSession(scene)
    settle(session)
    assert session.field("none") is None
    assert session.field("max_stretch") == pytest.approx(1.0, abs=1e-6)
    assert session.field("det_F") == pytest.approx(1.0, abs=1e-6)
    assert session.field("von_mises") == pytest.approx(0.0, abs=1e-6)
    assert session.field("displacement") == pytest.approx(0.0, abs=1e-12)
    session.command(0, 900.0)
    settle(session)
    stretch = session.field("max_stretch")
    assert stretch.shape == (session.mesh.n_vertices,) and stretch.max() > 1.05 and stretch.min() >= 1.0 - 1e-9
    # a node's value is the mean of its elements' values: checked for the node with the largest stretch
    from taichi_pneuma.fem.fields import element_fields

    cells = element_fields(session.mesh.vertices, session.positions(), session.mesh.elements)["max_stretch"]
    node = int(np.argmax(stretch))
    assert stretch[node] == pytest.approx(cells[np.any(session.mesh.elements == node, axis=1)].mean())
    with pytest.raises(PneumaInputError, match="field 'strain' is not one of none, max_stretch"):
        session.field("strain")


def test_saving_writes_the_kept_equilibria_as_a_ramps_files(scene, tmp_path):
    session = LiveSession(scene)
    with pytest.raises(PneumaInputError, match="nothing to save yet"):
        session.save(tmp_path, "live")
    settle(session)
    session.command(2, 450.0)
    settle(session)
    paths = session.save(tmp_path, "live")
    names = {p.name for p in paths}
    assert {"live_history.csv", "live_states.npz", "live_summary.json", "live_scene.toml"} <= names
    states = np.load(tmp_path / "live_states.npz")
    assert states["positions"].shape == (2, session.mesh.n_vertices, 2)
    assert states["pressure"][1, 2] == pytest.approx(450.0) and states["pressure"][0, 2] == pytest.approx(0.0)
    assert np.allclose(states["positions"][-1], session.positions())


def test_a_live_state_whose_chamber_wall_crosses_itself_is_never_shown_or_kept_as_an_equilibrium():
    """The reference chamber commanded to 0.05 of its area: Newton converges to a wall through itself (an exact
    equilibrium of the discrete energy, no physical state), which a ramp refuses (test_trust_runtime). Live, the
    same state is no equilibrium either: it is never kept, the session cuts back toward the command and, past its
    cuts, says there is none at that command and shows the last equilibrium, a simple wall part of the way closed.
    Commanded so before any frame, the way back is the body at rest."""
    from test_trust_runtime import crosses

    scene = tp.reference_scene(growth=0.05, steps=6, max_area=0.005)
    for first in (0.5, None):
        session = LiveSession(scene)
        rest = session.commands[0]
        if first is not None:
            session.command(0, first * rest)
            settle(session)
        session.command(0, 0.05 * rest)
        for _ in range(600):
            session.advance()
            if session.figures()["state"] == NO_EQUILIBRIUM:
                break
        assert session.figures()["state"] == NO_EQUILIBRIUM, session.figures()
        loop = session.built.chambers[0].loop_vertices
        assert not crosses(session.positions()[loop])  # the state shown: the last equilibrium
        assert not any(crosses(positions[loop]) for positions in session._positions)
        assert session.figures()["pressures"][0] > 0  # suction: the state shown is part of the way closed
        assert len(session.steps) == (first is not None)  # the equilibrium at 0.5 kept; none at the failed command
