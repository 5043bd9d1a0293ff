"""The balloon scenes: one thin wall dented into its chamber, whose pressure-volume curve has a limit point,
driven by volume control, a syringe and a pressure regulator (taichi_pneuma/scenes/balloon_*.toml, docs/chambers.md).

Volume control finds the peak, the drop and the rise after it; the syringe passes the peak as a sequence of
stable equilibria (its Hessian positive definite where pressure control's is not) on the same curve; pressure
control stops at the peak, as the scene declares (schedule.ends_at_limit_point), with exit code 0."""

import io
import json
import re
from contextlib import redirect_stderr, redirect_stdout
from pathlib import Path

import numpy as np
import pytest

import taichi_pneuma as tp
from taichi_pneuma.apps.inflate import main
from taichi_pneuma.solve.linsolve import FixedPattern
from taichi_pneuma.terms.chambers import AreaControl, PressureControl, Syringe

SCENES = Path(__file__).resolve().parent.parent / "taichi_pneuma" / "scenes"


@pytest.fixture(scope="module")
def runs():
    cache = {}
    return lambda drive: cache.setdefault(drive, tp.simulate(tp.load_scene(SCENES / f"balloon_{drive}.toml")))


def limit_point(pressure: np.ndarray) -> int:
    """The step of the first pressure peak: where the pressure first falls."""
    return int(np.flatnonzero(np.diff(pressure) < 0)[0])


def test_the_three_balloon_scenes_are_one_body_driven_three_ways():
    scenes = {drive: tp.load_scene(SCENES / f"balloon_{drive}.toml") for drive in ("volume", "syringe", "pressure")}
    assert len({(s.geometry, s.material, s.regions, s.clamp_stiffness) for s in scenes.values()}) == 1
    assert [type(s.controls[0].kind) for s in scenes.values()] == [AreaControl, Syringe, PressureControl]


def test_volume_control_finds_the_limit_point(runs):
    """The pressure rises to a peak, falls to a quarter of it while the chamber keeps growing, then rises past it."""
    result = runs("volume")
    pressure, volume = result.pressure[:, 0], result.area[:, 0]
    peak = limit_point(pressure)
    low = peak + int(np.argmin(pressure[peak:]))
    assert result.converged and 3 < peak and low < len(pressure) - 3
    assert max(s.cuts for s in result.steps) == 0  # exact Newton past the peak (Cholesky refuses its sparse part)
    assert np.all(np.diff(pressure[: peak + 1]) > 0) and np.all(np.diff(pressure[peak : low + 1]) < 0)
    assert pressure[low] < 0.3 * pressure[peak] and pressure[-1] > 2 * pressure[peak]
    assert np.all(np.diff(volume) > 0)


def test_the_syringe_passes_the_peak_through_stable_equilibria_on_the_same_curve(runs):
    """Every step converges, the pressure falls over the steps after the peak, each equilibrium keeps the gas law,
    its pressure-volume points lie on volume control's curve, and an equilibrium on the falling branch is stable
    (the exact Hessian, sparse part plus the gas's rank-1 part, positive definite) where the same state under
    pressure control (the sparse part alone) is not."""
    result, volume_run = runs("syringe"), runs("volume")
    pressure, volume = result.pressure[:, 0], result.area[:, 0]
    peak = limit_point(pressure)
    falling = np.arange(peak, peak + int(np.argmin(pressure[peak:])) + 1)
    assert result.converged and len(falling) >= 10 and np.all(np.diff(pressure[falling]) < 0)
    assert max(s.cuts for s in result.steps) == 0
    kind, rest_area = result.scene.controls[0].kind, volume[0]
    barrel = kind.dead_volume + kind.syringe_volume
    gas = volume + barrel - result.command[:, 0]
    assert (pressure + kind.atmosphere) * gas == pytest.approx(kind.atmosphere * (rest_area + barrel), rel=1e-12)
    on_curve = np.interp(volume[falling], volume_run.area[:, 0], volume_run.pressure[:, 0])
    assert np.abs(pressure[falling] - on_curve).max() < 0.01 * pressure[peak]

    built, state = result.built, falling[len(falling) // 2]
    built.set_commands(result.command[state])
    built.model.set_displacements(result.displacements[state])
    n = built.model.n_dofs
    sparse = FixedPattern(*built.model.hessian_pattern(), n).matrix(built.model.hessian_values(psd_only=False))
    hessian = sparse.toarray()
    for dofs, u, c in built.model.low_rank():
        hessian[np.ix_(dofs, dofs)] += c * np.outer(u, u)
    np.linalg.cholesky(hessian)  # positive definite: a stable equilibrium
    with pytest.raises(np.linalg.LinAlgError):
        np.linalg.cholesky(sparse.toarray())


def test_pressure_control_stops_at_the_peak_as_planned(runs, tmp_path):
    """Through the command line: exit 0, no error, one line naming the pressure and the last one reached, which is
    the peak of volume control's curve (to 1%); the steps done are saved, the summary says where it stopped and
    that the tip is the box at the dent's apex."""
    err, printed = io.StringIO(), io.StringIO()
    with redirect_stderr(err), redirect_stdout(printed):
        code = main(
            [
                "--scene",
                str(SCENES / "balloon_pressure.toml"),
                "--out",
                str(tmp_path),
                "--no-video",
                "--quiet",
                "--max-cuts",
                "3",
                "--max-iterations",
                "20",
            ]
        )
    lines = [line for line in printed.getvalue().splitlines() if line.startswith("stopped at the limit point")]
    assert code == 0 and "error" not in err.getvalue() and len(lines) == 1
    match = re.fullmatch(
        r"stopped at the limit point, as the scene plans \(schedule.ends_at_limit_point\): step (\d+): no "
        r"equilibrium at pressure ([0-9.]+) \(last equilibrium at pressure ([0-9.]+)\) after 3 cuts; residual .*",
        lines[0],
    )
    assert match
    peak = runs("volume").pressure[:, 0][limit_point(runs("volume").pressure[:, 0])]
    assert float(match[3]) == pytest.approx(peak, rel=1e-2) and float(match[2]) > float(match[3])
    history = np.genfromtxt(tmp_path / "balloon_pressure_history.csv", delimiter=",", names=True, deletechars="")
    assert history["main.pressure"].max() <= float(match[3]) and len(history) == int(match[1])
    summary = json.loads((tmp_path / "balloon_pressure_summary.json").read_text())
    assert summary["stopped"] == {"step": int(match[1]), "reason": "limit point", "message": lines[0].split(": ", 1)[1]}
    assert summary["steps"] == int(match[1]) and summary["tip_at"] == "the tip (box [-0.5, 0.5, 0.5, 2])"


def test_a_declared_limit_point_is_not_taken_for_a_ramp_that_fails_before_it_softens(tmp_path):
    """balloon_pressure with one Newton iteration per increment and no cut-back fails far below its peak, its
    compliance dV/dp barely changed: that is no limit point, so it is refused as any failed ramp (exit 1), saying
    why, with the steps done written."""
    err, printed = io.StringIO(), io.StringIO()
    with redirect_stderr(err), redirect_stdout(printed):
        code = main(
            ["--scene", "balloon_pressure", "--out", str(tmp_path), "--no-video", "--quiet"]
            + ["--max-iterations", "2", "--max-cuts", "0"]
        )
    assert code == 1 and "no equilibrium" in err.getvalue()
    assert "not a limit point" in printed.getvalue() and "stopped at the limit point" not in printed.getvalue()
    summary = json.loads((tmp_path / "balloon_pressure_summary.json").read_text())
    assert summary["stopped"]["reason"] == "no equilibrium"
