"""The shipped 3D actuator scenes (fiber_bending_3d, blocked_force_3d, fiber_twist_3d) do what their descriptions
say, checked on coarse meshes and short ramps against facts that need no simulation: the sign of the bend (towards
the strain-limiting sheet), an inextensible sheet against a stretching top, hoop fibres against free radial growth,
the statics of a held actuator (the clamp's reaction balances the plate's force: the chamber's pressure, the fibres
and the sheet are internal), and the sense of twist a helix's handedness gives.

The twist's sense: a single helix of fixed length l wound on a tube of radius r and length h through a total angle
phi obeys l^2 = (r phi)^2 + h^2; pressure pushes r and h up, so phi must fall: the tube unwinds its helix. A
right-handed helix turns counter-clockwise about +x as it advances along +x; unwinding turns the tip (at +x)
clockwise seen from +x: a negative twist by the right-hand rule (fem/tip.py), a left-handed helix the opposite.

Measured (the coarse mesh: 716 nodes, 2153 linear tetrahedra for the bending actuator): at 30 kPa it turns by
-17.5 degrees (-2.6 without its threads), its sheet's length changes by 5e-5 and its top ridge's by +3.1 %; the
section's height grows by 0.52 mm (1.00 mm without threads); held, the plate's force is 47.7 and 97.8 mN at 10 and
20 kPa, balanced by the clamp's to 2e-4 of it, the tip within 0.02 mm of its height (free: -11.2 mm at 20 kPa);
the tube twists by -21.2 degrees at 40 kPa wound right-handed, +21.7 left-handed.
"""

from pathlib import Path

import numpy as np
import pytest

from taichi_pneuma.scene.scenefile import load_scene
from taichi_pneuma.solve.simulate import run_schedule

SCENES = Path(__file__).resolve().parents[1] / "taichi_pneuma" / "scenes"
NEW = ("fiber_bending_3d", "blocked_force_3d", "fiber_twist_3d")
COARSE = {"mesh.size": 8.0, "mesh.near_chambers": 4.0, "mesh.distance": 4.0, "mesh.order": 1}


def coarse(name: str, pressure: float, increments: int, **values):
    """The shipped scene on a coarse linear mesh, its chamber ramped to pressure in increments."""
    scene = load_scene(SCENES / f"{name}.toml").with_values(
        {
            **COARSE,
            "schedule.increments": increments,
            "chambers[0].keyframes": [[0, 0.0], [increments, pressure]],
            **values,
        }
    )
    return run_schedule(scene.build())


def binned_length(rest: np.ndarray, current: np.ndarray, bins: int = 10) -> tuple[float, float]:
    """(rest, current) length of the polyline through the centroids of points binned by their rest x."""
    edges = np.linspace(rest[:, 0].min(), rest[:, 0].max(), bins + 1)
    where = np.clip(np.digitize(rest[:, 0], edges) - 1, 0, bins - 1)
    lengths = []
    for points in (rest, current):
        centroids = np.array([points[where == b].mean(axis=0) for b in range(bins)])
        lengths.append(float(np.linalg.norm(np.diff(centroids, axis=0), axis=1).sum()))
    return lengths[0], lengths[1]


def section_growth(result) -> float:
    """How much the body's section grows in height over the middle third of its length, whichever way it has turned:
    the mean change of the distance from each node of its top ridge there (within 1 mm of the top) to the node of
    its bottom face nearest below it at rest (those within 1.5 mm of straight below)."""
    rest, current = result.mesh.vertices, result.positions[-1]
    span = np.ptp(rest[:, 0])
    top = np.flatnonzero(
        (rest[:, 1] > rest[:, 1].max() - 1.0) & (np.abs(rest[:, 0] - rest[:, 0].min() - span / 2) < span / 6)
    )
    bottom = np.flatnonzero(rest[:, 1] < rest[:, 1].min() + 1e-6)
    growth = []
    for t in top:
        offsets = np.linalg.norm(rest[bottom][:, [0, 2]] - rest[t, [0, 2]], axis=1)
        if offsets.min() < 1.5:
            b = bottom[np.argmin(offsets)]
            growth.append(np.linalg.norm(current[t] - current[b]) - np.linalg.norm(rest[t] - rest[b]))
    assert len(growth) >= 3
    return float(np.mean(growth))


@pytest.mark.parametrize("name", NEW)
def test_each_actuator_scene_loads_and_builds(name):
    built = load_scene(SCENES / f"{name}.toml").build()
    assert built.mesh.dim == 3 and built.mesh.n_elements > 0


@pytest.fixture(scope="module")
def bending():
    """The bending actuator (coarse) at 30 kPa with its fibres, and without them."""
    return coarse("fiber_bending_3d", 30.0, 3), coarse("fiber_bending_3d", 30.0, 3, fibers=[])


def test_the_bending_actuator_bends_towards_its_sheet_which_barely_stretches_while_its_top_does(bending):
    result = bending[0]
    assert result.converged and result.tip_rotation < -5  # clockwise about z: the tip turns down, to the sheet
    rest, current = result.mesh.vertices, result.positions[-1]
    bottom = rest[:, 1] < rest[:, 1].min() + 1e-6
    top = rest[:, 1] > rest[:, 1].max() - 1.0
    sheet = binned_length(rest[bottom], current[bottom])
    ridge = binned_length(rest[top], current[top])
    assert abs(sheet[1] / sheet[0] - 1) < 1e-3
    assert ridge[1] / ridge[0] - 1 > 0.02


def test_the_crossed_helix_holds_the_radial_growth_down(bending):
    wound, bare = bending
    assert wound.tip_rotation < 2 * bare.tip_rotation < 0  # the growth held goes into bending: -17.5 and -2.6 deg
    assert section_growth(bare) > 0
    assert section_growth(wound) < 0.7 * section_growth(bare)  # 0.53 and 1.01 mm measured (coarse, 30 kPa)


def test_the_held_actuators_force_grows_with_pressure_and_the_clamp_balances_the_plate():
    result = coarse("blocked_force_3d", 20.0, 2)
    low, high = result.steps[1], result.steps[2]
    assert 0 < low.blocked_force < high.blocked_force
    row = high.row()
    plate = np.array([row["plate.fx"], row["plate.fy"], row["plate.fz"]])
    clamp = np.array([high.clamp["fx"], high.clamp["fy"], high.clamp["fz"]])
    assert plate[1] > 0  # the plate pushes the tip up, away from the sheet's side
    assert np.linalg.norm(plate + clamp) < 2e-3 * np.linalg.norm(plate)  # 2e-4 measured: the solve's tolerance
    assert abs(high.tip_dy) < 0.1 * abs(coarse("fiber_bending_3d", 20.0, 1).tip_deflection)


def test_a_single_helix_twists_the_tube_against_its_winding():
    right = coarse("fiber_twist_3d", 40.0, 2).steps[-1].tip_twist
    left = coarse("fiber_twist_3d", 40.0, 2, **{"fibers[0].path.handedness": "left"}).steps[-1].tip_twist
    assert right < 0 < left
    assert abs(right + left) < 0.2 * abs(right)  # mirror images, but for the mesh
