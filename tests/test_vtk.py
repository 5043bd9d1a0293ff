"""ParaView files: the VTU of every step and the PVD indexing them, read back with meshio."""

import xml.etree.ElementTree as ET

import meshio
import numpy as np
import pytest

import taichi_pneuma as tp
from taichi_pneuma.apps.inflate import main
from taichi_pneuma.materials import lame_parameters
from taichi_pneuma.render.paraview import VtkSeries


def read_pvd(path):
    """[(timestep, file path)] of a PVD collection."""
    root = ET.parse(path).getroot()
    assert root.get("type") == "Collection"
    return [(float(d.get("timestep")), path.parent / d.get("file")) for d in root.iter("DataSet")]


def deformation_gradient(rest, current, triangles):
    """F per triangle by solving F Dm = Ds (written here independently of fields.py)."""
    edges = lambda p: np.stack([p[triangles[:, 1]] - p[triangles[:, 0]], p[triangles[:, 2]] - p[triangles[:, 0]]], 2)
    return np.array([np.linalg.solve(dm.T, ds.T).T for dm, ds in zip(edges(rest), edges(current))])


def signed_areas(points, triangles):
    a, b, c = (points[triangles[:, i]] for i in range(3))
    return 0.5 * ((b - a)[:, 0] * (c - a)[:, 1] - (b - a)[:, 1] * (c - a)[:, 0])


@pytest.fixture(scope="module")
def run():
    return tp.simulate(tp.reference_scene(cy=0.15, growth=2.5, steps=4, max_area=0.01))


def test_every_step_reads_back_with_its_fields(run, tmp_path):
    pvd = VtkSeries(tmp_path, "ramp", run.built).write_all(run)
    entries = read_pvd(pvd)
    assert [t for t, _ in entries] == [0.0, 1.0, 2.0, 3.0]
    mesh, (mu, lam) = run.mesh, lame_parameters(1e4, 0.45)
    for (step, path), positions, record in zip(entries, run.positions, run.steps):
        grid = meshio.read(path)
        assert np.array_equal(grid.points, np.column_stack([mesh.vertices, np.zeros(mesh.n_vertices)]))
        assert np.array_equal(grid.cells_dict["triangle"], mesh.triangles)
        u = grid.point_data["displacement"]
        assert u.shape == (mesh.n_vertices, 3) and np.all(u[:, 2] == 0)
        current = grid.points[:, :2] + u[:, :2]
        assert np.allclose(current, positions, rtol=0, atol=1e-14)
        # det F of a linear triangle is its area ratio; the smallest is the Taichi kernel's min det F
        det = grid.cell_data["det_F"][0]
        assert det == pytest.approx(
            signed_areas(current, mesh.triangles) / signed_areas(mesh.vertices, mesh.triangles), rel=1e-10
        )
        assert det.min() == pytest.approx(record.min_det, rel=1e-10)
        F = deformation_gradient(mesh.vertices, current, mesh.triangles)
        C_eigen = np.linalg.eigvalsh(np.swapaxes(F, 1, 2) @ F)
        assert grid.cell_data["max_stretch"][0] == pytest.approx(np.sqrt(C_eigen[:, 1]), rel=1e-9)
        # stress in ParaView's order XX, YY, ZZ, XY, YZ, XZ: sigma = mu/J F F^T - (mu + lam (1 - J)) I
        stress = grid.cell_data["stress"][0]
        b = F @ np.swapaxes(F, 1, 2)
        iso = mu + lam * (1 - det)
        assert stress[:, 0] == pytest.approx(mu / det * b[:, 0, 0] - iso, rel=1e-8, abs=1e-6)
        assert stress[:, 1] == pytest.approx(mu / det * b[:, 1, 1] - iso, rel=1e-8, abs=1e-6)
        assert stress[:, 2] == pytest.approx(mu / det - iso, rel=1e-8, abs=1e-6)
        assert stress[:, 3] == pytest.approx(mu / det * b[:, 0, 1], rel=1e-8, abs=1e-6)
        assert np.all(stress[:, 4:] == 0)
        xx, yy, zz, xy = stress[:, :4].T
        vm = np.sqrt(((xx - yy) ** 2 + (yy - zz) ** 2 + (zz - xx) ** 2) / 2 + 3 * xy**2)
        assert grid.cell_data["von_mises"][0] == pytest.approx(vm, rel=1e-10)
        chamber = grid.point_data["chamber"]
        assert np.all(chamber[mesh.chambers[0]] == 0) and np.sum(chamber == 0) == len(mesh.chambers[0])
        assert np.all(chamber[np.setdiff1d(np.arange(mesh.n_vertices), mesh.chambers[0])] == -1)
        fields = grid.field_data
        assert fields["step"][0] == step
        assert fields["main.pressure"][0] == record.chambers["main"].pressure
        assert fields["main.area"][0] == record.chambers["main"].area
        assert fields["tip_dy"][0] == record.tip_dy
    assert run.steps[-1].chambers["main"].pressure > 0 and grid.cell_data["von_mises"][0].max() > 0


