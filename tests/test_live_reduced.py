"""The live views on a reduced model (realtime/reduced.py; pneuma-serve --reduced, pneuma-inflate --interactive
--reduced, tp.live(reduced=...)): inside the training range a frame is a reduced Newton step and a resting slider
settles at the reduced equilibrium, with the full residual of that state shown; outside it the full model solves;
a model of another scene is refused with one line.

On the coarse reference beam of tests/test_reduced.py (its area ramp 1 .. 2.5), with slider bounds 1 .. 3 so that a
slider can leave the training range."""

import numpy as np
import pytest

import taichi_pneuma as tp
from taichi_pneuma.realtime.session import LiveSession
from taichi_pneuma.reduce.solve import equilibrium
from taichi_pneuma.reduce.store import save_reduced
from taichi_pneuma.reduce.train import train
from taichi_pneuma.solve.newton import NewtonOptions, NewtonSolver
from taichi_pneuma.solve.simulate import settle as settle_full

COARSE = {
    "mesh.max_area": 0.01,
    "chambers[0].points": 32,
    "schedule.increments": 7,
    "chambers[0].keyframes": [[0, 1.0], [7, 2.5]],
    "chambers[0].bounds": [1.0, 3.0],
}


@pytest.fixture(scope="module")
def trained(tmp_path_factory):
    tp.init("cpu")
    scene = tp.load_scene("reference_beam").with_values(COARSE)
    training = train(scene.build(), modes=8, samples=6, options=NewtonOptions(tol=1e-9))
    path = tmp_path_factory.mktemp("reduced") / "beam_reduced.npz"
    save_reduced(path, training.model, training.singular_values)
    return scene, training.model, path


def settle(session, max_frames=200) -> int:
    for frame in range(max_frames):
        if not session.advance() and session.equilibrium.converged:
            return frame
    raise AssertionError(f"no rest after {max_frames} frames: {session.figures()}")


def full_tip(scene, ratio: float) -> np.ndarray:
    built = scene.build()
    rest = built.scene.schedule.rest_commands
    solver = NewtonSolver(built.model, NewtonOptions(tol=1e-9))
    u, *_ = settle_full(built, solver, rest, np.zeros_like(built.mesh.vertices), np.array([ratio]))
    return u[built.mesh.tip].mean(axis=0)


def test_a_resting_slider_settles_at_the_reduced_equilibrium_and_shows_its_full_residual(trained):
    scene, model, path = trained
    session = LiveSession(scene, reduced=path)
    settle(session)
    session.command(0, 2.2)
    settle(session)
    figures = session.figures()
    reduced = equilibrium(model, np.array([2.2]))
    length = np.ptp(session.mesh.vertices[:, 0])
    expected = model.displacements(reduced.q)[session.mesh.tip].mean(axis=0)
    assert np.allclose(figures["tip"], expected, atol=1e-5 * length)
    assert np.allclose(figures["tip"], full_tip(scene, 2.2), atol=2e-3 * length)  # the reduced model's own error
    assert figures["model"].startswith("reduced model (8 modes, ")
    residual = float(figures["model"].split("full residual ")[1])
    assert 1e-8 < residual < 1.0  # a reduced state: off the full equilibrium, by far less than its forces
    chamber = session.built.chambers[0]
    assert figures["pressures"][0] == pytest.approx(chamber.k * (2.2 * chamber.rest_area - chamber.area()), rel=1e-9)
    kept = session.steps[-1].chambers["main"]  # the history of the kept equilibrium: the full model at V q
    assert (kept.command, kept.pressure) == pytest.approx((2.2, figures["pressures"][0]), rel=1e-9)


def test_outside_the_training_range_the_full_model_solves_and_back_inside_the_reduced_one(trained):
    scene, model, path = trained
    session = LiveSession(scene, reduced=path)
    settle(session)
    session.command(0, 2.4)
    settle(session)
    session.command(0, 2.8)
    settle(session)
    figures = session.figures()
    assert figures["model"] == (
        "full model: commands outside the reduced model's training range (main 2.8 not in 1 .. 2.5)"
    )
    length = np.ptp(session.mesh.vertices[:, 0])
    assert np.allclose(figures["tip"], full_tip(scene, 2.8), atol=1e-4 * length)  # the full model's equilibrium
    session.command(0, 2.3)
    settle(session)
    assert session.figures()["model"].startswith("reduced model")


def test_a_model_of_another_scene_is_refused_by_the_page_and_the_window_flags(trained, capsys, tmp_path):
    from taichi_pneuma.apps import inflate, serve

    _, _, path = trained
    pytest.importorskip("viser")
    assert serve.main(["--scene", "reference_beam", "--reduced", str(path), "--out", str(tmp_path)]) == 2
    error = capsys.readouterr().err.strip()
    assert error.count("\n") == 0 and "was trained for another scene" in error
    assert inflate.main(["--scene", "reference_beam", "--reduced", str(path), "--out", str(tmp_path)]) == 2
    error = capsys.readouterr().err.strip()
    assert error == f"error: --reduced {path} needs --interactive on a 3D scene (the live page: pneuma-serve --reduced)"


def test_the_page_names_the_model_that_solves(trained, tmp_path):
    pytest.importorskip("viser")
    from taichi_pneuma.realtime.web import WebView

    scene, _, path = trained
    view = WebView(LiveSession(scene, reduced=path), tmp_path, port=0)
    try:
        for _ in range(30):
            view.step()
        assert "reduced model (8 modes, " in view.caption()
        assert "full residual " in view.caption()
    finally:
        view.stop()


def test_a_dragged_slider_takes_chord_steps_and_still_settles_at_the_reduced_equilibrium(trained):
    """While the command moves every frame, a frame reuses the last exact reduced Hessian's factor (no Hessian
    evaluated); once it rests, the state is the reduced equilibrium there."""
    scene, model, path = trained
    session = LiveSession(scene, reduced=path)
    settle(session)
    reduced = session.equilibrium.reduced
    calls = []
    hessian = reduced.model.hessian
    reduced.model.hessian = lambda psd_only=False: calls.append(psd_only) or hessian(psd_only)
    for value in np.linspace(1.2, 2.0, 12):
        session.command(0, float(value))
        session.advance()
    assert len(calls) < 6  # 12 frames, most of them chord steps
    settle(session)
    expected = model.displacements(equilibrium(model, np.array([2.0])).q)
    length = np.ptp(session.mesh.vertices[:, 0])
    assert np.allclose(session.equilibrium.u, expected, atol=1e-5 * length)
