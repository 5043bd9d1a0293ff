"""Chamber kinds: every registered kind's energy, gradient, Hessian and -d(residual)/d(command) against finite
differences; the gas kinds (closed gas, syringe) against their gas laws along ramps, their sensitivities
against finite differences of re-solves, a syringe twin through inverse control, the gas volume kept
positive by max_step; through scene files, inverse control's units, the plots and the failure message; and
every kind's validation naming the value."""

import dataclasses
from pathlib import Path

import numpy as np
import pytest
from fd import dense_hessian, fd_gradient, fd_hessian, random_state

import taichi_pneuma as tp
from taichi_pneuma.control.inverse import Reacher, ReachOptions, body_length, command_bounds
from taichi_pneuma.errors import PneumaInputError
from taichi_pneuma.fem.tip import tip_measures, tip_outputs
from taichi_pneuma.render.plots import command_axis
from taichi_pneuma.scene.build import ChamberControl, reference_scene
from taichi_pneuma.scene.scenefile import load_scene
from taichi_pneuma.scene.schedule import ChamberSchedule
from taichi_pneuma.scene.targets import Target
from taichi_pneuma.solve.newton import NewtonOptions, NewtonSolver
from taichi_pneuma.solve.sensitivity import sensitivity
from taichi_pneuma.solve.simulate import describe_commands, run_schedule, settle
from taichi_pneuma.terms.chambers import (
    KINDS,
    AreaControl,
    ChamberKind,
    ClosedGas,
    PressureControl,
    Syringe,
)

ATMOSPHERE = 1e3  # a soft gas for the reference beam (E = 1e4): gauge pressures of a few hundred
SYRINGE = Syringe(ATMOSPHERE, syringe_volume=1.0, dead_volume=0.3)
EXAMPLES = {  # kind, a command that inflates the coarse beam's chamber (rest area 0.57)
    "area": (AreaControl(), 1.5),
    "pressure": (PressureControl(), 300.0),
    "closed_gas": (ClosedGas(ATMOSPHERE), 0.6),
    "adiabatic_gas": (ClosedGas(ATMOSPHERE, gamma=1.4), 0.6),
    "syringe": (SYRINGE, 0.6),
    "adiabatic_syringe": (dataclasses.replace(SYRINGE, gamma=1.4), 0.6),
}


def test_every_registered_kind_has_an_example():
    """The checks below run over EXAMPLES: a newly registered kind must be added to it."""
    assert {kind.name for kind in KINDS.values()} == {kind.name for kind, _ in EXAMPLES.values()}


def kind_scene(kind, keyframes, **coarse):
    """The reference beam (coarse by default) with its chamber driven by `kind` through `keyframes`."""
    scene = reference_scene(**({"chamber_points": 32, "max_area": 0.02} | coarse))
    return dataclasses.replace(
        scene, controls=(ChamberControl(ChamberSchedule(kind, keyframes)),), increments=int(keyframes[-1][0])
    )


@pytest.fixture(scope="module", params=list(EXAMPLES))
def inflated(request):
    """A coarse beam whose chamber of each kind is commanded to inflate, in a random state."""
    kind, command = EXAMPLES[request.param]
    built = kind_scene(kind, ((1, command),)).build()
    built.set_commands([command])
    u = random_state(built)
    built.model.set_displacements(u)
    return built, u, command


def test_energy_gradient_and_hessian_match_finite_differences(inflated):
    check_derivatives(*inflated[:2])


def check_derivatives(built, u):
    """The chamber's gradient and exact Hessian (rank-1 part included) against central differences at u; its
    PSD-only Hessian positive semi-definite."""
    model, chamber = built.model, built.chambers[0]
    g = chamber.gradient().ravel()
    assert np.linalg.norm(g - fd_gradient(model, chamber, u)) < 1e-6 * np.linalg.norm(g)
    model.set_displacements(u)
    hessian = dense_hessian(model.n_dofs, [chamber], psd_only=False)
    h_fd = fd_hessian(model, [chamber], u)
    assert np.linalg.norm(hessian - h_fd) < 1e-6 * np.linalg.norm(h_fd)
    model.set_displacements(u)
    eigenvalues = np.linalg.eigvalsh(dense_hessian(model.n_dofs, [chamber], psd_only=True))
    assert eigenvalues.min() >= -1e-12 * max(eigenvalues.max(), 1.0)


