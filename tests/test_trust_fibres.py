"""The trust issue's fibre, resource-cap, mesh-cache and locking repros: a fibre's points counted as they will be
made (a ring takes at least 3) and its Hessian priced as the solver allocates it, both before anything is made; the
segments between a fibre's samples kept out of the chambers; fibre names held to the chamber names' rule; caps on
the fibres and obstacles a scene holds, each raised by a flag; a mesh-cache entry used only if it is a regular file
holding this call's inputs and the arrays its content hash was made of; and the run's first line warning where
linear elements lock."""

import os
import threading
import tracemalloc
from pathlib import Path

import numpy as np
import pytest
from solid_meshes import box_with_cavity, scene_of
from test_untrusted_input import QUICK, error_line, files_under, reference_with

import taichi_pneuma as tp
from taichi_pneuma import limits, runtime
from taichi_pneuma.apps import inflate, reach, serve, steer, sweep
from taichi_pneuma.apps.inflate import main
from taichi_pneuma.errors import PneumaInputError
from taichi_pneuma.fem import embedding, sizing
from taichi_pneuma.fem.fiber_paths import Crossed, Helix, Line, Polyline, Rings
from taichi_pneuma.fem.gmsh_mesher import MeshSizes, Solid, mesh_solid
from taichi_pneuma.fem.solids import Box, Ellipsoid
from taichi_pneuma.io import cache
from taichi_pneuma.materials import IsochoricMaterial
from taichi_pneuma.scene.build import Material
from taichi_pneuma.scene.scenefile import load_scene
from taichi_pneuma.scene.schedule import ChamberSchedule
from taichi_pneuma.solve.linsolve import FixedPattern
from taichi_pneuma.study import RunOptions, Task, run_task
from taichi_pneuma.terms.fibers import Fiber
from taichi_pneuma.terms.model import Configuration


@pytest.fixture(scope="module", autouse=True)
def taichi():
    runtime.ensure_initialised()


# --- the points and the memory of a fibre, counted before sampling -------------------------------------------------

LAYOUTS = {
    "line": Line((0.0, 0.0, 0.0), (1.0, 0.3, 0.0)),
    "polyline": Polyline(((0.0, 0.0), (1.0, 0.0), (1.0, 0.7), (0.2, 0.9))),
    "rings": Rings((0.0, 0.0, 0.0), 0.2, 5, 0.3, "x"),
    "tiny rings": Rings((0.0, 0.0, 0.0), 1e-6, 4, 0.3, "y"),
    "helix": Helix((0.0, 0.0, 0.0), 0.3, turns=2.5, pitch=0.4, strands=3),
    "crossed": Crossed((0.0, 0.0, 0.0), 0.3, extent=3.4, axis="x", angle=30.0, strands=4),
    "flat crossed": Crossed((0.0, 0.0, 0.0), 0.3, turns=1.5, axis="z", angle=45.0, flat=0.1),
}


@pytest.mark.parametrize("spacing", [1e-3, 0.037, 0.25, 10.0])
@pytest.mark.parametrize("layout", LAYOUTS)
def test_every_layout_counts_its_curves_and_points_as_it_samples_them(layout, spacing):
    path = LAYOUTS[layout]
    curves = path.curves(spacing)
    assert path.size(spacing) == (len(curves), sum(len(c) for c in curves))


def test_a_hundred_million_tiny_rings_are_refused_before_a_point_is_made():
    """The old cap counted length / spacing (6e-4 here); each ring takes 3 points at least: 3e8."""
    mesh = box_with_cavity()
    rings = Fiber(Rings((-1.5, -0.2, 0.0), 1e-6, 10**8, 1e-9, "x"), 1e3, diameter=1e-3, name="rings")
    tracemalloc.start()
    try:
        with pytest.raises(
            PneumaInputError, match=r"fiber 'rings': spacing .* would sample it at 3e\+08 points; at mo"
        ):
            rings.terms(Configuration(mesh.vertices), mesh, None, limits.Budget())
        assert tracemalloc.get_traced_memory()[1] < 10**7  # refused before sampling
    finally:
        tracemalloc.stop()


