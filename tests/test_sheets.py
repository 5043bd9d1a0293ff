"""Strain-limiting sheets ([[layers]]): the membrane's energy, gradient and Hessian against finite differences, its
energies and edge forces against the closed forms of prescribed homogeneous stretches, the faces a layer covers,
and the acceptance check: a meshed bottom layer of thickness h and modulus E_s t / h converges to the sheet's tip
deflection as h -> 0, in 2D and 3D."""

import dataclasses
import math
import tomllib
from itertools import permutations

import numpy as np
import pytest
from fd import term_derivatives, term_hessian
from solid_meshes import box_with_cavity, scene_of

import taichi_pneuma as tp
from taichi_pneuma import backend
from taichi_pneuma.errors import PneumaInputError
from taichi_pneuma.fem.elements import boundary_facets, family_of
from taichi_pneuma.materials.neo_hookean import StableNeoHookean
from taichi_pneuma.scene.scenefile import read_scene
from taichi_pneuma.scene.schedule import area_ramp
from taichi_pneuma.scene.shipped import find
from taichi_pneuma.solve.newton import NewtonSolver
from taichi_pneuma.terms import Clamp, Elasticity, membrane
from taichi_pneuma.terms.gravity import Gravity
from taichi_pneuma.terms.membrane import Membrane
from taichi_pneuma.terms.model import Configuration, EnergyModel
from taichi_pneuma.terms.sheets import Layer

T, E, NU = 0.01, 2e5, 0.3
INSTANCES = {"taichi": "compiled_kernels", "quadrants": "materialized_kernels"}  # a kernel's compiled instances
LAM, MU, E_PLANE = E * NU / (1 - NU**2), E / (2 * (1 + NU)), E / (1 - NU**2)


SQUARE = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0.5, 0.5, 0]], dtype=float)  # the unit square
ROTATION = np.linalg.qr(np.random.default_rng(0).standard_normal((3, 3)))[0]  # tilts it out of every plane


