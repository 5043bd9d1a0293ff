"""What a run pays before and around its solve: the modules it loads, and the on-disk cache of gmsh meshes
(io/cache.py, fem/gmsh_mesher.py), here in a folder of each test's own, never the user's."""

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from taichi_pneuma import backend
from taichi_pneuma.backend import ti
from taichi_pneuma.errors import PneumaInputError
from taichi_pneuma.fem import gmsh_mesher
from taichi_pneuma.fem.gmsh_mesher import MeshSizes, Solid, estimate_tets, mesh_solid
from taichi_pneuma.fem.polygons import has_close_pair
from taichi_pneuma.fem.solids import Box, Ellipsoid
from taichi_pneuma.io import cache

ROOT = Path(__file__).resolve().parents[1]
SOLID = Solid(Box((0.0, 0.0, 0.0), (1.2, 0.6, 0.6)), (("c", Ellipsoid((0.0, 0.0, 0.0), (0.3, 0.15, 0.15))),))
SIZES = MeshSizes(0.3, near_chambers=0.15)


def test_close_pairs_are_those_of_all_pairwise_distances():
    """The outline check's sweep finds a pair within r exactly when the smallest of all pairwise distances is
    at most r, also when many points share one x (a straight vertical side)."""
    rng = np.random.default_rng(7)
    for trial in range(300):
        points = rng.random((int(rng.integers(2, 40)), 2))
        if trial % 3 == 0:
            points[:, 0] = np.round(points[:, 0], 1)
        distances = np.linalg.norm(points[:, None] - points[None], axis=2)
        nearest = distances[np.triu_indices(len(points), 1)].min()
        for r in (nearest * (1 - 1e-9), nearest * (1 + 1e-9), 0.05):
            assert has_close_pair(points, r) == (nearest <= r)


