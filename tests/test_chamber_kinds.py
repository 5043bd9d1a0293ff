"""Chamber kinds: each kind's energy, gradient, Hessian and -d(residual)/d(command) against finite
differences; the closed gas kind of tests/closed_gas.py (registered there, no other module edited) through
scene files, the ramp, sensitivities, inverse control's units, the plots and the failure message; and
every kind's validation naming the value."""

import dataclasses
from pathlib import Path

import numpy as np
import pytest
from closed_gas import ClosedGas
from test_terms import dense_hessian, fd_gradient, fd_hessian, random_state

from taichi_pneuma.control.inverse import Reacher, command_bounds
from taichi_pneuma.errors import PneumaInputError
from taichi_pneuma.io.scenefile import load_scene
from taichi_pneuma.render.plots import command_axis
from taichi_pneuma.scene import ChamberControl, reference_scene
from taichi_pneuma.solve.newton import NewtonOptions, NewtonSolver
from taichi_pneuma.solve.schedule import ChamberSchedule
from taichi_pneuma.solve.sensitivity import sensitivity
from taichi_pneuma.solve.simulate import describe_commands, run_schedule, settle, tip_measures
from taichi_pneuma.terms.chambers import AreaControl, ChamberKind, PressureControl, register

ATMOSPHERE = 1e3  # a soft gas for the reference beam (E = 1e4): gauge pressures of a few hundred
KINDS = {"area": (AreaControl(), 1.5), "pressure": (PressureControl(), 300.0),
         "closed_gas": (ClosedGas(ATMOSPHERE), 1.5)}  # kind, a command that inflates the chamber


def kind_scene(kind, keyframes, **coarse):
    """The reference beam (coarse by default) with its chamber driven by `kind` through `keyframes`."""
    scene = reference_scene(**({"chamber_points": 32, "max_area": 0.02} | coarse))
    return dataclasses.replace(scene, controls=(ChamberControl(ChamberSchedule(kind, keyframes)),),
                               increments=int(keyframes[-1][0]))


@pytest.fixture(scope="module", params=list(KINDS))
def inflated(request):
    """A coarse beam whose chamber of each kind is commanded to inflate, in a random state."""
    kind, command = KINDS[request.param]
    built = kind_scene(kind, ((1, command),)).build()
    built.set_commands([command])
    u = random_state(built)
    built.model.set_displacements(u)
    return built, u


def test_energy_gradient_and_hessian_match_finite_differences(inflated):
    built, u = inflated
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
    """-dr/dq at a fixed state against central differences of the gradient in the command."""
    built, u = inflated
    chamber = built.chambers[0]
    command, h = KINDS[chamber.kind.name][1], 1e-4 * KINDS[chamber.kind.name][1]
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
    for kind, command in KINDS.values():
        built = kind_scene(kind, ((1, command),)).build()
        chamber = built.chambers[0]
        loads = []
        for q in (kind.rest, command):
            chamber.set_command(q)
            loads.append(np.abs(chamber.gradient()).max())
        assert loads[0] <= 1e-12 * loads[1]


def test_closed_gas_obeys_the_gas_law_and_is_the_pressure_load_of_its_own_pressure():
    """Along a ramp of gas amount q, (p + p_atm) A = n R T = q p_atm A_rest at every equilibrium; the
    final one is also the equilibrium of pressure control at the gas's pressure (a gas is a pressure load)."""
    result = run_schedule(kind_scene(ClosedGas(ATMOSPHERE), ((4, 2.0),)).build())
    rest_area = result.steps[0].chambers["main"].area
    for step in result.steps:
        c = step.chambers["main"]
        assert (c.pressure + ATMOSPHERE) * c.area == pytest.approx(c.command * ATMOSPHERE * rest_area, rel=1e-12)
    final = result.steps[-1].chambers["main"]
    assert 1.3 < final.area_ratio < 2.0 and final.pressure > 100  # inflated, the gas expanded below q = 2
    built = kind_scene(PressureControl(), ((1, final.pressure),)).build()
    u = settle(built, NewtonSolver(built.model), np.zeros(1), np.zeros_like(built.mesh.vertices),
               np.array([final.pressure]))[0]
    moved = result.positions[-1] - built.mesh.vertices
    assert np.abs(u - moved).max() < 1e-6 * np.abs(moved).max()


def test_closed_gas_sensitivities_match_finite_differences_of_resolves():
    built = kind_scene(ClosedGas(ATMOSPHERE), ((1, 1.5),), max_area=0.01, chamber_points=64).build()
    solver = NewtonSolver(built.model, NewtonOptions(tol=1e-10))
    q, h = np.array([1.5]), 1e-3
    u = settle(built, solver, np.ones(1), np.zeros_like(built.mesh.vertices), q)[0]
    s = sensitivity(built, q, u)
    plus, minus = (settle(built, solver, q, u, q + sign * h)[0] for sign in (1, -1))
    fd_tip = (np.array(tip_measures(built.mesh, plus)) - tip_measures(built.mesh, minus)) / (2 * h)
    fd_u = (plus - minus) / (2 * h)
    assert np.all(np.abs(fd_tip) > 0)
    assert np.abs(s.tip[:, 0] - fd_tip).max() <= 1e-5 * np.abs(fd_tip).max()
    assert np.abs(s.displacements[..., 0] - fd_u).max() <= 1e-5 * np.abs(fd_u).max()