def test_a_failed_run_leaves_its_finished_steps_readable(tmp_path):
    out = tmp_path / "out"
    assert (
        main(
            [
                "--steps",
                "2",
                "--max-area",
                "0.01",
                "--max-iterations",
                "3",
                "--max-cuts",
                "0",
                "--no-video",
                "--quiet",
                "--out",
                str(out),
            ]
        )
        == 1
    )
    entries = read_pvd(out / "inflate_cy+0.15_steps2_max_area0.01.pvd")
    assert [t for t, _ in entries] == [0.0]  # the rest state converged, step 1 did not
    grid = meshio.read(entries[0][1])
    assert np.all(grid.point_data["displacement"] == 0) and grid.field_data["converged"][0] == 1
    assert sorted(p.name for p in (out / "inflate_cy+0.15_steps2_max_area0.01_vtk").iterdir()) == [
        "inflate_cy+0.15_steps2_max_area0.01_0000.vtu"
    ]


def test_contact_scenes_write_the_contact_force(tmp_path):
    scene = tp.load_scene("finger_on_ground").with_values(
        {
            "mesh.max_area": 0.02,
            "schedule.increments": 2,
            **{f"chambers[{i}].keyframes": [[2, 200.0]] for i in range(5)},
        }
    )
    result = tp.simulate(scene)
    entries = read_pvd(VtkSeries(tmp_path, "f", result.built).write_all(result))
    force = meshio.read(entries[-1][1]).point_data["contact_force"]
    assert np.allclose(force[:, :2], result.contact_forces[-1], rtol=0, atol=1e-12) and np.all(force[:, 2] == 0)
    assert force[:, 1].sum() == pytest.approx(result.steps[-1].contact["ground"][1], rel=1e-9)
    assert force[:, 1].sum() > 0  # the ground pushes up


def test_quadratic_elements_are_vtk_six_node_triangles_with_their_mean_det_f(tmp_path):
    """P2: cells are 'triangle6' on the mesh's nodes; det F is the element's mean, its curved current area
    (parabolic sides a, m, b: 1/6 (4 a x m + 4 m x b - a x b) each) over its rest area."""
    result = tp.simulate(tp.reference_scene(cy=0.15, growth=2.0, steps=3, max_area=0.02, order=2))
    entries = read_pvd(VtkSeries(tmp_path, "p2", result.built).write_all(result))
    grid = meshio.read(entries[-1][1])
    elements = grid.cells_dict["triangle6"]
    assert np.array_equal(elements, result.mesh.triangles)
    x = grid.points[:, :2] + grid.point_data["displacement"][:, :2]
    cross = lambda a, b: a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]
    area = lambda p: sum(
        (4 * cross(p[a], p[m]) + 4 * cross(p[m], p[b]) - cross(p[a], p[b])) / 6
        for a, m, b in ((0, 3, 1), (1, 4, 2), (2, 5, 0))
    )
    rest = grid.points[:, :2]
    ratio = area(np.swapaxes(x[elements], 0, 1)) / area(np.swapaxes(rest[elements], 0, 1))
    assert grid.cell_data["det_F"][0] == pytest.approx(ratio, rel=1e-10)
    assert np.ptp(ratio) > 0.05  # a real, uneven deformation
