"""Quadratic (P2) triangles: derivatives against finite differences, the curved chamber area, nodal loads,
the reference ramp against an independent code, and the convergence order under uniform refinement."""

import math
from pathlib import Path

import numpy as np
import pytest
from fd import dense_hessian, fd_hessian
from renderers import SOFTWARE
from scenes import grounded_beam
from test_terms import assert_gradient_matches_finite_differences, assert_max_step_stops_before_inversion

from taichi_pneuma.fem.planar import Geometry
from taichi_pneuma.fem.shapes import Ellipse, Rectangle
from taichi_pneuma.scene.build import reference_scene
from taichi_pneuma.solve.simulate import run_schedule
from taichi_pneuma.terms.chambers import PressureControl
from taichi_pneuma.terms.model import Configuration

# scikit-fem (an independent code, same model): P2 on the reference mesh refined twice, 96,384 nodes
INDEPENDENT_CONVERGED_TIP = -0.2583


@pytest.fixture(scope="module")
def coarse_p2():
    """A coarse quadratic beam on the ground under gravity, chamber commanded to 1.5x, in a random state."""
    return grounded_beam(2, 0.05, 5)


def test_quadratic_mesh_has_midside_nodes_everywhere(coarse_p2):
    """Every edge has a midside node: at its middle, but on the chamber wall, where corners and midside nodes
    lie on the exact ellipse (tests/test_curved_boundaries.py)."""
    built, _ = coarse_p2
    mesh = built.mesh
    x, t = mesh.vertices, mesh.triangles
    assert mesh.order == 2 and t.shape[1] == 6
    loop = mesh.chambers[0]
    for a, b, m in ((0, 1, 3), (1, 2, 4), (2, 0, 5)):
        straight = ~np.isin(t[:, m], loop)
        assert np.allclose(x[t[straight, m]], 0.5 * (x[t[straight, a]] + x[t[straight, b]]), atol=1e-15)
    assert np.allclose(np.hypot(x[loop, 0] / 0.85, (x[loop, 1] - 0.15) / 0.22), 1.0, atol=1e-14)
    assert np.sum(np.isclose(x[mesh.tip, 0], 1.75)) == len(mesh.tip) and len(mesh.tip) % 2 == 1  # corners + mids


@pytest.mark.parametrize("name", ["elastic", "chamber:main", "clamp", "gravity", "ground"])
def test_gradient_matches_finite_differences(coarse_p2, name):
    built, u = coarse_p2
    assert_gradient_matches_finite_differences(built, name, u)


def test_full_hessian_matches_finite_differences(coarse_p2):
    built, u = coarse_p2
    model = built.model
    model.set_displacements(u)
    hessian = dense_hessian(model.n_dofs, model.terms, psd_only=False)
    h_fd = fd_hessian(model, model.terms, u)
    assert np.linalg.norm(hessian - h_fd) / np.linalg.norm(h_fd) < 1e-6


def test_projected_hessian_is_psd(coarse_p2):
    built, u = coarse_p2
    built.model.set_displacements(3 * u)
    projected = dense_hessian(built.model.n_dofs, [built.elastic], psd_only=True)
    exact = dense_hessian(built.model.n_dofs, [built.elastic], psd_only=False)
    values = np.linalg.eigvalsh(projected)
    assert values.min() > -1e-9 * values.max() and np.linalg.eigvalsh(exact).min() < -1e-6 * values.max()


def test_max_step_keeps_every_quadrature_point_uninverted(coarse_p2):
    assert_max_step_stops_before_inversion(coarse_p2[0])


def test_curved_wall_area_is_exact_for_parabolic_sides():
    """A square of side s whose quadratic sides bulge out by h at their middles: each side is a parabola,
    and Archimedes' parabolic segment adds 2/3 s h per side."""
    s, h = 2.0, 0.3
    corners = np.array([[0.0, 0.0], [s, 0.0], [s, s], [0.0, s]])
    outward = np.array([[0.0, -1.0], [1.0, 0.0], [0.0, 1.0], [-1.0, 0.0]])
    mids = 0.5 * (corners + np.roll(corners, -1, axis=0)) + h * outward
    nodes = np.column_stack([corners, mids]).reshape(-1, 2)  # corner, midside, corner, ...
    chamber = PressureControl().term(Configuration(nodes), np.arange(8), "main", order=2)
    assert chamber.rest_area == pytest.approx(s * s + 4 * 2 / 3 * s * h, rel=1e-14)
    assert chamber.area() == pytest.approx(chamber.rest_area, rel=1e-14)


def test_nodal_areas_integrate_linear_loads_exactly():
    """sum_a a_a = the body area and sum_a a_a x_a = its first moment (the weight and its moment under gravity).
    The chamber's wall is a chain of parabolic arcs X(s) through corner a, midside m, corner b (its nodes lie on
    the ellipse), whose hole has, by Green's theorem, area 1/2 int (x y' - y x') ds and moments
    (1/2 int x^2 y' ds, -1/2 int y^2 x' ds), integrands of degree <= 5: 3-point Gauss-Legendre is exact.
    Off the curved triangles (those with a node on the wall), corners carry no weight."""
    geometry = Geometry(
        Rectangle((0.3, -0.1), (1.2, 0.5)), (("c", Ellipse((0.2, 0.0), (0.3, 0.1), 24)),), 0.01, order=2
    )
    mesh = geometry.mesh()
    weights = mesh.nodal_areas()
    loop = mesh.chambers[0]
    a, m = mesh.vertices[loop[0::2]], mesh.vertices[loop[1::2]]
    b = np.roll(a, -1, axis=0)
    s, w = np.polynomial.legendre.leggauss(3)
    s, w = (s[:, None, None] + 1) / 2, w / 2
    x = a * (1 - s) * (1 - 2 * s) + m * 4 * s * (1 - s) + b * s * (2 * s - 1)  # (3 points, arcs, 2)
    dx = a * (4 * s - 3) + m * (4 - 8 * s) + b * (4 * s - 1)
    hole_area = 0.5 * np.einsum("q,qk->", w, x[..., 0] * dx[..., 1] - x[..., 1] * dx[..., 0])
    hole_moment = 0.5 * np.array(
        [np.einsum("q,qk->", w, x[..., 0] ** 2 * dx[..., 1]), -np.einsum("q,qk->", w, x[..., 1] ** 2 * dx[..., 0])]
    )
    assert weights.sum() == pytest.approx(1.2 * 0.5 - hole_area, rel=1e-12)
    assert weights @ mesh.vertices == pytest.approx(np.array([0.3, -0.1]) * 0.6 - hole_moment, rel=1e-12)
    curved = np.isin(mesh.triangles, loop).any(axis=1)
    corners = np.setdiff1d(mesh.triangles[:, :3], mesh.triangles[curved])
    assert np.abs(weights[corners]).max() < 1e-15 * weights.max()