def test_a_registered_kind_is_a_scene_file_control(tmp_path):
    """The gas kind's name and parameter read and write through scene files; "volume" names area control;
    a parameter of another kind is an unknown key."""
    scene = kind_scene(ClosedGas(ATMOSPHERE), ((4, 2.0),))
    text = scene.to_toml()
    assert 'control = "closed_gas"' in text and "atmosphere = 1000.0" in text
    path = tmp_path / "gas.toml"
    path.write_text(text)
    assert load_scene(path) == scene
    path.write_text(text.replace("atmosphere = 1000.0", "stiffness = 1e5"))
    with pytest.raises(PneumaInputError, match=r"unknown key 'chambers\[0\].stiffness' \(allowed here: atmosphere,"):
        load_scene(path)
    path.write_text(text.replace('"closed_gas"', '"volume"').replace("atmosphere = 1000.0", "stiffness = 2e5"))
    assert load_scene(path).controls[0].kind == AreaControl(stiffness=2e5)


def test_the_apps_ask_the_kind():
    """Inverse control's units and default bounds, the plots' label and a failed solve's words come from the kind."""
    scene = kind_scene(ClosedGas(ATMOSPHERE), ((2, 1.5), (4, 0.8)))
    assert [b.tolist() for b in command_bounds(scene)] == [[0.8], [1.5]]
    command = np.array([[1.0], [1.2]])
    assert command_axis(command, [c.kind.quantity for c in scene.controls])[1] == "commanded gas amount"
    built = scene.build()
    assert Reacher(built, bounds=([1.0], [1.5])).units == ["gas amount"]
    assert describe_commands(built, np.array([1.5]), np.array([1.25])) == \
        "gas amount 1.5 (last equilibrium at gas amount 1.25)"
    area = kind_scene(AreaControl(), ((1, 2.0),)).build()
    assert describe_commands(area, np.array([2.0]), np.array([1.5])) == \
        f"commanded area {2 * area.chambers[0].rest_area:.6g} (2 x rest)"


@pytest.mark.parametrize("make, message", [
    (lambda: ChamberSchedule("area", ((1, 0.0),)), r"keyframes area ratio 0.0 must lie in \(0, 1000\]"),
    (lambda: ChamberSchedule(AreaControl(), ((1, 1.5), (2, 2e3))), r"keyframes area ratio 2000.0 must lie in"),
    (lambda: AreaControl(stiffness=0.0), r"chamber stiffness k = 0.0 must be > 0"),
    (lambda: ChamberSchedule("pressure", ((1, -5.0),)), r"keyframes pressure -5.0 is negative; set allow_vacuum"),
    (lambda: ChamberControl(ChamberSchedule("area", ((1, 2.0),)), (0.5, 2e3)),
     r"bounds = \[0.5, 2000.0\]: area ratio 2000.0 must lie in"),
    (lambda: ChamberControl(ChamberSchedule("pressure", ((1, 2.0),)), (-1.0, 2.0)),
     r"bounds = \[-1.0, 2.0\]: pressure -1.0 is negative"),
    (lambda: ChamberSchedule(ClosedGas(), ((1, -1.0),)), r"keyframes gas amount -1.0 must be > 0"),
    (lambda: ClosedGas(atmosphere=0.0), r"atmosphere = 0.0 must be > 0"),
    (lambda: ChamberSchedule("syringe", ((1, 1.0),)), r"control = 'syringe' is not one of area, volume, pressure"),
])
def test_bad_commands_and_parameters_are_refused_naming_the_value(make, message):
    with pytest.raises(PneumaInputError, match=message):
        make()


def test_suction_with_allow_vacuum_and_a_taken_name():
    assert ChamberSchedule(PressureControl(allow_vacuum=True), ((1, -5.0),)).command(1) == -5.0

    @dataclasses.dataclass(frozen=True)
    class Impostor(ChamberKind):
        name = "area"

    with pytest.raises(ValueError, match="'area' is taken by AreaControl"):
        register(Impostor)


def test_the_extending_page_shows_this_example():
    """docs/extending.md's code of the closed gas kind is the code these tests run."""
    page = (Path(__file__).resolve().parents[1] / "docs" / "extending.md").read_text()
    block = next(b.split("```")[0] for b in page.split("```python\n")[1:] if "class ClosedGas" in b)
    assert block in (Path(__file__).resolve().parent / "closed_gas.py").read_text()