def test_command_force_is_minus_the_residual_derivative(inflated):
    check_command_force(*inflated)


def check_command_force(built, u, command):
    """-dr/dq at a fixed state against central differences of the gradient in the command."""
    chamber, h = built.chambers[0], 1e-4 * command
    built.model.set_displacements(u)
    residual = []
    for q in (command + h, command - h):
        chamber.set_command(q)
        residual.append(chamber.gradient()[chamber.loop_vertices].ravel())
    chamber.set_command(command)
    fd = -(residual[0] - residual[1]) / (2 * h)
    assert np.linalg.norm(chamber.command_force() - fd) < 1e-8 * np.linalg.norm(fd)


def test_rest_command_loads_nothing():
    """At the rest state the rest command's wall force vanishes (to round-off against an inflating command's)."""
    for kind, command in EXAMPLES.values():
        built = kind_scene(kind, ((1, command),)).build()
        chamber = built.chambers[0]
        loads = []
        for q in (kind.rest, command):
            chamber.set_command(q)
            loads.append(np.abs(chamber.gradient()).max())
        assert loads[0] <= 1e-12 * loads[1]


def gas_law_constant(chamber_record, kind, rest_area: float, gamma: float) -> tuple[float, float]:
    """(p_abs G^gamma, p_atm V_atm^gamma) of one equilibrium of a gas kind, from its recorded pressure and area:
    G and V_atm from the kind's definition (closed gas: G = A, V_atm = A_rest + q; syringe: G = A + V_d + V_s0 - dV,
    V_atm = A_rest + V_d + V_s0)."""
    c, p_atm = chamber_record, kind.atmosphere
    if isinstance(kind, Syringe):
        barrel = kind.dead_volume + kind.syringe_volume
        gas, air = c.area + barrel - c.command, rest_area + barrel
    else:
        gas, air = c.area, rest_area + c.command
    return (c.pressure + p_atm) * gas**gamma, p_atm * air**gamma


@pytest.mark.parametrize(
    "kind",
    [ClosedGas(ATMOSPHERE), ClosedGas(ATMOSPHERE, gamma=1.4), SYRINGE],
    ids=["isothermal", "adiabatic", "syringe"],
)
def test_gas_kinds_obey_their_gas_law_along_a_ramp(kind):
    """At every equilibrium of a ramp p_abs G = n R T (isothermal) or p_abs G^1.4 = its rest value (adiabatic);
    the chamber inflates and its gauge pressure rises."""
    result = run_schedule(kind_scene(kind, ((4, 0.8),)).build())
    assert 1.3 < check_gas_law(result, kind) < 2.4  # inflated; the gas kept some of the volume


def check_gas_law(result, kind) -> float:
    """The kind's gas law at every equilibrium of the ramp, its gauge pressure rising from 0; the final area ratio."""
    rest_area = result.steps[0].chambers["main"].area
    for step in result.steps:
        reached, law = gas_law_constant(step.chambers["main"], kind, rest_area, kind.gamma)
        assert reached == pytest.approx(law, rel=1e-12)
    pressures = [step.chambers["main"].pressure for step in result.steps]
    # at rest the gauge pressure is p_atm (V0 / V0)^gamma - p_atm: zero up to the round-off of p_atm's size
    assert pressures[0] == pytest.approx(0, abs=1e-15 * ATMOSPHERE) and np.all(np.diff(pressures) > 0)
    return result.steps[-1].chambers["main"].area_ratio


