"""The chamber kinds on 3D cavities: every registered kind's energy, gradient, exact Hessian (with its rank-1
part) and -d(residual)/d(command) against finite differences on an octant cavity closed by three symmetry
planes (linear and quadratic tetrahedra), the gas volume kept positive by max_step (a volume is cubic in the
positions), the gas laws at every equilibrium of a 3D ramp (Boyle's p V = p0 V0, the adiabatic p V^1.4, the
syringe's balance of the air in chamber, tube and barrel), a gas being the pressure load of its own pressure,
and a mesh-file scene in mm and kPa with a closed-gas chamber whose outputs carry volume units."""

import dataclasses

import numpy as np
import pytest
from solid_meshes import box_with_cavity, scene_of, shell_octant
from test_chamber_kinds import check_command_force, check_derivatives, check_gas_law

import taichi_pneuma as tp
from taichi_pneuma.fem.meshfile import write_mesh
from taichi_pneuma.scene.build import Material
from taichi_pneuma.scene.schedule import ChamberSchedule
from taichi_pneuma.solve.newton import NewtonOptions, NewtonSolver
from taichi_pneuma.solve.simulate import run_schedule, settle
from taichi_pneuma.terms.chambers import KINDS, AreaControl, ClosedGas, PressureControl, Syringe

ATMOSPHERE = 1e3  # with E = 1e4: gauge pressures of a few hundred
SYRINGE = Syringe(ATMOSPHERE, syringe_volume=0.5, dead_volume=0.1)
# kind, a command that inflates the octant's cavity (rest volume about 0.5) or the box's (0.12)
KINDS_3D = {
    "area": (AreaControl(1e4), 1.4),
    "pressure": (PressureControl(), 300.0),
    "closed_gas": (ClosedGas(ATMOSPHERE), 0.2),
    "adiabatic_gas": (ClosedGas(ATMOSPHERE, gamma=1.4), 0.2),
    "syringe": (SYRINGE, 0.2),
    "adiabatic_syringe": (dataclasses.replace(SYRINGE, gamma=1.4), 0.2),
}


def test_every_registered_kind_is_checked_in_3d():
    assert {kind.name for kind in KINDS.values()} == {kind.name for kind, _ in KINDS_3D.values()}


@pytest.fixture(
    scope="module", params=[(name, order) for order in (1, 2) for name in KINDS_3D], ids=lambda p: f"{p[0]}-P{p[1]}"
)
def octant(request):
    """The octant cavity (A = 1, B = 2, closed by the three coordinate planes) of each kind, commanded to inflate,
    in a random state."""
    name, order = request.param
    kind, command = KINDS_3D[name]
    built = scene_of(shell_octant(2, 1, order), [ChamberSchedule(kind, ((1, command),))], 1).build()
    built.set_commands([command])
    u = 0.02 * np.random.default_rng(order).standard_normal(built.mesh.vertices.shape)
    built.model.set_displacements(u)
    return built, u, command


def test_energy_gradient_and_hessian_match_finite_differences(octant):
    check_derivatives(*octant[:2])


def test_command_force_is_minus_the_residual_derivative(octant):
    check_command_force(*octant)


@pytest.mark.parametrize("kind", [ClosedGas(ATMOSPHERE), SYRINGE], ids=["closed_gas", "syringe"])
def test_max_step_is_where_the_gas_volume_vanishes(kind):
    """Moving the wall by (x, y, z) -> (x (1 + t), y (1 - 2 t), z) scales the volume the octant's wall closes with
    the symmetry planes (they map to themselves) to V (1 + t)(1 - 2 t); max_step is the first t > 0 where
    V (1 + t)(1 - 2 t) + c vanishes (c: the gas outside the chamber)."""
    built = scene_of(shell_octant(2, 1), [ChamberSchedule(kind, ((1, 0.1),))], 1).build()
    built.set_commands([0.1])
    chamber = built.chambers[0]
    dx = np.zeros_like(built.mesh.vertices)
    dx[chamber.loop_vertices] = built.mesh.vertices[chamber.loop_vertices] * (1.0, -2.0, 0.0)
    volume, outside = chamber.area(), chamber.outside
    roots = np.roots([-2 * volume, -volume, volume + outside])
    assert chamber.max_step(dx) == pytest.approx(roots[roots > 0].min(), rel=1e-10)
    built.model.set_displacements(1.001 * chamber.max_step(dx) * dx)
    assert chamber.energy() == np.inf


