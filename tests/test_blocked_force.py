"""A slender pneumatic actuator's blocked force against the moment balance of its pressure about its strain-limiting
sheet (beam theory, derived here; no code under test computes it).

The actuator: a clamped plane-strain strip of length L and height H = 8 (E = 1, nu = 0.45; its plane-strain modulus
E' = E / (1 - nu^2)), with a row of 4 x 6 chambers (height h_c = 4 between y = 2 and 6, every 9 along x) and an
inextensible sheet on its bottom face y = 0 (E_s t = 1e3, a hundred times the strip's E' H). A chamber at pressure p
pushes on its two end walls with p h_c at its mid-height y_c = 4; cut the strip inside a chamber and the pressure on the
part beyond the cut (the end wall's p h_c; the top and bottom walls' pushes cancel) has the moment M_p = p h_c y_c about
the sheet's line; cut it through a wall between chambers and the part beyond holds whole chambers: M_p = 0. With the
sheet inextensible, plane sections turn about it: the curvature is kappa(x) = (M(x)) / EI(x), EI(x) = E' int y^2 dA
about the sheet (the strip's E' H^3 / 3, less the chamber's E' (6^3 - 2^3) / 3 where a chamber is cut).

Free, the tip turns by theta = -int_0^L M_p / EI dx (clockwise: towards the sheet). Held at its tip by a plate (a
contact at x_c = L), the plate pushes up with F and M(x) = M_p(x) - F (x_c - x); the tip stays at its height,
v(x_c) = int_0^x_c (x_c - x) kappa dx = 0 (clamped at x = 0), so

    F = int_0^x_c (x_c - x) M_p / EI dx / int_0^x_c (x_c - x)^2 / EI dx,

the blocked force of a clamped-pinned beam under the pressure's moment (3 M_p / (2 L) for M_p and EI uniform).

Measured (quadratic triangles, max area 1): free, the tip turns 3.0 % more than theta (L = 100); blocked, F is 0.84
of the beam's at L = 100 (L / H = 12.5) and 0.89 at L = 200 (L / H = 25): a beam without shear compliance
overestimates the force, the less the more slender the strip (the walls between the chambers shear and bend under
the plate's force, which the beam model does not see). The test takes the slender strip and asserts 15 %.
"""

import math
import tomllib

import numpy as np
import pytest
from scipy.integrate import quad

from taichi_pneuma.scene.scenefile import read_scene
from taichi_pneuma.solve.simulate import run_schedule

E, NU, H, PITCH = 1.0, 0.45, 8.0, 9.0
E_PLANE = E / (1 - NU**2)
CHAMBER_HEIGHT, CHAMBER_MIDDLE = 4.0, 4.0


def actuator(length: float, pressure: float, plate: bool) -> str:
    """The scene file of the strip of the module docstring, its chambers ramped to `pressure` in one increment."""
    chambers = "".join(
        f'[[chambers]]\nname = "c{i}"\nshape = "rounded_rectangle"\ncenter = [{8.0 + PITCH * i}, 4.0]\n'
        f'size = [6.0, 4.0]\nradius = 0.5\ncontrol = "pressure"\nkeyframes = [[1, {pressure}]]\n'
        for i in range(chamber_count(length))
    )
    obstacle = (
        f'[[obstacles]]\nname = "plate"\nshape = "box"\ncenter = [{length - 1}, -1.02]\nsize = [4.0, 2.0]\n'
        "dhat = 0.02\nstiffness = 1.0\n"
        if plate
        else ""
    )
    return (
        f'[body]\nshape = "rectangle"\ncenter = [{length / 2}, 4.0]\nsize = [{length}, {H}]\n'
        f"[mesh]\nmax_area = 1.0\norder = 2\n[material]\nE = {E}\nnu = {NU}\n"
        '[clamp]\nside = "left"\n'
        f"{chambers}"
        # the beam bends about the sheet, which carries the slight compression there: the SVK sheet, not wrinkling
        '[[layers]]\nname = "sheet"\nside = "bottom"\nE = 1e4\nnu = 0.3\nthickness = 0.1\nwrinkles = false\n'
        f"{obstacle}[schedule]\nincrements = 1\n"
    )


def chamber_count(length: float) -> int:
    """Chambers every PITCH from x = 5, the last ending at least 8 before the tip."""
    return int((length - 8.0 - 11.0) // PITCH) + 1


def beam(length: float):
    """The chambers' x spans, EI(x) about the sheet and M_p(x) / p of the module docstring."""
    spans = [(5.0 + PITCH * i, 11.0 + PITCH * i) for i in range(chamber_count(length))]

    def inside(x: float) -> bool:
        return any(a < x < b for a, b in spans)

    def stiffness(x: float) -> float:
        return E_PLANE * (H**3 - ((6.0**3 - 2.0**3) if inside(x) else 0.0)) / 3

    def moment_per_pressure(x: float) -> float:
        return CHAMBER_HEIGHT * CHAMBER_MIDDLE if inside(x) else 0.0

    return [x for span in spans for x in span], stiffness, moment_per_pressure


def run(length: float, pressure: float, plate: bool):
    built = read_scene(tomllib.loads(actuator(length, pressure, plate)), "strip").build()
    return run_schedule(built)


def test_the_free_strip_turns_as_its_pressure_moment_about_the_sheet_bends_it():
    length, pressure = 100.0, 0.001
    breaks, stiffness, moment = beam(length)
    theta = quad(lambda x: pressure * moment(x) / stiffness(x), 0.0, length, points=breaks, limit=400)[0]
    result = run(length, pressure, plate=False)
    assert result.tip_rotation == pytest.approx(-math.degrees(theta), rel=0.05)


@pytest.mark.slow
def test_a_held_strips_blocked_force_is_the_beam_balance_of_its_pressure_moment():
    """The plate's force against the clamped-pinned beam's (module docstring), within 15 %; and the statics exactly:
    the clamp's force and moment balance the plate's (no other external force: the chambers are closed)."""
    length, pressure = 200.0, 0.0005
    result = run(length, pressure, plate=True)
    final = result.steps[-1]
    forces = result.contact_forces[-1]
    weights = np.linalg.norm(forces, axis=1)
    x_c = float(result.positions[-1][:, 0] @ weights / weights.sum())
    breaks, stiffness, moment = beam(length)
    work = quad(lambda x: (x_c - x) * pressure * moment(x) / stiffness(x), 0.0, x_c, points=breaks, limit=400)[0]
    compliance = quad(lambda x: (x_c - x) ** 2 / stiffness(x), 0.0, x_c, points=breaks, limit=400)[0]
    assert final.blocked_force == pytest.approx(work / compliance, rel=0.15)
    assert abs(final.tip_dy) < 0.01 * abs(run(length, pressure, plate=False).tip_deflection)  # held: it barely moves
    plate_fy = final.row()["plate.fy"]
    assert plate_fy > 0 and final.blocked_force == pytest.approx(plate_fy, rel=1e-9)
    # balanced to the solve's tolerance: 1e-6 of the sum of the terms' force norms, the sheet's and rubber's
    # internal forces, a thousand times the plate's force here
    assert final.clamp["fy"] == pytest.approx(-plate_fy, rel=1e-3)
    clamp_centre = result.mesh.vertices[result.mesh.pinned].mean(axis=0)
    assert final.clamp["mz"] == pytest.approx(-(x_c - clamp_centre[0]) * plate_fy, rel=1e-3)