def braid(strands: int, spacing: float | None = None) -> Fiber:
    """A crossed braid of `strands` helices of each hand around the box's axis, clear of its cavity."""
    path = Crossed((-1.7, 0.0, 0.0), 0.3, extent=3.4, axis="x", angle=30.0, strands=strands)
    return Fiber(path, 2e5, diameter=0.01, spacing=spacing, name="braid")


def test_a_fibre_hessian_entry_is_priced_at_what_the_solver_allocates_for_it():
    """The peak traced while the term is made, the Newton solver analyses its pattern (FixedPattern of the model's
    concatenated pattern) and assembles one matrix, per Hessian entry: BYTES_PER_FIBER_ENTRY covers it, within 1.5x."""
    mesh = box_with_cavity()
    config = Configuration(mesh.vertices)
    braid(1).terms(config, mesh, None, limits.Budget())[0].hessian_values()  # kernels compiled outside the trace
    tracemalloc.start()
    try:
        (term,) = braid(8, 0.02).terms(config, mesh, None, limits.Budget())
        rows, cols = (np.concatenate([part]) for part in term.hessian_pattern())  # EnergyModel.hessian_pattern's copy
        FixedPattern(rows, cols, mesh.vertices.size).matrix([term.hessian_values()])
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    per_entry = peak / (len(term.segments) * 24**2)
    assert per_entry <= limits.BYTES_PER_FIBER_ENTRY <= 1.5 * per_entry


def test_a_braid_of_256_strands_is_refused_in_the_default_budget_before_it_allocates():
    """20,480 segments of 576 entries: about 1 GB where the solver allocates them, priced at 24 bytes an entry (71k
    triangles' worth) it passed the default 200,000; it is refused now, naming the flag, before it allocates."""
    mesh = box_with_cavity()
    tracemalloc.start()
    try:
        with pytest.raises(PneumaInputError) as refused:
            braid(256, 0.099).terms(Configuration(mesh.vertices), mesh, None, limits.Budget(limits.MAX_TRIANGLES))
        assert tracemalloc.get_traced_memory()[1] < 10**7
    finally:
        tracemalloc.stop()
    message = str(refused.value)
    assert "20480 cord segments" in message and "11796480 Hessian entries" in message
    assert "the limit is 200000 triangles (--max-triangles raises it)" in message


# --- a fibre's segments stay in the rubber --------------------------------------------------------------------------


def box_fiber(start, end, spacing: float) -> Fiber:
    return Fiber(Line(start, end), 1e3, diameter=0.01, spacing=spacing, name="cord")


def test_a_fibre_whose_segment_crosses_the_cavity_between_two_samples_is_refused():
    """The box's cavity spans x in [-0.75, 0.75], y in [0, 0.2]: a cord at y = 0.1 sampled only at x = -1.5 and 1.5
    passed (both samples in the rubber); its segment leaves the rubber at x = -0.75."""
    mesh = box_with_cavity()
    config = Configuration(mesh.vertices)
    with pytest.raises(
        PneumaInputError, match=r"fiber 'cord': its segment .* leaves the body at \[-0\.75, 0\.1, 0\.0\]"
    ):
        box_fiber((-1.5, 0.1, 0.0), (1.5, 0.1, 0.0), 3.0).terms(config, mesh, None, limits.Budget())
    # past the first CHUNK segments: 111 passes along the box's bottom (10 segments each), then across the cavity floor
    passes = [(1.5 * (-1) ** (k + 1), -0.2, 0.0) for k in range(112)]
    zigzag = Fiber(Polyline((*passes, (0.0, -0.05, 0.0), (0.0, 0.25, 0.0))), 1e3, diameter=0.01, spacing=0.3, name="z")
    assert zigzag.path.size(0.3)[1] - 1 > embedding.CHUNK + 2
    with pytest.raises(
        PneumaInputError,
        match=r"from \[0\.0, -0\.05, 0\.0\] to \[0\.0, 0\.25, 0\.0\] leaves the body at \[0\.0, 0\.0, 0",
    ):
        zigzag.terms(config, mesh, None, limits.Budget())
    # from the cavity's floor to its ceiling: both ends on its wall, the segment across the air
    with pytest.raises(PneumaInputError, match=r"runs outside the body at its middle \[0\.0, 0\.1, 0\.0\]"):
        box_fiber((0.0, 0.0, 0.0), (0.0, 0.2, 0.0), 1.0).terms(config, mesh, None, limits.Budget())
    # a cord beside the cavity, and one along the body's outer face, stay in the rubber
    for y in (-0.1, -0.4):
        (term,) = box_fiber((-1.5, y, 0.0), (1.5, y, 0.0), 3.0).terms(config, mesh, None, limits.Budget())
        assert len(term.segments) == 1