def test_a_gas_is_the_pressure_load_of_its_own_pressure():
    """The closed gas's equilibrium is that of pressure control at the gas's pressure (and the syringe's too)."""
    for kind in (ClosedGas(ATMOSPHERE), SYRINGE):
        result = run_schedule(kind_scene(kind, ((2, 0.8),)).build())
        final = result.steps[-1].chambers["main"]
        built = kind_scene(PressureControl(), ((1, final.pressure),)).build()
        u = settle(
            built,
            NewtonSolver(built.model),
            np.zeros(1),
            np.zeros_like(built.mesh.vertices),
            np.array([final.pressure]),
        )[0]
        moved = result.positions[-1] - built.mesh.vertices
        assert np.abs(u - moved).max() < 1e-6 * np.abs(moved).max()


def test_the_syringe_compresses_its_air_more_the_more_there_is_of_it():
    """The same displaced volume inflates the chamber less through a larger dead volume (more air to
    compress), and with no tube a syringe that empties itself is the closed gas chamber pumped that much."""
    areas = []
    for dead in (0.0, 1.0, 4.0):
        kind = dataclasses.replace(SYRINGE, dead_volume=dead)
        areas.append(run_schedule(kind_scene(kind, ((1, 0.8),)).build()).steps[-1].chambers["main"].area)
    assert areas[0] > areas[1] > areas[2]
    emptied = run_schedule(kind_scene(Syringe(ATMOSPHERE, syringe_volume=0.8), ((1, 0.8),)).build())
    pumped = run_schedule(kind_scene(ClosedGas(ATMOSPHERE), ((1, 0.8),)).build())
    assert np.abs(emptied.positions[-1] - pumped.positions[-1]).max() < 1e-9


@pytest.mark.parametrize(
    "kind",
    [ClosedGas(ATMOSPHERE), ClosedGas(ATMOSPHERE, gamma=1.4), SYRINGE],
    ids=["closed_gas", "adiabatic", "syringe"],
)
def test_gas_sensitivities_match_finite_differences_of_resolves(kind):
    built = kind_scene(kind, ((1, 0.6),), max_area=0.01, chamber_points=64).build()
    solver = NewtonSolver(built.model, NewtonOptions(tol=1e-10))
    q, h = np.array([0.6]), 1e-3
    u = settle(built, solver, np.zeros(1), np.zeros_like(built.mesh.vertices), q)[0]
    s = sensitivity(built, q, u)
    plus, minus = (settle(built, solver, q, u, q + sign * h)[0] for sign in (1, -1))
    fd_tip = (tip_outputs(built.mesh, plus) - tip_outputs(built.mesh, minus)) / (2 * h)
    fd_u = (plus - minus) / (2 * h)
    assert np.all(np.abs(fd_tip) > 0)
    assert np.abs(s.tip[:, 0] - fd_tip).max() <= 1e-5 * np.abs(fd_tip).max()
    assert np.abs(s.displacements[..., 0] - fd_u).max() <= 1e-5 * np.abs(fd_u).max()


@pytest.mark.parametrize("seed", [1, 2])
def test_syringe_twin_through_inverse_control(seed):
    """A displaced volume drawn at random, solved forward (not by the code under test), is recovered from the
    tip it produced."""
    scene = kind_scene(SYRINGE, ((1, 0.8),), max_area=0.01, chamber_points=64)
    built = scene.build()
    displaced = np.random.default_rng(seed).uniform(0.1, 0.7, 1)
    u = settle(
        built,
        NewtonSolver(built.model, NewtonOptions(tol=1e-9)),
        np.zeros(1),
        np.zeros_like(built.mesh.vertices),
        displaced,
    )[0]
    (dx, dy), _ = tip_measures(built.mesh, u)
    tip = built.mesh.vertices[built.mesh.tip].mean(axis=0) + (dx, dy)
    result = Reacher(built, options=ReachOptions(tol=1e-7), newton=NewtonOptions(tol=1e-9)).reach(Target(tuple(tip)))
    assert result.reached and result.error <= 1e-7 * body_length(built)
    assert result.pose.commands == pytest.approx(displaced, rel=1e-4)
    assert Reacher(built).units == ["displaced volume"] and command_bounds(scene)[1].tolist() == [0.8]


