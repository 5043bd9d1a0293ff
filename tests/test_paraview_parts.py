"""ParaView files beside the body: the fibres, sheets and obstacles as parts of the PVD, read back with meshio and
checked against the terms' own data computed here; and the PVD's timestep rule."""

import dataclasses
import xml.etree.ElementTree as ET

import meshio
import numpy as np
import pytest

import taichi_pneuma as tp
from taichi_pneuma.fem.fiber_paths import Line
from taichi_pneuma.render.paraview import VtkSeries, pressure_timesteps
from taichi_pneuma.terms.fibers import Cords, Fiber
from taichi_pneuma.terms.membrane import Membrane


def read_pvd(path):
    """{timestep: {name: file path}} of a PVD collection, checking each step's parts are numbered 0, 1, ..."""
    steps: dict = {}
    for d in ET.parse(path).getroot().iter("DataSet"):
        files = steps.setdefault(float(d.get("timestep")), {})
        assert int(d.get("part")) == len(files)
        files[d.get("name")] = path.parent / d.get("file")
    return steps


def current(grid):
    """A part's points at the step: rest points + its displacement."""
    return grid.points + grid.point_data["displacement [mm]"]


def terms(result, kind):
    return [t for t in result.built.model.terms if isinstance(t, kind)]


@pytest.fixture(scope="module")
def gripper(tmp_path_factory):
    """gripper_2d, coarse and linear, 3 increments to 45 kPa, its cylinder moved down 3 mm meanwhile."""
    scene = tp.load_scene("gripper_2d").with_values(
        {
            "mesh.max_area": 6.0,
            "mesh.order": 1,
            "schedule.increments": 3,
            **{f"chambers[{i}].keyframes": [[3, 45.0]] for i in range(8)},
            "obstacles[0].keyframes": [[3, [0.0, -3.0]]],
        }
    )
    result = tp.simulate(scene)
    out = tmp_path_factory.mktemp("gripper")
    return result, read_pvd(VtkSeries(out, "g", result.built).write_all(result))


def test_a_pressure_ramp_is_timed_by_its_pressure_and_lists_every_part(gripper):
    result, steps = gripper
    assert list(steps) == [s.chambers["l1"].pressure for s in result.steps] == [0.0, 15.0, 30.0, 45.0]
    for files in steps.values():
        assert list(files) == ["body", "sheets", "obstacles"]
        assert all(path.is_file() for path in files.values())
    body = meshio.read(steps[45.0]["body"])
    assert body.field_data["step"][0] == 3 and body.field_data["l1.pressure [kPa]"][0] == 45.0


def test_sheet_segments_carry_their_stress(gripper):
    """2D: each layer's segments at the body's positions, with the tension-only sheet's stress along them,
    E' g s (g = (s^2 - 1) / 2 the Green strain of the stretch s, E' = E / (1 - nu^2)), computed here."""
    result, steps = gripper
    membranes = terms(result, Membrane)
    cells = np.vstack([t.cells for t in membranes])
    for (_, files), positions in zip(steps.items(), result.positions):
        grid = meshio.read(files["sheets"])
        segments = grid.cells_dict["line"]
        x = current(grid)
        assert len(segments) == len(cells)
        assert np.allclose(x[segments][..., :2], positions[cells], rtol=0, atol=1e-12)
        assert np.all(x[:, 2] == 0)
        layer = grid.cell_data["layer"][0]
        assert np.array_equal(layer, np.repeat([0, 1], [len(t.cells) for t in membranes]))
        assert np.all(positions[cells[layer == 0]][..., 0] < 0) and np.all(positions[cells[layer == 1]][..., 0] > 0)
        rest = result.mesh.vertices[cells]
        edge = positions[cells[:, 1]] - positions[cells[:, 0]]
        s = np.linalg.norm(edge, axis=1) / np.linalg.norm(rest[:, 1] - rest[:, 0], axis=1)
        g = (s**2 - 1) / 2
        sheet = result.scene.layers[0]
        tension = sheet.E / (1 - sheet.nu**2) * np.maximum(g, 0) * s
        t = edge / np.linalg.norm(edge, axis=1)[:, None]
        stress = grid.cell_data["stress [kPa]"][0]
        expected = (
            np.column_stack([t[:, 0] ** 2, t[:, 1] ** 2, 0 * s, t[:, 0] * t[:, 1], 0 * s, 0 * s]) * tension[:, None]
        )
        assert stress == pytest.approx(expected, rel=1e-9, abs=1e-9 * np.abs(expected).max() + 1e-12)
        assert grid.cell_data["max_stretch"][0] == pytest.approx(s, rel=1e-12)
    assert np.abs(stress).max() > 100  # the sheet is stretched: kPa