def test_a_2d_cord_across_the_chamber_is_refused_in_one_line_and_nothing_is_written(tmp_path, capsys):
    """The reference beam's chamber spans x in [-0.85, 0.85] at y = 0.15; the cord's two samples lie beyond it."""
    fiber = (
        '\n[[fibers]]\nname = "cord"\nE = 1e5\narea = 0.001\nspacing = 3.0\n'
        'path = { layout = "line", start = [-1.2, 0.15], end = [1.2, 0.15] }\n'
    )
    path = reference_with(tmp_path, ("[schedule]", fiber + "[schedule]"))
    out = tmp_path / "out"
    assert main(["--scene", str(path), "--out", str(out), *QUICK]) == 2
    line = error_line(capsys)
    assert "fiber 'cord': its segment from [-1.2, 0.15] to [1.2, 0.15] leaves the body at [-0.85" in line
    assert not files_under(out)


# --- fibre names ----------------------------------------------------------------------------------------------------


FIBER_TABLE = (
    "[[fibers]]\nname = {name}\nE = 1e5\narea = 1e-5\n"
    'path = {{ layout = "line", start = [-1.6, {y}], end = [1.6, {y}] }}\n'
)


@pytest.mark.parametrize("name", ["x/../../escaped", "\tthread", "=1+2", "@sum", "-x", "+x", "\rx", "thread"])
def test_a_fibre_name_is_refused_exactly_where_a_chamber_name_is(tmp_path, name):
    quoted = '"' + name.replace("\t", "\\t").replace("\r", "\\r") + '"'
    fiber = FIBER_TABLE.format(name=quoted, y=-0.3)
    as_fiber = reference_with(tmp_path, ("[schedule]", fiber + "[schedule]"), file_name="f.toml")
    as_chamber = reference_with(tmp_path, ('name = "main"', f"name = {quoted}"), file_name="c.toml")

    def refusal(path: Path) -> str | None:
        try:
            load_scene(path)
        except PneumaInputError as exc:
            return str(exc)
        return None

    fiber_refused, chamber_refused = refusal(as_fiber), refusal(as_chamber)
    assert (fiber_refused is None) == (chamber_refused is None)
    if fiber_refused is not None:
        assert f"fiber name {name!r}" in fiber_refused


# --- how many fibres and obstacles a scene may hold -----------------------------------------------------------------

OBSTACLE_TABLE = '[[obstacles]]\nname = "o{k}"\nshape = "sphere"\ncenter = [{x}, -2.0]\nradius = 0.001\n'


def crowded(tmp_path, fibers: int, obstacles: int) -> Path:
    tables = [FIBER_TABLE.format(name=f'"f{k}"', y=-0.35 + 0.001 * k) for k in range(fibers)]
    tables += [OBSTACLE_TABLE.format(k=k, x=-1.7 + 0.008 * k) for k in range(obstacles)]
    return reference_with(tmp_path, ("[schedule]", "\n".join(tables) + "\n[schedule]"))


