"""3D bodies from mesh files (meshio formats, groups by name) through scene files, the API and the command line;
their result files: VTU tetrahedra (4- and 10-node) with the chamber walls, history, npz, summary."""

import dataclasses
import json
import os
from pathlib import Path

import meshio
import numpy as np
import pytest
from solid_meshes import DEPTH, extruded_beam, scene_of, shell_octant

import taichi_pneuma as tp
from taichi_pneuma.apps.inflate import main
from taichi_pneuma.errors import PneumaInputError
from taichi_pneuma.fem.elements import TET_P2
from taichi_pneuma.fem.meshfile import MeshBody, MeshGeometry, MeshSurface, read_mesh, write_mesh
from taichi_pneuma.fem.planar import Geometry
from taichi_pneuma.fem.shapes import Ellipse, Rectangle
from taichi_pneuma.fem.supports import PointSet, Roller
from taichi_pneuma.render.paraview import VtkSeries
from taichi_pneuma.scene.build import ChamberControl, Scene
from taichi_pneuma.scene.schedule import ChamberSchedule, area_ramp

SCENES = Path(__file__).resolve().parents[1] / "taichi_pneuma" / "scenes"
ROLLERS = """
[[rollers]]
normal = [0.0, 0.0, 1.0]
point = [0.0, 0.0, 0.0]

[[rollers]]
normal = [0.0, 0.0, 1.0]
point = [0.0, 0.0, 0.8]
"""


def write_msh(path, mesh):
    """The mesh (tetrahedra: group "body"), its chamber wall turned inside out (group "chamber"), as write_mesh
    writes it (gmsh 2.2 or Abaqus by the file's suffix)."""
    wall = mesh.chambers[0]
    return write_mesh(
        path, dataclasses.replace(mesh, chambers=(wall[:, list(mesh.family.facet_family.mirror)],)), ("chamber",)
    )


def scene_text(mesh_file, order=1, steps=2, more=""):
    return f"""name = "beam3d"
[body]
shape = "mesh"
file = "{mesh_file}"
[mesh]
order = {order}
[[chambers]]
name = "main"
shape = "mesh_surface"
group = "chamber"
control = "volume"
stiffness = {1e5 / DEPTH}
keyframes = [[0, 1.0], [{steps}, 1.5]]
[schedule]
increments = {steps}
[clamp]
side = "left"
{ROLLERS}{more}"""


@pytest.mark.parametrize("order, file_format", [(1, "gmsh22"), (2, "gmsh22"), (1, "abaqus"), (2, "abaqus")])
def test_a_mesh_file_reads_back_to_the_mesh_it_was_written_from(tmp_path, order, file_format):
    """Linear tetrahedra, and quadratic ones written as 10-node cells (in gmsh's own node order in a .msh file,
    VTK's once read) and read as they are, from gmsh 2.2 physical groups or Abaqus element sets (gmsh 4.1: the
    shipped scene); the chamber wall written inside out comes back oriented out of the cavity."""
    mesh, _ = extruded_beam(0.1, order, chamber_points=16)
    path = write_msh(tmp_path / ("beam.inp" if file_format == "abaqus" else "beam.msh"), mesh)
    geometry = MeshGeometry(MeshBody(str(path)), (("main", MeshSurface("chamber")),), order, rollers=mesh_rollers())
    read = geometry.mesh()
    assert np.array_equal(read.vertices, mesh.vertices) and np.array_equal(read.elements, mesh.elements)
    assert np.array_equal(read.chambers[0], mesh.chambers[0])
    assert np.array_equal(read.regions, np.full(mesh.n_elements, 1 if file_format == "gmsh22" else 0))
    estimate = geometry.size_estimate()
    assert (estimate.elements, estimate.nodes) == (mesh.n_elements, mesh.n_vertices)


def test_a_mesh_file_rewritten_with_its_size_and_time_stamp_is_read_again(tmp_path):
    """A file rewritten in place with the same size and modification time (as a clock too coarse to tell two writes
    apart leaves it) but its first two nodes swapped is read anew: the second read has them swapped."""
    mesh, _ = extruded_beam(0.1, 1, chamber_points=16)
    path = write_msh(tmp_path / "beam.msh", mesh)
    first = read_mesh(str(path)).points.copy()
    before = os.stat(path)
    lines = path.read_bytes().split(b"\n")
    k = lines.index(b"$Nodes") + 2  # the first node's line, after the count
    (a, _, x), (b, _, y) = lines[k].partition(b" "), lines[k + 1].partition(b" ")
    lines[k], lines[k + 1] = a + b" " + y, b + b" " + x
    path.write_bytes(b"\n".join(lines))
    os.utime(path, ns=(before.st_atime_ns, before.st_mtime_ns))
    after = os.stat(path)
    assert (after.st_size, after.st_mtime_ns) == (before.st_size, before.st_mtime_ns) and x != y
    assert np.array_equal(read_mesh(str(path)).points, first[[1, 0, *range(2, len(first))]])