@pytest.mark.slow
def test_reference_ramp_on_p2_is_within_one_percent_of_the_converged_figure():
    result = run_schedule(reference_scene(0.15, max_area=0.005, order=2).build())
    assert all(s.converged for s in result.steps) and result.history["min_det"].min() > 0
    assert result.tip_deflection == pytest.approx(INDEPENDENT_CONVERGED_TIP, rel=0.01)
    assert result.history["main.area"][-1] / result.history["main.area"][0] == pytest.approx(3.5, rel=2e-3)


def tip_under_refinement(order: int) -> list[float]:
    """Tip deflection of a small problem (coarse beam, 1.5x in 3 increments) on 3 uniformly refined meshes."""
    return [
        run_schedule(
            reference_scene(
                0.15, growth=1.5, steps=4, max_area=0.02, chamber_points=32, order=order, refinements=r
            ).build()
        ).tip_deflection
        for r in range(3)
    ]


@pytest.mark.slow
def test_convergence_order_under_uniform_refinement():
    """Observed order p = log2(|f0 - f1| / |f1 - f2|) of the tip deflection as h halves: P2 converges far
    faster than P1 (measured: P1 ~0.7, P2 ~3.6 on this problem)."""
    orders = {}
    for order in (1, 2):
        f = tip_under_refinement(order)
        orders[order] = math.log2(abs(f[0] - f[1]) / abs(f[1] - f[2]))
    assert orders[1] < 1.5 and orders[2] > 2.5


def test_order_flag_quality_preset_and_scene_key(tmp_path, capsys):
    import json

    from taichi_pneuma.apps.inflate import main
    from taichi_pneuma.apps.quality import QUALITY
    from taichi_pneuma.errors import PneumaInputError
    from taichi_pneuma.fem.planar import BeamGeometry
    from taichi_pneuma.scene.scenefile import load_scene

    for flags in (["--order", "2", "--max-area", "0.02"], ["--quality", "high", "--max-area", "0.02"]):
        out = tmp_path / flags[1]
        assert main([*flags, "--steps", "3", "--growth", "1.2", "--no-video", "--quiet", "--out", str(out)]) == 0
        stem = "inflate_cy+0.15_growth1.2_steps3_max_area0.02" + ("_high" if "high" in flags else "_order2")
        summary = json.loads((out / f"{stem}_summary.json").read_text())
        assert summary["element_order"] == 2 and summary["all_converged"]
        assert summary["vertices"] == BeamGeometry(cy=0.15, max_area=0.02, order=2).mesh().n_vertices
    assert QUALITY["default"][:2] == (0.0012, 1)  # the main command keeps the reference's linear mesh
    reference = (Path(__file__).resolve().parents[1] / "taichi_pneuma" / "scenes" / "reference_beam.toml").read_text()
    for order in (2, 3, 4):
        path = tmp_path / f"order{order}.toml"
        path.write_text(reference.replace("[mesh]", f"[mesh]\norder = {order}"))
        if order < 4:
            assert load_scene(path).geometry.order == order
        else:
            with pytest.raises(PneumaInputError, match="order = 4"):
                load_scene(path)


def test_quadratic_frame_fills_every_subtriangle_and_draws_curved_walls():
    from test_render import pixels_at, rgb8

    from taichi_pneuma.render.colours import CHAMBER_FILL, CHAMBER_WALL, FACE
    from taichi_pneuma.render.frames import FrameRenderer, Track

    built = reference_scene(cy=0.15, growth=2.0, steps=3, max_area=0.02, order=2).build()
    track = Track.from_result(run_schedule(built))
    renderer = FrameRenderer([track], 960, 384, trace=False, backend=SOFTWARE)  # subtriangles wider than the outlines
    image = renderer.frame(2)
    x = track.states[2]
    faces = built.mesh.display_triangles()
    assert len(faces) == 4 * built.mesh.n_triangles
    on_face = np.all(np.abs(pixels_at(renderer, image, x[faces].mean(axis=1)) - rgb8(FACE)) < 40, axis=1)
    assert on_face.mean() > 0.6  # the rest fall on drawn element outlines
    loop = built.mesh.chambers[0]
    assert np.all(np.abs(pixels_at(renderer, image, x[loop].mean(axis=0, keepdims=True)) - rgb8(CHAMBER_FILL)) <= 3)
    walls = pixels_at(renderer, image, x[loop[1::2]])  # the midside nodes lie on the drawn wall
    assert np.mean(np.all(np.abs(walls - rgb8(CHAMBER_WALL)) < 60, axis=1)) > 0.8