@pytest.mark.parametrize("kind", [ClosedGas(ATMOSPHERE), SYRINGE], ids=["closed_gas", "syringe"])
def test_max_step_is_where_the_gas_volume_vanishes(kind):
    """Moving the wall nodes by (x, y) -> (x + t (x - c_x), y - 2 t (y - c_y)) scales the enclosed area to
    A (1 + t)(1 - 2 t); max_step is the first t > 0 with A (1 + t)(1 - 2 t) + c = 0 (c: the gas outside)."""
    built = kind_scene(kind, ((1, 0.5),)).build()
    built.set_commands([0.5])
    chamber = built.chambers[0]
    wall = built.mesh.vertices[chamber.loop_vertices]
    dx = np.zeros_like(built.mesh.vertices)
    dx[chamber.loop_vertices] = (wall - wall.mean(axis=0)) * (1.0, -2.0)
    area, outside = chamber.area(), chamber.outside  # the model is at rest
    roots = np.roots([-2 * area, -area, area + outside])
    assert chamber.max_step(dx) == pytest.approx(roots[roots > 0].min(), rel=1e-10)
    assert chamber.max_step(-dx) == np.inf or chamber.max_step(-dx) > 1
    built.model.set_displacements(1.001 * chamber.max_step(dx) * dx)
    assert chamber.energy() == np.inf


def test_a_registered_kind_is_a_scene_file_control(tmp_path):
    """The gas kinds' names and parameters read and write through scene files; a missing required parameter is
    named; "volume" names area control; a parameter of another kind is an unknown key."""
    scene = kind_scene(ClosedGas(ATMOSPHERE, gamma=1.4), ((4, 0.8),))
    text = scene.to_toml()
    assert 'control = "closed_gas"' in text and "atmosphere = 1000.0" in text and "gamma = 1.4" in text
    path = tmp_path / "gas.toml"
    path.write_text(text)
    assert load_scene(path) == scene
    path.write_text(text.replace("atmosphere = 1000.0", "stiffness = 1e5"))
    with pytest.raises(PneumaInputError, match=r"unknown key 'chambers\[0\].stiffness' \(allowed here: atmosphere,"):
        load_scene(path)
    path.write_text(
        text.replace('"closed_gas"', '"volume"')
        .replace("atmosphere = 1000.0", "stiffness = 2e5")
        .replace("gamma = 1.4\n", "")
    )
    assert load_scene(path).controls[0].kind == AreaControl(stiffness=2e5)
    syringe = kind_scene(SYRINGE, ((4, 0.8),))
    path.write_text(syringe.to_toml())
    assert load_scene(path) == syringe
    path.write_text(syringe.to_toml().replace("syringe_volume = 1.0\n", ""))
    with pytest.raises(PneumaInputError, match=r"missing key 'chambers\[0\].syringe_volume'"):
        load_scene(path)


def test_the_apps_ask_the_kind():
    """Inverse control's units and default bounds, the plots' label and a failed solve's words come from the kind."""
    scene = kind_scene(ClosedGas(ATMOSPHERE), ((2, 0.5), (4, 0.2)))
    assert [b.tolist() for b in command_bounds(scene)] == [[0.0], [0.5]]
    command = np.array([[0.0], [0.2]])
    assert command_axis(command, [c.kind.quantity for c in scene.controls])[1] == "commanded air pumped in"
    built = scene.build()
    assert Reacher(built, bounds=([0.0], [0.5])).units == ["air pumped in"]
    assert (
        describe_commands(built, np.array([0.5]), np.array([0.25]))
        == "air pumped in 0.5 (last equilibrium at air pumped in 0.25)"
    )
    area = kind_scene(AreaControl(), ((1, 2.0),)).build()
    assert (
        describe_commands(area, np.array([2.0]), np.array([1.5]))
        == f"commanded area {2 * area.chambers[0].rest_area:.6g} (2 x rest)"
    )
    assert area.chambers[0].quantity == "area ratio"  # in messages; a 3D chamber's is its volume's
    assert tp.load_scene("beam_3d").build().chambers[0].quantity == "volume ratio"