def test_an_earlier_runs_part_files_are_removed_when_a_series_starts(gripper, tmp_path):
    result, _ = gripper
    folder = tmp_path / "g_vtk"
    folder.mkdir()
    for name in ("g_0007.vtu", "g_sheets_0007.vtu", "g_obstacles_0007.vtu", "g_fibers_0007.vtu", "other_0007.vtu"):
        (folder / name).write_text("old")
    VtkSeries(tmp_path, "g", result.built).write(result.steps[0], result.positions[0])
    assert sorted(p.name for p in folder.iterdir()) == [
        "g_0000.vtu",
        "g_obstacles_0000.vtu",
        "g_sheets_0000.vtu",
        "other_0007.vtu",
    ]


def test_the_2d_obstacle_outline_follows_its_keyframes(gripper):
    result, steps = gripper
    for (_, files), step in zip(steps.items(), result.steps):
        grid = meshio.read(files["obstacles"])
        polygon = next(iter(grid.cells_dict.values()))
        assert polygon.shape == (1, len(grid.points))
        centre = np.array([0.0, 30.0 - step.step, 0.0])  # keyframes: down 3 mm over 3 steps
        assert np.allclose(result.obstacle_positions()[step.step, 0], centre)
        x = current(grid)
        assert np.linalg.norm(x - centre, axis=1) == pytest.approx(16.0, rel=1e-12)
        assert np.all(x[:, 2] == 0) and np.all(grid.cell_data["obstacle"][0] == 0)


def test_a_held_objects_height_moves_its_outline_as_in_the_npz(gripper, tmp_path):
    """A held object's height (the history's '<name>.dy') moves its outline as it moves obstacle_positions."""
    result, _ = gripper
    steps = [dataclasses.replace(s, extra={**s.extra, "object.dy": -0.25 * s.step}) for s in result.steps]
    held = dataclasses.replace(result, steps=steps)
    files = read_pvd(VtkSeries(tmp_path, "h", result.built).write_all(held))
    for (_, paths), centre in zip(files.items(), held.obstacle_positions()[:, 0]):
        x = current(meshio.read(paths["obstacles"]))
        assert np.linalg.norm(x - centre, axis=1) == pytest.approx(16.0, rel=1e-12)
    assert centre[1] == 30.0 - 3.0 - 0.75


def test_fibres_are_lines_at_their_embedded_points_with_their_tension(tmp_path):
    """3D: each cord segment a line between its embedded points p = sum_i w_i x_i, tension E A (l / L0 - 1) where
    taut (A = pi d^2 / 4 of the scene's fibre), computed here from the term's embedding."""
    scene = tp.load_scene("fiber_bending_3d").with_values(
        {"mesh.size": 10.0, "mesh.order": 1, "schedule.increments": 2, "chambers[0].keyframes": [[2, 40.0]]}
    )
    result = tp.simulate(scene)
    steps = read_pvd(VtkSeries(tmp_path, "f", result.built).write_all(result))
    assert list(steps) == [0.0, 20.0, 40.0]
    (cords,) = terms(result, Cords)
    fiber = scene.fibers[0]
    EA = fiber.E * np.pi * fiber.diameter**2 / 4
    embedded = lambda x: np.einsum("pi,pid->pd", cords.weights, x[cords.nodes])  # noqa: E731
    L0 = np.linalg.norm(np.diff(embedded(result.mesh.vertices)[cords.segments], axis=1)[:, 0], axis=1)
    for (_, files), positions in zip(steps.items(), result.positions):
        assert list(files) == ["body", "fibers", "sheets"]
        grid = meshio.read(files["fibers"])
        lines = grid.cells_dict["line"]
        assert np.array_equal(lines, cords.segments)
        p = embedded(positions)
        assert np.allclose(current(grid), p, rtol=0, atol=1e-10)
        tension = grid.cell_data["tension [mN]"][0]
        assert tension.shape == (len(lines),)
        l = np.linalg.norm(p[lines[:, 1]] - p[lines[:, 0]], axis=1)
        assert tension == pytest.approx(EA * np.maximum(l / L0 - 1, 0), rel=1e-6, abs=1e-9 * EA)
        assert grid.cell_data["stretch"][0] == pytest.approx(l / L0, rel=1e-9)
        assert np.all(grid.cell_data["fiber"][0] == 0)
        sheets = meshio.read(files["sheets"])
        check_sheet_triangles(sheets, terms(result, Membrane), positions, scene.layers[0].E)
    assert tension.max() > 0 and np.count_nonzero(tension == 0) > 0  # some cords taut, some slack