@pytest.mark.parametrize("table, flag, limit", [("fibers", "--max-fibers", 100), ("obstacles", "--max-obstacles", 400)])
def test_a_scene_past_the_fibre_or_obstacle_cap_is_refused_before_meshing_naming_its_flag(
    tmp_path, capsys, table, flag, limit
):
    counts = {"fibers": 0, "obstacles": 0, table: limit + 1}
    path = crowded(tmp_path, **counts)
    out = tmp_path / "out"
    assert main(["--scene", str(path), "--out", str(out), *QUICK]) == 2
    assert (
        error_line(capsys)
        == f"error: the scene has {limit + 1} [[{table}]] tables; the limit is {limit} ({flag} raises it)"
    )
    assert not files_under(out)
    scene = load_scene(path)
    with pytest.raises(PneumaInputError, match=f"the limit is {limit} \\({flag}"):
        sizing.check_scene(scene)
    sizing.check_scene(scene, **{f"max_{table}": limit + 1})  # raised by its flag's value


@pytest.mark.parametrize("app", [inflate, reach, steer, sweep, serve])
def test_every_app_that_builds_scenes_takes_both_caps(app):
    parser = app.parser()
    assert {"--max-fibers", "--max-obstacles"} <= set(parser._option_string_actions)
    assert parser.get_default("max_fibers") == limits.MAX_FIBERS
    assert parser.get_default("max_obstacles") == limits.MAX_OBSTACLES


def test_each_run_of_a_study_keeps_to_the_caps_it_was_given(tmp_path):
    text = crowded(tmp_path, 3, 0).read_text()
    row = run_task(Task(text, {}, RunOptions(max_fibers=2)))
    assert row["error"] == "the scene has 3 [[fibers]] tables; the limit is 2 (--max-fibers raises it)"


# --- the mesh cache -------------------------------------------------------------------------------------------------

SOLID = Solid(Box((0.0, 0.0, 0.0), (1.2, 0.6, 0.6)), (("c", Ellipsoid((0.0, 0.0, 0.0), (0.3, 0.15, 0.15))),))
SMALL = Solid(SOLID.body, (("c", Ellipsoid((0.0, 0.0, 0.0), (0.2, 0.1, 0.1))),))
SIZES = MeshSizes(0.3, near_chambers=0.15)


def rest_volume(mesh) -> float:
    """The chamber's volume, 1/6 sum over its wall of x0 . (x1 x x2)."""
    x = mesh.vertices[mesh.chambers["c"]]
    return float(np.einsum("fi,fi->f", x[:, 0], np.cross(x[:, 1], x[:, 2])).sum() / 6)


@pytest.mark.parametrize("forged", ["key", "key and inputs"])
def test_another_valid_mesh_under_this_entrys_name_is_meshed_afresh(cache_dir, forged):
    """SMALL's entry, relabelled with SOLID's key (and its inputs' text), put at SOLID's name: the cache gave
    SMALL's chamber for SOLID's (rest volume 0.0056 for 0.0225)."""
    pytest.importorskip("gmsh")
    fresh = mesh_solid(SOLID, SIZES)
    [own] = cache_dir.glob("gmsh-mesh-*.npz")
    small = mesh_solid(SMALL, SIZES)
    [foreign] = set(cache_dir.glob("gmsh-mesh-*.npz")) - {own}
    with np.load(own) as stored:
        labels = {name: stored[name] for name in stored.files if name.startswith("__")}
    with np.load(foreign) as stored:
        arrays = dict(stored)
    arrays["__key__"] = labels["__key__"]
    if forged == "key and inputs":
        arrays["__inputs__"] = labels["__inputs__"]
    np.savez(own, **arrays)
    assert rest_volume(small) < 0.5 * rest_volume(fresh)
    again = mesh_solid(SOLID, SIZES)
    assert rest_volume(again) == rest_volume(fresh) and np.array_equal(again.tets, fresh.tets)


def load_within(entry, seconds: float = 10.0) -> list:
    """[cache.load's answer] if it came within `seconds` (a daemon thread asks), else []."""
    got: list = []
    reader = threading.Thread(target=lambda: got.append(cache.load("test", entry, lambda a: True, 10**6)), daemon=True)
    reader.start()
    reader.join(timeout=seconds)
    return got