def mesh_rollers():
    return (Roller((0.0, 0.0, 1.0), (0.0, 0.0, 0.0)), Roller((0.0, 0.0, 1.0), (0.0, 0.0, DEPTH)))


def test_the_shipped_gmsh_scene_encloses_the_cavity_the_box_has_lost():
    """taichi_pneuma/scenes/beam_3d.toml (a gmsh mesh): the chamber's rest volume is the box's volume less the
    tetrahedra's (the outer boundary is the box itself), for linear and for quadratic tetrahedra."""
    scene = tp.load_scene(SCENES / "beam_3d.toml")
    for order in (1, 2):
        built = scene.with_value("mesh.order", order).build()
        lost = 3.5 * 0.8 * 0.8 - built.mesh.volume
        assert built.chambers[0].rest_area == pytest.approx(lost, rel=1e-9)
        assert built.mesh.order == order and 0.18 < lost < 0.2  # the ellipsoid's 4/3 pi 0.85 0.22 0.25 = 0.196
    assert scene.to_toml().count('shape = "mesh') == 2


def test_mesh_paths_are_relative_to_the_scene_file_and_round_trip(tmp_path):
    mesh, _ = extruded_beam(0.2, chamber_points=8)
    (tmp_path / "meshes").mkdir()
    write_msh(tmp_path / "meshes" / "beam.msh", mesh)
    (tmp_path / "scene.toml").write_text(scene_text("meshes/beam.msh"))
    scene = tp.load_scene(tmp_path / "scene.toml")
    assert scene.geometry.body.file == str(tmp_path / "meshes" / "beam.msh")
    (tmp_path / "elsewhere.toml").write_text(scene.to_toml())
    assert tp.load_scene(tmp_path / "elsewhere.toml") == scene
    assert scene.with_value("chambers[0].stiffness", 2e5).controls[0].kind.stiffness == 2e5


@pytest.mark.parametrize(
    "case, message",
    [
        ("missing group", "has no group 'cavity' \\(its groups: chamber, body\\)"),
        ("no file", "does not exist"),
        ("not a mesh", "cannot be read by meshio"),
        ("no tetrahedra", "has no tetrahedra"),
        ("max_area", "mesh.max_area: a mesh file's body keeps the file's elements"),
        ("open wall", "lies on no roller plane"),
        ("surface on a 2D body", "needs a body from a mesh file"),
        ("polygon wall on a mesh body", "chambers are the mesh file's groups"),
        ("3D roller on a 2D body", "a 2D body's rollers have 2 components"),
        ("self contact", "self_contact is 2D only"),
    ],
)
def test_bad_mesh_scenes_are_one_clear_error(tmp_path, case, message):
    mesh, _ = extruded_beam(0.2, chamber_points=8)
    write_msh(tmp_path / "beam.msh", mesh)
    text = scene_text("beam.msh")
    if case == "missing group":
        text = text.replace('group = "chamber"', 'group = "cavity"')
    elif case == "no file":
        text = text.replace("beam.msh", "gone.msh")
    elif case == "not a mesh":
        (tmp_path / "beam.msh").write_text("$MeshFormat\nnonsense\n")
    elif case == "no tetrahedra":
        meshio.write(
            tmp_path / "beam.msh", meshio.Mesh(mesh.vertices, [("triangle", mesh.surface)]), "gmsh22", binary=False
        )
    elif case == "max_area":
        text = text.replace("order = 1", "order = 1\nmax_area = 0.01")
    elif case == "open wall":
        text = text.replace(ROLLERS, "")
    elif case == "self contact":
        text += "\n[effects.self_contact]\n"
    path = tmp_path / "scene.toml"
    path.write_text(text)
    with pytest.raises(PneumaInputError, match=message):
        if case == "surface on a 2D body":
            Geometry(Rectangle((0.0, 0.0), (1.0, 1.0)), (("c", MeshSurface("chamber")),))
        elif case == "polygon wall on a mesh body":
            MeshGeometry(MeshBody(str(tmp_path / "beam.msh")), (("c", Ellipse((0.0, 0.0), (0.1, 0.1))),))
        elif case == "3D roller on a 2D body":
            Geometry(Rectangle((0.0, 0.0), (1.0, 1.0)), (), rollers=(Roller((0.0, 0.0, 1.0), (0.0, 0.0, 0.0)),))
        else:
            tp.load_scene(path).build()