def patch(d: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """(rest positions, cells) of a small membrane: in 3D the four triangles of the unit square with a centre node,
    tilted by ROTATION; in 2D a chain of four segments of total length 1 along a random direction."""
    if d == 3:
        return SQUARE @ ROTATION.T, np.array([[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]])
    direction = np.random.default_rng(seed).standard_normal(2)
    return np.outer(np.linspace(0, 1, 5), direction / np.linalg.norm(direction)), np.array(
        [[i, i + 1] for i in range(4)]
    )


@pytest.mark.parametrize("d", [2, 3])
@pytest.mark.parametrize("scale", [0.7, 1.3])  # compressed, stretched
def test_membrane_gradient_and_exact_hessian_match_finite_differences(d, scale):
    rest, cells = patch(d)
    config = Configuration(rest)
    term = Membrane(config, cells, T, E, NU, wrinkles=False)
    config.u[:] = (scale - 1) * rest + 0.05 * np.random.default_rng(1).standard_normal(rest.shape)
    g = term.gradient().ravel()
    g_fd, numeric = term_derivatives(term, config.u.copy())
    assert np.linalg.norm(g - g_fd) < 1e-6 * np.linalg.norm(g)
    hessian = term_hessian(term)
    assert np.linalg.norm(hessian - numeric) < 1e-6 * np.linalg.norm(numeric)
    values = term.hessian_values(True).reshape(len(cells), d * d, d * d)
    assert np.linalg.eigvalsh(values).min() > -1e-9 * np.abs(values).max()  # every projected block is PSD
    if scale < 1:  # compressed: the exact Hessian is indefinite, the projected one is not
        assert np.linalg.eigvalsh(hessian).min() < -1e-3 * np.abs(hessian).max()
    else:  # stretched along every direction: no block is projected
        np.testing.assert_allclose(term_hessian(term, psd_only=True), hessian, atol=1e-9 * np.abs(hessian).max())


@pytest.mark.parametrize("stretch", [0.9, 1.2])
def test_a_tilted_square_under_equibiaxial_stretch_stores_t_A0_times_the_closed_form_density(stretch):
    rest, cells = patch(3)
    config = Configuration(rest)
    term = Membrane(config, cells, T, E, NU, wrinkles=False)  # SVK: compressed, it stores energy too
    config.u[:] = (stretch - 1) * (rest - rest[0])  # x = X0 + lambda (X - X0): in plane
    g = (stretch**2 - 1) / 2
    assert term.energy() == pytest.approx(T * 1.0 * (LAM / 2 * (2 * g) ** 2 + MU * 2 * g**2), rel=1e-12)


def test_a_uniaxial_stretch_with_the_sides_held_gives_the_closed_form_energy_and_edge_force():
    """x = (lambda X, Y) on the unit square: G = diag(g, 0), psi = (lam/2 + mu) g^2, and the right edge carries
    t P_11 * width with P_11 = lambda S_11 = lambda (lam + 2 mu) g."""
    rest, cells = patch(3)
    config = Configuration(rest)
    term = Membrane(config, cells, T, E, NU)
    stretch = 1.1
    config.u[:] = (stretch - 1) * SQUARE[:, :1] * ROTATION[:, 0]  # along the tilted square's first side
    g = (stretch**2 - 1) / 2
    assert term.energy() == pytest.approx(T * (LAM / 2 + MU) * g**2, rel=1e-12)
    force = term.gradient()[SQUARE[:, 0] == 1.0].sum(axis=0)  # on the right side, of width 1
    np.testing.assert_allclose(force, T * stretch * (LAM + 2 * MU) * g * 1.0 * ROTATION[:, 0], rtol=1e-12, atol=1e-9)


def test_a_stretched_chain_of_segments_stores_t_L0_E_plane_g_squared_over_two_and_pulls_its_end():
    rest, cells = patch(2, seed=4)
    config = Configuration(rest)
    term = Membrane(config, cells, T, E, NU)
    stretch = 1.25
    config.u[:] = (stretch - 1) * rest
    g = (stretch**2 - 1) / 2
    assert term.energy() == pytest.approx(T * 1.0 * E_PLANE * g**2 / 2, rel=1e-12)
    along = rest[-1] / np.linalg.norm(rest[-1])
    np.testing.assert_allclose(term.gradient()[-1], T * E_PLANE * g * stretch * along, rtol=1e-12)


def principal_strains(term: Membrane) -> np.ndarray:
    """(f, m) the principal Green strains g1 >= ... of each cell (the kernels' G, in NumPy)."""
    x = term.config.rest + term.config.u
    m = term.dim - 1
    edges = np.stack([x[term.cells[:, a + 1]] - x[term.cells[:, 0]] for a in range(m)], axis=-1)  # (f, d, m)
    F = edges @ term.inverse.reshape(-1, m, m)
    G = 0.5 * (np.swapaxes(F, 1, 2) @ F - np.eye(m))
    return np.linalg.eigvalsh(G)[:, ::-1]


def regimes(term: Membrane) -> set[str]:
    """The regimes of the relaxed energy the cells are in: taut (S2 = lam tr G + 2 mu g2 >= 0), wrinkled (not taut,
    g1 > 0), slack (g1 <= 0)."""
    g = principal_strains(term)
    taut = LAM * g.sum(axis=1) + 2 * MU * g[:, -1] >= 0 if term.dim == 3 else g[:, 0] >= 0
    return {"taut" if t else "wrinkled" if g1 > 0 else "slack" for t, g1 in zip(taut, g[:, 0], strict=True)}


def in_plane(stretches: tuple[float, float]) -> np.ndarray:
    """The displacement of the tilted square (patch(3)) under x = X0 + diag(stretches) (X - X0) in its plane."""
    return (SQUARE[:, :2] * (np.array(stretches) - 1)) @ ROTATION[:, :2].T


WRINKLING_STATES = {  # in the square's plane (3D) or along the chain (2D); 2D has no wrinkled regime
    "taut": ({"taut"}, lambda d, rest: 0.2 * rest if d == 2 else in_plane((1.2, 1.2))),
    "wrinkled": ({"wrinkled"}, lambda d, rest: in_plane((1.2, 0.85))),
    "slack": ({"slack"}, lambda d, rest: -0.2 * rest if d == 2 else in_plane((0.8, 0.8))),
    "random": (None, lambda d, rest: 0.12 * np.random.default_rng(0).standard_normal(rest.shape)),  # every regime
}


@pytest.mark.parametrize(
    ("d", "state"),
    [(3, "taut"), (3, "wrinkled"), (3, "slack"), (3, "random"), (2, "taut"), (2, "slack"), (2, "random")],
)
def test_the_wrinkling_membrane_gradient_and_exact_hessian_match_finite_differences_and_are_psd(d, state):
    """The relaxed energy is convex in G with S >= 0: its exact Hessian is symmetric and PSD in every regime, each
    cell's block too (so psd_only need not project it)."""
    rest, cells = patch(d, seed=2)
    config = Configuration(rest)
    term = Membrane(config, cells, T, E, NU)
    expected, displacement = WRINKLING_STATES[state]
    config.u[:] = displacement(d, rest)
    assert regimes(term) == (expected or {"taut", "slack", "wrinkled"} - ({"wrinkled"} if d == 2 else set()))
    g = term.gradient().ravel()
    scale = np.linalg.norm(g) or 1.0
    g_fd, numeric = term_derivatives(term, config.u.copy())
    assert np.linalg.norm(g - g_fd) < 1e-6 * scale
    hessian = term_hessian(term)
    size = np.linalg.norm(numeric) or 1.0
    assert np.linalg.norm(hessian - numeric) < 1e-6 * size
    np.testing.assert_allclose(hessian, hessian.T, atol=1e-12 * size)
    assert np.linalg.eigvalsh(hessian).min() >= -1e-10 * np.abs(hessian).max()
    blocks = term.hessian_values().reshape(len(cells), d * d, d * d)  # each cell's own block is PSD too
    assert np.linalg.eigvalsh(blocks).min() >= -1e-10 * np.abs(blocks).max()
    if state == "slack":
        assert term.energy() == 0.0 and not g.any() and not hessian.any()


@pytest.mark.parametrize("lateral", [1 - NU * 0.105, 0.95, 0.8, 0.5])  # g2 = -nu g (the edge of the regime) and below
def test_a_wrinkled_sheet_stretched_uniaxially_stores_t_A0_E_g_squared_over_two_whatever_its_lateral_compression(
    lateral,
):
    """x = (lambda X, s Y) on the unit square with g2 = (s^2 - 1) / 2 <= -nu g: wrinkled, psi = E/2 g^2 with
    g = (lambda^2 - 1) / 2, S = E g e1 e1^T, and the right edge carries t lambda E g * width along the stretch."""
    rest, cells = patch(3)
    config = Configuration(rest)
    term = Membrane(config, cells, T, E, NU)
    stretch = 1.1
    g = (stretch**2 - 1) / 2
    lateral = lateral if lateral != 1 - NU * 0.105 else math.sqrt(1 - 2 * NU * g)  # exactly g2 = -nu g
    config.u[:] = in_plane((stretch, lateral))
    assert term.energy() == pytest.approx(T * 1.0 * E / 2 * g**2, rel=1e-12)
    force = term.gradient()[SQUARE[:, 0] == 1.0].sum(axis=0)
    np.testing.assert_allclose(force, T * stretch * E * g * ROTATION[:, 0], rtol=1e-12, atol=1e-9)
    if lateral == math.sqrt(1 - 2 * NU * g):  # the energy is continuous (C1) into the taut regime
        assert Membrane(config, cells, T, E, NU, wrinkles=False).energy() == pytest.approx(term.energy(), rel=1e-9)


def test_a_wrinkling_sheet_compressed_equibiaxially_stores_nothing_and_stretched_is_the_svk_membrane():
    rest, cells = patch(3)
    config = Configuration(rest)
    relaxed, svk = Membrane(config, cells, T, E, NU), Membrane(config, cells, T, E, NU, wrinkles=False)
    config.u[:] = in_plane((0.9, 0.9))
    assert relaxed.energy() == 0.0 and not relaxed.gradient().any() and not relaxed.hessian_values().any()
    assert svk.energy() > 0
    config.u[:] = in_plane((1.1, 1.1))
    g = (1.1**2 - 1) / 2
    assert relaxed.energy() == svk.energy() == pytest.approx(T * (LAM / 2 * (2 * g) ** 2 + MU * 2 * g**2), rel=1e-12)
    np.testing.assert_array_equal(relaxed.gradient(), svk.gradient())
    np.testing.assert_array_equal(relaxed.hessian_values(), svk.hessian_values())
    chain, segments = patch(2, seed=4)  # 2D: tension-only
    config = Configuration(chain)
    term = Membrane(config, segments, T, E, NU)
    config.u[:] = -0.1 * chain
    assert term.energy() == 0.0 and not term.gradient().any()
    config.u[:] = 0.1 * chain
    assert term.energy() == pytest.approx(T * E_PLANE * ((1.1**2 - 1) / 2) ** 2 / 2, rel=1e-12)


def cell_measures(term: Membrane) -> float:
    return float(term.weights.sum() / T)


@pytest.mark.parametrize("order", [1, 2])
def test_a_layer_covers_its_side_or_box_of_the_outer_boundary_and_never_a_chamber_wall(order):
    scene = tp.reference_scene(max_area=0.05, chamber_points=32, order=order)
    bottom, everything = Layer("bottom", E, NU, T, side="bottom"), Layer("all", E, NU, T, box=(-2, -1, 2, 1))
    built = dataclasses.replace(scene, layers=(bottom, everything)).build()
    first, second = built.model.terms[-2:]
    assert isinstance(first, Membrane) and isinstance(second, Membrane)
    assert cell_measures(first) == pytest.approx(3.5, rel=1e-12)  # the bottom of the 3.5 x 0.8 beam
    assert cell_measures(second) == pytest.approx(2 * (3.5 + 0.8), rel=1e-12)  # its outline, not the chamber's
    facets = bottom.facets(built.mesh)
    assert len(first.cells) == order * len(facets)  # a quadratic edge in two segments through its midside node
    with pytest.raises(PneumaInputError, match=r"layer 'patch': box = \[-1.0, 0.0, 1.0, 0.3\] selects \d+ mesh"):
        Layer("patch", E, NU, T, box=(-1.0, 0.0, 1.0, 0.3)).facets(built.mesh)  # inside the body: no facet


@pytest.mark.parametrize("order", [1, 2])
def test_a_3d_layer_covers_the_bottom_face_or_the_outer_surface_in_triangles(order):
    mesh = box_with_cavity(order)
    config = Configuration(mesh.vertices)
    (bottom,) = Layer("bottom", E, NU, T, side="bottom").terms(config, mesh, None, None)
    (outer,) = Layer("all", E, NU, T, box=(-2, -1, -1, 2, 1, 1)).terms(config, mesh, None, None)
    assert cell_measures(bottom) == pytest.approx(3.5 * 0.8, rel=1e-12)
    assert cell_measures(outer) == pytest.approx(2 * (3.5 * 0.8 * 2 + 0.8 * 0.8), rel=1e-12)  # no cavity wall
    assert len(outer.cells) == (4 if order == 2 else 1) * len(
        Layer("all", E, NU, T, box=(-2, -1, -1, 2, 1, 1)).facets(mesh)
    )
    assert scene_of(mesh, [area_ramp(1.2, 2, 1e5)], 1, layers=(Layer("b", E, NU, T, side="bottom"),)).build()


def test_a_scene_with_layers_reads_back_equal_from_its_scene_file():
    scene = dataclasses.replace(
        tp.reference_scene(max_area=0.05),
        layers=(
            Layer("sheet", 1e6, 0.3, 0.01, side="bottom"),
            Layer("patch", 2e5, 0.0, 0.005, box=(-1, -0.4, 1, 0), wrinkles=False),
        ),
    )
    text = scene.to_toml()
    assert "[[layers]]" in text and "wrinkles = false" in text
    assert read_scene(tomllib.loads(text), "other") == scene
    data = tomllib.loads(text)
    del data["layers"][0]["wrinkles"]  # the default: the sheet wrinkles
    assert read_scene(data, "other").layers[0].wrinkles is True
    data["layers"][1]["wrinkles"] = "no"
    with pytest.raises(PneumaInputError, match=r"layers\[1\]\.wrinkles = 'no' must be of type bool \(true or false\)"):
        read_scene(data, "other")


def membranes(scene) -> list[Membrane]:
    return [t for t in scene.build().model.terms if isinstance(t, Membrane)]


def test_a_layer_with_a_preset_has_its_published_moduli_in_the_scenes_units():
    """[[layers]] preset = "paper": the sheet's E and nu are those presets.py states for paper ([P]: E = 6.5 GPa,
    nu = 0.2), in kPa in a mm-kPa scene, so its membrane is that of E = 6.5e6, nu = 0.2; "dragon_skin_10" (Yeoh,
    C10 = 25 kPa, the silicones' default nu = 0.49): E = 2 mu0 (1 + nu), mu0 = 2 C10, or with nu = 0.3 given, the
    preset's Poisson's ratio replaced (as a region's is). The scene file writes the preset, not E, and reads back."""
    data = tomllib.loads(find("pneunet_mm_kpa").read_text())
    data["layers"] = [{"name": "sheet", "side": "bottom", "thickness": 0.1, "preset": "paper"}]
    scene = read_scene(data, "layered")
    (sheet,) = membranes(scene)
    E, nu = 6.5e6, 0.2  # kPa
    assert sheet.mu == pytest.approx(E / (2 * (1 + nu)), rel=1e-12)
    assert sheet.lam == pytest.approx(E * nu / (1 - nu**2), rel=1e-12)
    text = scene.to_toml()
    assert 'preset = "paper"' in text and read_scene(tomllib.loads(text), "layered") == scene
    # E and preset exclude each other: setting one (--set, with_values) drops the other
    given = scene.with_values({"layers[0].E": 6.5e6, "layers[0].nu": 0.2})
    assert given.layers[0].preset is None
    assert given.with_values({"layers[0].preset": "paper", "layers[0].nu": None}) == scene  # (a nu kept replaces its)
    (same,) = membranes(given)
    assert (same.mu, same.lam) == pytest.approx((sheet.mu, sheet.lam), rel=1e-12)
    for given, nu in ((None, 0.49), (0.3, 0.3)):
        layer = dataclasses.replace(scene.layers[0], preset="dragon_skin_10", nu=given)
        (sheet,) = membranes(dataclasses.replace(scene, layers=(layer,)))
        E = 2 * (2 * 25.0) * (1 + nu)  # kPa
        assert sheet.mu == pytest.approx(E / (2 * (1 + nu)), rel=1e-12)
        assert sheet.lam == pytest.approx(E * nu / (1 - nu**2), rel=1e-12)


def test_a_layer_preset_needs_the_scenes_units_and_no_E():
    unitless = dataclasses.replace(
        tp.reference_scene(max_area=0.05), layers=(Layer("sheet", None, None, 0.01, side="bottom", preset="paper"),)
    )
    with pytest.raises(PneumaInputError, match="preset = 'paper' needs the scene's units"):
        unitless.build()


@pytest.mark.parametrize(
    ("keys", "message"),
    [
        ({"nu": 0.5}, r"nu = 0.5 must be in \[0, 0.5\)"),
        ({"E": None}, r"layer 's': give E and nu, or a preset \(E = None, nu = 0.3\)"),
        ({"preset": "paper"}, r"layer 's': preset = 'paper' gives E \(and nu\): drop E = 200000.0"),
        ({"preset": "cardboard", "E": None}, "preset = 'cardboard' is not one of ecoflex_00_30"),
        ({"preset": "paper", "E": None, "nu": 0.5}, r"nu = 0.5 must lie in \(-1, 0.5\)"),
        ({"E": 0.0}, "E = 0.0 must be > 0"),
        ({"thickness": -1.0}, "thickness = -1.0 must be > 0"),
        ({"side": "up"}, "side = 'up' is not one of"),
        ({"side": None}, "give exactly one of 'side' and 'box'"),
        ({"wrinkles": 1}, "wrinkles = 1 must be true or false"),
    ],
)
def test_a_bad_layer_is_refused_naming_the_key(keys, message):
    with pytest.raises(PneumaInputError, match=message):
        Layer(**{"name": "s", "E": E, "nu": NU, "thickness": T, "side": "bottom", **keys})


# The acceptance check: a clamped 1 x 0.1 (x 0.1 in 3D) cantilever (E = 1, nu = 0.3; plane strain in 2D) under its
# weight, with a sheet of membrane stiffness E_s t = 0.1 on its bottom, against the same body with a meshed layer of
# thickness h and modulus E_s t / h below it (four rows of elements). The body's mesh is the same in every case.
LENGTH, HEIGHT, COLUMNS, ROWS, SHEET = 1.0, 0.1, 32, 4, 0.1


def kuhn_grid(axes: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """The structured simplex mesh of the grid of these axes' coordinates: each cell split into d! simplices, one
    per order of the axes (the Kuhn split: from the cell's low corner one step along each axis in that order), each
    of positive measure."""
    d, shape = len(axes), tuple(len(a) for a in axes)
    vertices = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, d)
    origins = np.stack(np.meshgrid(*(np.arange(n - 1) for n in shape), indexing="ij"), axis=-1).reshape(-1, 1, d)
    paths = [
        np.cumsum(np.vstack([np.zeros(d, int), np.eye(d, dtype=int)[list(p)]]), axis=0) for p in permutations(range(d))
    ]
    simplices = np.vstack([np.ravel_multi_index(tuple(np.moveaxis(origins + path, -1, 0)), shape) for path in paths])
    edges = vertices[simplices[:, 1:]] - vertices[simplices[:, :1]]
    flip = np.linalg.det(edges) < 0
    simplices[flip, 1], simplices[flip, 2] = simplices[flip, 2], simplices[flip, 1].copy()
    return vertices, simplices


def tip_deflection(d: int, h: float | None, sheet: bool = True) -> float:
    """The mean vertical tip displacement of the d-dimensional cantilever with the sheet (h None), with the meshed
    layer of thickness h (the layer has no weight, nor has the sheet), or of the body alone (h None, sheet False)."""
    body = np.linspace(0.0, HEIGHT, ROWS + 1)
    ys = body if h is None else np.concatenate([np.linspace(-h, 0.0, ROWS + 1)[:-1], body])
    vertices, cells = kuhn_grid([np.linspace(0.0, LENGTH, COLUMNS + 1), ys, np.array([0.0, HEIGHT])][:d])
    model = EnergyModel(vertices, 1e-9, 1e-15)
    config = model.config
    layer = vertices[cells].mean(axis=1)[:, 1] < 0
    moduli = np.where(layer, SHEET / (h or 1.0), 1.0)
    law = StableNeoHookean
    model.add(Elasticity(config, cells, law, np.array([law.parameters(m, 0.3)[0] for m in moduli])))
    model.add(Clamp(config, np.flatnonzero(vertices[:, 0] == 0.0), 1e4))
    measures = np.abs(np.linalg.det(vertices[cells[:, 1:]] - vertices[cells[:, :1]])) / math.factorial(d)
    masses = np.zeros(len(vertices))
    np.add.at(masses, cells[~layer], measures[~layer, None] / (d + 1))
    model.add(Gravity(config, masses, 1e-3))
    if h is None and sheet:
        facets = boundary_facets(family_of(cells, d), cells)
        bottom = facets[(vertices[facets, 1] == 0.0).all(axis=1)]
        model.add(Membrane(config, bottom, 1.0, SHEET, 0.3, wrinkles=False))  # compressed, as the meshed layer
    u, record = NewtonSolver(model).solve(np.zeros_like(vertices))
    assert record.converged
    return float(u[vertices[:, 0] == LENGTH, 1].mean())


@pytest.mark.parametrize("d", [2, 3])
def test_a_meshed_layer_of_the_same_membrane_stiffness_converges_to_the_sheet_as_it_thins(d):
    """The meshed layer differs from the sheet by its own offset below the bottom (h/2) and bending: O(h). The
    bottom of the hanging cantilever is in compression, which the meshed layer carries: the sheet is the SVK
    membrane (wrinkles = False; a wrinkling one goes slack and the beam deflects as without it)."""
    sheet = tip_deflection(d, None)
    assert abs(sheet) < 0.7 * abs(tip_deflection(d, None, sheet=False))  # the sheet stiffens the beam markedly
    meshed = np.array([tip_deflection(d, h) for h in (0.04, 0.02, 0.01, 0.005)])
    differences = np.abs(meshed - sheet) / abs(sheet)
    ratios = differences[1:] / differences[:-1]
    assert np.all((0.4 < ratios) & (ratios < 0.62))  # shrinking about as h, halved at each step
    assert differences[-1] < 0.06
    assert abs(2 * meshed[-1] - meshed[-2] - sheet) < 0.02 * abs(sheet)  # Richardson's extrapolation to h = 0


def test_membrane_kernels_compile_once_per_dimension_whatever_the_cells_or_the_sheet():
    """(tests/test_compile_once.py checks the package's kernels on scenes without layers.)"""
    kernels = (membrane.membrane_energy, membrane.membrane_gradient, membrane.membrane_hessian)
    count = lambda: [len(getattr(k._primal, INSTANCES[backend.NAME])) for k in kernels]  # noqa: E731

    def evaluate(d, scale):
        rest, cells = patch(d, seed=int(10 * scale))
        for wrinkles in (True, False):
            term = Membrane(
                Configuration(scale * rest), np.vstack([cells, cells[::-1]]), scale * T, scale * E, NU / scale, wrinkles
            )
            term.energy(), term.gradient(), term.hessian_values(), term.hessian_values(True)

    evaluate(2, 1.0), evaluate(3, 1.0)
    before = count()
    evaluate(2, 2.0), evaluate(3, 2.0)
    assert count() == before