def test_a_2d_run_without_video_loads_no_module_it_does_not_use(tmp_path):
    """pneuma-inflate --no-video on the reference beam loads no plotting, video, mesh-file, spatial-search or
    gmsh module."""
    code = (
        "import runpy, sys\n"
        "sys.argv = ['pneuma-inflate', '--cy', '0.15', '--steps', '2', '--max-area', '0.01', '--no-video', "
        f"'--quiet', '--out', {str(tmp_path)!r}]\n"
        "try:\n    runpy.run_module('taichi_pneuma.apps.inflate', run_name='__main__')\n"
        "except SystemExit as exc:\n    assert not exc.code, exc.code\n"
        "print(' '.join(sorted(sys.modules)))\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, check=True)
    loaded = set(done.stdout.splitlines()[-1].split())
    for unused in ("matplotlib", "imageio", "imageio_ffmpeg", "PIL", "scipy.spatial", "meshio", "gmsh", "pyamg"):
        assert unused not in loaded
    assert "taichi_pneuma.solve.simulate" in loaded  # it did run


def counting_gmsh(monkeypatch) -> list:
    """Count gmsh sessions (each mesh or estimate made afresh opens one)."""
    calls, session = [], gmsh_mesher.session
    monkeypatch.setattr(gmsh_mesher, "session", lambda *a, **k: calls.append(1) or session(*a, **k))
    return calls


def same_mesh(a, b) -> bool:
    return (
        all(
            np.array_equal(getattr(a, k), getattr(b, k)) and getattr(a, k).dtype == getattr(b, k).dtype
            for k in ("vertices", "tets", "boundary", "regions")
        )
        and a.chambers.keys() == b.chambers.keys()
        and all(np.array_equal(a.chambers[k], b.chambers[k]) for k in a.chambers)
        and a.region_names == b.region_names
    )


def test_a_second_mesh_of_the_same_solid_comes_from_the_cache_bit_for_bit(cache_dir, monkeypatch):
    pytest.importorskip("gmsh")
    calls = counting_gmsh(monkeypatch)
    estimate, fresh = estimate_tets(SOLID, SIZES), mesh_solid(SOLID, SIZES)
    assert len(calls) == 2 and len(list(cache_dir.glob("gmsh-*.npz"))) == 2
    assert estimate_tets(SOLID, SIZES) == estimate
    assert same_mesh(mesh_solid(SOLID, SIZES), fresh)
    assert len(calls) == 2  # no gmsh for either
    # another size, or another chamber, is another mesh
    mesh_solid(SOLID, MeshSizes(0.3))
    moved = Solid(SOLID.body, (("c", Ellipsoid((0.1, 0.0, 0.0), (0.3, 0.15, 0.15))),))
    mesh_solid(moved, SIZES)
    assert len(calls) == 4


def test_a_cached_mesh_over_the_limit_is_refused_as_a_fresh_one_is(cache_dir, monkeypatch):
    pytest.importorskip("gmsh")
    with pytest.raises(PneumaInputError) as fresh:
        mesh_solid(SOLID, SIZES, max_tets=10)
    mesh_solid(SOLID, SIZES)
    calls = counting_gmsh(monkeypatch)
    with pytest.raises(PneumaInputError) as cached:
        mesh_solid(SOLID, SIZES, max_tets=10)
    assert str(cached.value) == str(fresh.value) and "the limit is 10 tetrahedra" in str(fresh.value)
    assert not calls


@pytest.mark.parametrize("spoil", ["garbage", "truncated", "foreign", "index out of range", "inverted"])
def test_a_corrupt_or_foreign_cache_file_is_ignored_and_rewritten(cache_dir, monkeypatch, spoil):
    pytest.importorskip("gmsh")
    fresh = mesh_solid(SOLID, SIZES)
    [path] = cache_dir.glob("gmsh-mesh-*.npz")
    with np.load(path) as stored:
        arrays = dict(stored)
    if spoil == "garbage":
        path.write_bytes(b"not a mesh" * 100)
    elif spoil == "truncated":
        path.write_bytes(path.read_bytes()[: len(path.read_bytes()) // 2])
    else:
        if spoil == "foreign":
            arrays["__key__"] = np.array("0" * 64)
        elif spoil == "index out of range":
            arrays["tets"] = arrays["tets"].copy()
            arrays["tets"][0, 0] = len(arrays["vertices"])
        else:
            arrays["tets"] = arrays["tets"][:, [0, 2, 1, 3]]
        np.savez(path, **arrays)
    calls = counting_gmsh(monkeypatch)
    assert same_mesh(mesh_solid(SOLID, SIZES), fresh) and len(calls) == 1  # meshed afresh
    assert same_mesh(mesh_solid(SOLID, SIZES), fresh) and len(calls) == 1  # and the file rewritten whole


def test_the_cache_folder_follows_the_environment(tmp_path, monkeypatch):
    monkeypatch.delenv(cache.VARIABLE, raising=False)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    if sys.platform.startswith("linux"):
        assert cache.directory() == tmp_path / "xdg" / "taichi-pneuma"
    monkeypatch.setenv(cache.VARIABLE, str(tmp_path / "mine"))
    assert cache.directory() == tmp_path / "mine"
    for off in ("", "off", "OFF"):
        monkeypatch.setenv(cache.VARIABLE, off)
        assert cache.directory() is None
        cache.store("test", cache.key("test"), {"a": np.zeros(3)})
        assert cache.load("test", cache.key("test"), lambda arrays: True, 10**6) is None
    assert not any(tmp_path.rglob("*.npz"))


def test_keys_tell_apart_inputs_that_differ_in_the_last_bit():
    a = Ellipsoid((0.0, 0.0, 0.0), (0.3, 0.15, 0.15))
    b = Ellipsoid((0.0, 0.0, 0.0), (np.nextafter(0.3, 1.0), 0.15, 0.15))
    assert cache.key(a) != cache.key(b)
    assert cache.key(np.array([0.1234567891])) != cache.key(np.array([0.1234567892]))  # past NumPy's repr digits
    assert cache.key(1) != cache.key(1.0) and cache.key(True) != cache.key(1)
    assert cache.key(object()) is None  # no exact text: not cached


@pytest.mark.skipif(backend.NAME != "taichi", reason="Taichi 1.7's AST transformer (Quadrants memoises it itself)")
def test_memoised_source_positions_are_the_texts_taichi_makes(monkeypatch):
    """A new kernel inlining a package ti.func twice compiles with every node's memoised position text equal to the
    text Taichi's own get_pos_info makes, some of them served by the memo, and computes det(A B) = det A det B."""
    from taichi.lang.ast.ast_transformer_utils import ASTTransformerContext

    from taichi_pneuma.materials.law import embedded

    memoised, texts = ASTTransformerContext.get_pos_info, []

    def checked(self, node):
        text = memoised(self, node)
        assert text == memoised.original(self, node)
        texts.append(text)
        return text

    monkeypatch.setattr(ASTTransformerContext, "get_pos_info", checked)

    @ti.kernel
    def det_of_product(F: ti.types.ndarray(dtype=ti.f64, ndim=2)) -> ti.f64:
        A = embedded(ti.Matrix([[F[0, 0], F[0, 1]], [F[1, 0], F[1, 1]]], dt=ti.f64), 2)
        B = embedded(ti.Matrix([[F[1, 1], F[0, 1]], [F[1, 0], F[0, 0]]], dt=ti.f64), 2)
        return (A @ B).determinant()

    F = np.array([[1.5, 2.0], [3.0, 5.0]])
    assert det_of_product(F) == pytest.approx((1.5 * 5.0 - 2.0 * 3.0) ** 2, rel=1e-14)
    assert len(texts) > len(set(texts))  # the two call sites of embedded repeat its nodes' texts