@pytest.mark.parametrize("what", ["fifo", "link to a fifo", "folder"])
def test_a_fifo_a_link_to_one_or_a_folder_at_an_entrys_name_is_a_miss_not_a_hang(cache_dir, tmp_path, what):
    entry = cache.key("fifo test")
    path = cache.path_of("test", entry)
    cache_dir.mkdir()
    if what == "fifo":
        os.mkfifo(path)
    elif what == "link to a fifo":
        os.mkfifo(tmp_path / "pipe")
        os.symlink(tmp_path / "pipe", path)
    else:
        path.mkdir()
    assert load_within(entry) == [None]
    if what == "folder":
        return
    cache.store("test", entry, {"a": np.arange(3.0)})  # the fresh result replaces it
    assert np.array_equal(load_within(entry)[0]["a"], np.arange(3.0))


# --- locking --------------------------------------------------------------------------------------------------------


def first_line(capsys) -> str:
    return next(line for line in capsys.readouterr().out.splitlines() if line.startswith("scene "))


@pytest.mark.parametrize("nu, order, warns", [(0.4999, 1, True), (0.49, 1, True), (0.45, 1, False), (0.4999, 2, False)])
def test_linear_elements_near_incompressibility_warn_in_the_runs_first_line(tmp_path, capsys, nu, order, warns):
    path = reference_with(tmp_path, ("nu = 0.45", f"nu = {nu}"), ("[mesh]", f"[mesh]\norder = {order}"))
    assert main(["--scene", str(path), "--out", str(tmp_path / "out"), *QUICK]) == 0
    line = first_line(capsys)
    assert ("warning: linear triangles lock" in line) == warns
    if warns:
        assert f"nu = {nu:g}" in line and "order = 2" in line


def test_an_isochoric_law_whose_bulk_modulus_is_fifty_times_its_shear_modulus_warns_on_linear_tetrahedra():
    """K / mu0 = 50 is nu = 0.4901 (mu0 = 2 C10)."""
    from taichi_pneuma.apps.cli import locking_note

    mesh = box_with_cavity()
    pressure = ChamberSchedule("pressure", ((1, 10.0),))
    for K, warns in ((50 * 2 * 1e3, True), (40 * 2 * 1e3, False)):
        material = IsochoricMaterial("neo_hookean", C10=1e3, bulk_modulus=K)
        note = locking_note(scene_of(mesh, [pressure], 1, material), mesh)
        assert ("linear tetrahedra lock at nu = 0.4901" in note) == warns, note
    nodal = scene_of(
        mesh, [pressure], 1, IsochoricMaterial("neo_hookean", C10=1e3, bulk_modulus=1e6), volumetric="nodal"
    )
    assert locking_note(nodal, mesh) == ""
    assert locking_note(scene_of(mesh, [pressure], 1, Material(1e4, 0.495)), mesh) != ""


def test_a_thread_on_the_round_outer_wall_is_snapped_onto_the_faceted_surface_not_refused():
    """fiber_bending_3d's thread moved from mid-wall (radius 7) onto the outer wall (radius 8, the body's own): the
    mesh's straight facets lie inside the round wall (by up to h^2 / 8R), so most of its points fall just outside
    them. Each is snapped onto the surface: every embedded point lies on the body's pieces (weights >= 0), within
    the facets' sagitta (0.5 mm here) inside radius 8, none outside it; radius 9 is still refused."""
    scene = tp.load_scene("fiber_bending_3d")
    built = scene.with_values({"fibers[0].path.radius": 8.0}).build()
    (cords,) = [t for t in built.model.terms if t.name == "fibers"]
    assert np.all(cords.weights >= 0)
    points = np.einsum("pi,pid->pd", cords.weights, built.mesh.vertices[cords.nodes])
    round_part = points[:, 1] > 2.0 + 1e-6  # the half above the flat face (y = 2 there: the path's centre)
    radius = np.hypot(points[round_part, 1] - 2.0, points[round_part, 2])
    assert radius.max() <= 8.0 + 1e-9 and radius.min() >= 7.5
    with pytest.raises(PneumaInputError, match=r"fiber 'thread': .* points lie outside the body"):
        scene.with_values({"fibers[0].path.radius": 9.0}).build()