def test_inflate_runs_a_mesh_file_scene_and_writes_3d_results(tmp_path, capsys):
    """The command line on a mesh-file scene: the summary line of 2D plus tip dz and the bend angle; VTU files of
    tetrahedra and chamber-wall triangles whose det F is each tetrahedron's volume ratio; history with tip_dz;
    npz with the tetrahedra; summary JSON."""
    mesh, _ = extruded_beam(0.1, chamber_points=16)
    write_msh(tmp_path / "beam.msh", mesh)
    (tmp_path / "beam3d.toml").write_text(scene_text("beam.msh"))
    out = tmp_path / "out"
    assert main(["--scene", str(tmp_path / "beam3d.toml"), "--no-video", "--quiet", "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert f"mesh {mesh.n_vertices} vertices, {mesh.n_elements} tetrahedra" in printed
    assert "main: volume control, wall" in printed and "rest volume" in printed and "main: volume" in printed
    line = next(x for x in printed.splitlines() if x.startswith("tip deflection (mean y displacement of the right"))
    assert line.startswith("tip deflection (mean y displacement of the right face)")
    summary = json.loads((out / "beam3d_summary.json").read_text())
    assert f"{summary['tip_deflection']:+.4f}; tip dz {summary['tip_dz']:+.4f}; bend angle" in line
    assert summary["tetrahedra"] == mesh.n_elements and summary["all_converged"]
    assert abs(summary["tip_deflection"]) > 0.01 and abs(summary["tip_dz"]) < 1e-6
    header = (out / "beam3d_history.csv").read_text().splitlines()[0].split(",")
    assert header[header.index("tip_dy") + 1 : header.index("tip_dy") + 3] == ["tip_dz", "tip_rotation"]
    states = np.load(out / "beam3d_states.npz")
    assert np.array_equal(states["tetrahedra"], mesh.elements) and states["positions"].shape == (3, mesh.n_vertices, 3)
    grid = meshio.read(out / "beam3d_vtk" / "beam3d_0002.vtu")
    assert np.array_equal(grid.cells_dict["tetra"], mesh.elements)
    assert np.array_equal(grid.cells_dict["triangle"], mesh.chambers[0])
    current = grid.points + grid.point_data["displacement"]
    x = lambda p: p[mesh.elements]
    volume = lambda p: np.linalg.det(np.stack([x(p)[:, i] - x(p)[:, 0] for i in (1, 2, 3)], axis=2))
    assert grid.cell_data["det_F"][0] == pytest.approx(volume(current) / volume(grid.points), rel=1e-10)
    assert np.all(np.isnan(grid.cell_data["det_F"][1])) and np.all(grid.cell_data["chamber"][1] == 0)
    assert np.array_equal(grid.cell_data["chamber"][0], np.full(mesh.n_elements, -1))
    tip_dz = states["positions"][2][mesh.tip, 2].mean() - mesh.vertices[mesh.tip, 2].mean()
    assert grid.field_data["tip_dz"][0] == pytest.approx(tip_dz, abs=1e-14)


def test_quadratic_tetrahedra_are_written_as_vtk_tetra10_with_their_mean_det_f(tmp_path):
    """The octant of the pressurised shell with curved quadratic tetrahedra: cells 'tetra10' on the mesh's nodes (and
    'triangle6' on the wall), det F the mean over the element: its current volume over its rest volume, each here
    by a conical product rule exact for det dX/dxi."""
    mesh = shell_octant(2, 1, order=2, curved=True)
    result = tp.simulate(scene_of(mesh, [ChamberSchedule("pressure", ((1, 300.0),))], 1))
    grid = meshio.read(read_last(VtkSeries(tmp_path, "shell", result.built).write_all(result)))
    assert np.array_equal(grid.cells_dict["tetra10"], mesh.elements) and "triangle6" in grid.cells_dict
    s, w = np.polynomial.legendre.leggauss(4)  # a Stroud conical product rule, exact for det J (cubic)
    s, w = 0.5 * (s + 1), 0.5 * w
    a, b, c = np.meshgrid(s, s, s, indexing="ij")
    points = np.column_stack([a.ravel(), (b * (1 - a)).ravel(), (c * (1 - a) * (1 - b)).ravel()])
    weights = (w[:, None, None] * w[None, :, None] * w[None, None, :] * (1 - a) ** 2 * (1 - b)).ravel()
    dN = TET_P2.shape_gradients(points)
    volume = lambda p: np.einsum("q,mq->m", weights, np.linalg.det(np.einsum("mai,qaj->mqij", p[mesh.elements], dN)))
    current = grid.points + grid.point_data["displacement"]
    # (the element's degree-2 rule integrates det dX/dxi, a cubic on a curved element, to 5e-5 here)
    assert grid.cell_data["det_F"][0] == pytest.approx(volume(current) / volume(grid.points), rel=2e-4)
    assert np.ptp(grid.cell_data["det_F"][0]) > 1e-3


def read_last(pvd: Path) -> Path:
    return sorted((pvd.parent / f"{pvd.stem}_vtk").glob("*.vtu"))[-1]


def test_the_api_simulates_and_saves_a_3d_scene(tmp_path):
    mesh, _ = extruded_beam(0.2, chamber_points=8)
    write_msh(tmp_path / "beam.msh", mesh)
    (tmp_path / "beam3d.toml").write_text(scene_text("beam.msh"))
    result = tp.simulate(tp.load_scene(tmp_path / "beam3d.toml"))
    fields = result.fields()
    assert fields["stress"].shape == (mesh.n_elements, 3, 3) and fields["von_mises"].shape == (mesh.n_elements,)
    assert np.all(fields["max_stretch"] >= 1.0 - 1e-12)
    written = result.save(tmp_path / "out")
    assert {p.name for p in written} >= {
        "beam3d_history.csv",
        "beam3d_states.npz",
        "beam3d_plot.png",
        "beam3d_scene.toml",
        "beam3d_summary.json",
        "beam3d.pvd",
    }


def test_a_3d_material_region_is_a_box_of_six_numbers(tmp_path):
    mesh, _ = extruded_beam(0.2, chamber_points=8)
    write_msh(tmp_path / "beam.msh", mesh)
    region = "\n[material]\nregions = [{ box = [0, -1, 0, 2, 1, 1], E = 5e4 }]\n"
    (tmp_path / "s.toml").write_text(scene_text("beam.msh", more=region))
    built = tp.load_scene(tmp_path / "s.toml").build()
    _, parameters = built.scene.element_material(built.mesh)
    _, (base, region) = built.scene.law_parameters()
    assert not np.allclose(base, region)
    inside = built.mesh.vertices[built.mesh.elements].mean(axis=1)[:, 0] >= 0
    assert np.all(parameters[inside] == region) and np.all(parameters[~inside] == base)
    assert inside.any() and not inside.all()
    with pytest.raises(PneumaInputError, match="must have 6 numbers on this 3D body"):
        built.scene.with_value("material.regions[0].box", [0, -1, 2, 1]).build()


def test_a_mesh_past_the_element_limit_is_refused_before_any_work(tmp_path, capsys):
    mesh, _ = extruded_beam(0.2, chamber_points=8)
    write_msh(tmp_path / "beam.msh", mesh)
    (tmp_path / "s.toml").write_text(scene_text("beam.msh", order=2))
    out = tmp_path / "out"
    assert main(["--scene", str(tmp_path / "s.toml"), "--no-video", "--max-triangles", "100", "--out", str(out)]) == 2
    error = capsys.readouterr().err
    assert f"the mesh would have about {mesh.n_elements:.3g} quadratic tetrahedra, counted 8 times" in error
    assert "the limit is 100 elements (--max-triangles raises it)" in error and not (out / "s_history.csv").exists()


def test_a_curved_quadratic_gmsh_mesh_is_read_as_is(tmp_path):
    """gmsh's own 10-node tetrahedra (its node order in the file), their cavity's midside nodes on the sphere: read
    as they are, the cavity's volume is much closer to the sphere's than the linear mesh's (gmsh optional)."""
    gmsh = pytest.importorskip("gmsh")
    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        box = gmsh.model.occ.addBox(-1.0, -0.5, -0.5, 2.0, 1.0, 1.0)
        ball = gmsh.model.occ.addSphere(0.0, 0.0, 0.0, 0.3)
        body, _ = gmsh.model.occ.cut([(3, box)], [(3, ball)])
        gmsh.model.occ.synchronize()
        walls = [t for d, t in gmsh.model.getBoundary(body, oriented=False) if gmsh.model.getType(d, t) == "Sphere"]
        gmsh.model.addPhysicalGroup(3, [t for _, t in body], name="body")
        gmsh.model.addPhysicalGroup(2, walls, name="chamber")
        gmsh.option.setNumber("Mesh.MeshSizeMax", 0.2)
        gmsh.model.mesh.generate(3)
        gmsh.write(str(tmp_path / "linear.msh"))
        gmsh.model.mesh.setOrder(2)
        gmsh.write(str(tmp_path / "curved.msh"))
    finally:
        gmsh.finalize()
    sphere = 4 / 3 * np.pi * 0.3**3
    errors = []
    for name in ("linear", "curved"):
        geometry = MeshGeometry(
            MeshBody(str(tmp_path / f"{name}.msh")),
            (("c", MeshSurface("chamber")),),
            order=1 if name == "linear" else 2,
            clamp=PointSet("left"),
        )
        built = Scene(geometry, (ChamberControl(area_ramp(1.1, 2)),), 1).build()
        assert built.mesh.elements.shape[1] == (4 if name == "linear" else 10)
        errors.append(abs(built.chambers[0].rest_area / sphere - 1))
    assert errors[1] < 0.05 * errors[0]