@pytest.mark.parametrize(
    "make, message",
    [
        (lambda: ChamberSchedule("area", ((1, 0.0),)), r"keyframes area ratio 0.0 must lie in \(0, 1000\]"),
        (lambda: ChamberSchedule(AreaControl(), ((1, 1.5), (2, 2e3))), r"keyframes area ratio 2000.0 must lie in"),
        (lambda: AreaControl(stiffness=0.0), r"chamber stiffness k = 0.0 must be > 0"),
        (lambda: ChamberSchedule("pressure", ((1, -5.0),)), r"keyframes pressure -5.0 is negative; set allow_vacuum"),
        (
            lambda: ChamberControl(ChamberSchedule("area", ((1, 2.0),)), (0.5, 2e3)),
            r"bounds = \[0.5, 2000.0\]: area ratio 2000.0 must lie in",
        ),
        (
            lambda: ChamberControl(ChamberSchedule("pressure", ((1, 2.0),)), (-1.0, 2.0)),
            r"bounds = \[-1.0, 2.0\]: pressure -1.0 is negative",
        ),
        (lambda: ChamberSchedule(ClosedGas(), ((1, -1.0),)), r"keyframes air pumped in -1.0 must be >= 0"),
        (lambda: ClosedGas(atmosphere=0.0), r"atmosphere = 0.0 must be > 0"),
        (lambda: ClosedGas(gamma=0.9), r"gamma = 0.9 must lie in \[1, 5/3\]"),
        (lambda: ClosedGas(gamma=float("nan")), r"gamma = nan must be a finite number"),
        (
            lambda: ChamberSchedule("bellows", ((1, 1.0),)),
            r"control = 'bellows' is not one of area, volume, closed_gas, pressure, syringe",
        ),
        (lambda: ChamberSchedule("syringe", ((1, 1.0),)), r"control = 'syringe' has no default for syringe_volume"),
        (lambda: Syringe(syringe_volume=0.0), r"syringe_volume = 0.0 must be > 0"),
        (lambda: Syringe(syringe_volume=1.0, dead_volume=-0.1), r"dead_volume = -0.1 must be >= 0"),
        (
            lambda: ChamberSchedule(SYRINGE, ((1, 0.5), (2, 1.5))),
            r"keyframes displaced volume 1.5 exceeds syringe_volume = 1.0 \(the plunger stops at the barrel's end\)",
        ),
        (
            lambda: ChamberControl(ChamberSchedule(SYRINGE, ((1, 0.5),)), (-0.5, 2.0)),
            r"bounds = \[-0.5, 2.0\]: displaced volume 2.0 exceeds",
        ),
    ],
)
def test_bad_commands_and_parameters_are_refused_naming_the_value(make, message):
    with pytest.raises(PneumaInputError, match=message):
        make()


def test_suction_with_allow_vacuum_and_a_taken_name():
    assert ChamberSchedule(PressureControl(allow_vacuum=True), ((1, -5.0),)).command(1) == -5.0

    @dataclasses.dataclass(frozen=True)
    class Impostor(ChamberKind):
        name = "area"

    with pytest.raises(ValueError, match="'area' is taken by AreaControl"):
        KINDS.register(Impostor)


def test_the_extending_page_shows_the_shipped_closed_gas_kind():
    """docs/extending.md's worked example is the code of the shipped closed gas kind, which these tests run."""
    root = Path(__file__).resolve().parents[1]
    page = (root / "docs" / "extending.md").read_text()
    block = next(b.split("```")[0] for b in page.split("```python\n")[1:] if "class ClosedGas" in b)
    assert block in (root / "taichi_pneuma" / "terms" / "chambers" / "closed_gas.py").read_text()