@pytest.mark.parametrize(
    "kind",
    [ClosedGas(ATMOSPHERE), ClosedGas(ATMOSPHERE, gamma=1.4), SYRINGE],
    ids=["isothermal", "adiabatic", "syringe"],
)
def test_gas_kinds_obey_their_gas_law_on_a_3d_cavity(kind):
    """The clamped box with its closed cavity (rest volume 0.12), air pumped in (or a syringe pushed) over 3
    increments: at every equilibrium p_abs V = p_atm V0 (isothermal; V0 the air's volume at p_atm: the cavity's
    rest volume plus the air pumped in, or plus the tube and barrel for the syringe, whose gas volume counts them
    too) or p_abs V^1.4 = p_atm V0^1.4 (adiabatic); the cavity inflates and its pressure rises."""
    result = run_schedule(
        scene_of(box_with_cavity(), [ChamberSchedule(kind, ((3, 0.05),))], 3, Material(1e4, 0.45)).build()
    )
    rest = result.steps[0].chambers["main"].area
    assert 1.01 < check_gas_law(result, kind) < 1 + 0.05 / rest  # inflated, the air compressed


def test_a_gas_is_the_pressure_load_of_its_own_pressure_in_3d():
    mesh = box_with_cavity()
    tight = NewtonOptions(tol=1e-10)  # the two equilibria agree to what the solves leave
    final = run_schedule(
        scene_of(mesh, [ChamberSchedule(ClosedGas(ATMOSPHERE), ((2, 0.05),))], 2).build(), options=tight
    )
    reached = final.steps[-1].chambers["main"]
    built = scene_of(mesh, [ChamberSchedule("pressure", ((1, reached.pressure),))], 1).build()
    u = settle(
        built, NewtonSolver(built.model, tight), np.zeros(1), np.zeros_like(mesh.vertices), np.array([reached.pressure])
    )[0]
    moved = final.positions[-1] - mesh.vertices
    assert np.abs(u - moved).max() < 1e-6 * np.abs(moved).max()


def test_closed_gas_scene_in_mm_and_kpa(tmp_path):
    """A mesh-file scene in mm and kPa (an Ecoflex 00-30 box, its 0.12 mm^3 cavity pumped with 0.01 mm^3 of air
    at 101.325 kPa): Boyle's law in those units, and the chamber's command and measure labelled mm^3."""
    write_mesh(tmp_path / "box.msh", box_with_cavity(), ("chamber",))
    (tmp_path / "box.toml").write_text("""name = "box"
units = "mm-kPa"
[body]
shape = "mesh"
file = "box.msh"
[material]
preset = "ecoflex_00_30"
[clamp]
side = "left"
[[chambers]]
name = "main"
shape = "mesh_surface"
group = "chamber"
control = "closed_gas"
atmosphere = 101.325
keyframes = [[0, 0.0], [2, 0.01]]
[schedule]
increments = 2
""")
    result = tp.simulate(tp.load_scene(tmp_path / "box.toml"))
    assert result.converged
    final, rest = result.steps[-1].chambers["main"], result.steps[0].chambers["main"].area
    assert (final.pressure + 101.325) * final.area == pytest.approx(101.325 * (rest + 0.01), rel=1e-12)
    assert 0 < final.pressure < 101.325 * 0.01 / rest  # some of the air's compression taken up by the cavity
    header = result.history_csv().splitlines()[0]
    assert "main.command [mm^3]" in header and "main.area [mm^3]" in header and "main.pressure [kPa]" in header
    assert "tip_dz [mm]" in header