def test_2d_fibres_are_lines_in_the_plane_with_the_terms_tension(tmp_path):
    """2D: a fibre below the reference beam's axis, its lines at z = 0, tension (per unit depth; the scene has no
    units: bare names) the term's."""
    fiber = Fiber(Line((-1.7, -0.3), (1.7, -0.3)), 1e5, area=0.01)
    result = tp.simulate(dataclasses.replace(tp.reference_scene(max_area=0.05, steps=3), fibers=(fiber,)))
    steps = read_pvd(VtkSeries(tmp_path, "r", result.built).write_all(result))
    assert list(steps) == [0.0, 1.0, 2.0]  # an area ratio drives it: the step
    (cords,) = terms(result, Cords)
    for (_, files), positions in zip(steps.items(), result.positions):
        grid = meshio.read(files["fibers"])
        x = grid.points + grid.point_data["displacement"]
        assert np.all(x[:, 2] == 0)
        assert np.allclose(x[:, :2], np.einsum("pi,pid->pd", cords.weights, positions[cords.nodes]), atol=1e-12)
        assert np.array_equal(grid.cell_data["tension"][0], cords.tension(positions - result.mesh.vertices))
    assert grid.cell_data["tension"][0].max() > 0


def check_sheet_triangles(grid, membranes, positions, E):
    """3D sheets: the membranes' triangles at the body's positions, their stress symmetric, in the sheet's plane
    (sigma n = 0) and, the wrinkling sheet carrying no compression, positive semi-definite, and zero where no
    principal stretch passes 1 (the sheet's modulus E)."""
    triangles = grid.cells_dict["triangle"]
    cells = np.vstack([t.cells for t in membranes])
    assert np.allclose(current(grid)[triangles], positions[cells], rtol=0, atol=1e-10)
    xx, yy, zz, xy, yz, xz = grid.cell_data["stress [kPa]"][0].T
    sigma = np.stack([np.stack([xx, xy, xz], -1), np.stack([xy, yy, yz], -1), np.stack([xz, yz, zz], -1)], -1)
    x = positions[cells]
    n = np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0])
    n /= np.linalg.norm(n, axis=1)[:, None]
    scale = np.abs(sigma).max()
    assert np.abs(np.einsum("fij,fj->fi", sigma, n)).max() < 1e-8 * scale
    assert np.linalg.eigvalsh(sigma).min() > -1e-8 * scale
    slack = grid.cell_data["max_stretch"][0] <= 1  # no principal strain > 0: no stress (but round-off's)
    assert np.abs(sigma[slack]).max(initial=0) < 1e-12 * E


def test_3d_sheets_and_a_sphere_obstacle(tmp_path):
    scene = tp.load_scene("gripper_3d").with_values(
        {
            "mesh.size": 12.0,
            "mesh.order": 1,
            "schedule.increments": 1,
            **{f"chambers[{i}].keyframes": [[1, 10.0]] for i in range(8)},
        }
    )
    result = tp.simulate(scene)
    steps = read_pvd(VtkSeries(tmp_path, "g3", result.built).write_all(result))
    assert list(steps) == [0.0, 10.0]
    files = steps[10.0]
    assert list(files) == ["body", "sheets", "obstacles"]
    check_sheet_triangles(
        meshio.read(files["sheets"]), terms(result, Membrane), result.positions[-1], scene.layers[0].E
    )
    ball = meshio.read(files["obstacles"])
    centre = result.obstacle_positions()[-1, 0]
    assert np.linalg.norm(current(ball) - centre, axis=1) == pytest.approx(16.0, rel=1e-12)
    assert len(ball.cells_dict["triangle"]) > 100


def test_the_timestep_is_the_step_unless_a_pressure_rises_at_every_step():
    gripper = tp.load_scene("gripper_2d")
    ramp = lambda *keyframes: gripper.with_values(  # noqa: E731
        {"schedule.increments": 3, **{f"chambers[{i}].keyframes": list(keyframes) for i in range(8)}}
    )
    assert pressure_timesteps(ramp([3, 30.0])) == [0.0, 10.0, 20.0, 30.0]
    assert pressure_timesteps(ramp([2, 30.0], [3, 10.0])) is None  # deflating
    assert pressure_timesteps(ramp([2, 30.0])) is None  # step 3 holds 30 kPa
    assert pressure_timesteps(tp.reference_scene(steps=3)) is None  # an area ratio, not a pressure
