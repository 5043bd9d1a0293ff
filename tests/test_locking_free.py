"""Elements that do not lock: the volumetric part of the law on the volume ratios of patches (terms/nodal_volume.py):
each node's patch of linear elements (Scene.volumetric = "nodal", the scene file's mesh.volumetric) or each quadratic
element's own points, one pressure per element (volumetric = "mixed", the P2/P0 element).

- Their energy, forces and Hessian are exact derivatives of each other (finite differences), in 2D and 3D, for the
  isochoric laws; the projected Hessian is positive semi-definite.
- The patch test: with the boundary held at a homogeneous deformation, the interior nodes settle exactly there.
- The incompressible thick-walled sphere (test_trust_supports' exact answer: neo-Hookean, inner radius 1, outer 2,
  pressure 0.4429 mu): at nu = 0.499 linear tetrahedra lock (the inner radius' growth r(A) - A is a quarter short
  on every mesh), with nodal averaging they converge to the exact answer; at nu = 0.45 they converge to the answer
  of curved quadratic tetrahedra. Curved quadratic tetrahedra are a few tenths of a percent short at nu = 0.499;
  with one pressure per element ("mixed") they are a few hundredths of a percent from the exact answer.
"""

import dataclasses
import shutil
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp
from solid_meshes import scene_of, shell_octant
from test_compile_once import compiled_instances
from test_trust_supports import PRESSURE, exact_inner_stretch

import taichi_pneuma as tp
from taichi_pneuma.errors import PneumaInputError
from taichi_pneuma.fem.planar import BeamGeometry
from taichi_pneuma.materials import IsochoricMaterial, IsochoricPolynomial
from taichi_pneuma.scene.schedule import ChamberSchedule
from taichi_pneuma.terms import VOLUMETRIC, Elasticity
from taichi_pneuma.terms.model import EnergyModel

MATERIALS = {
    "neo_hookean": lambda nu: IsochoricMaterial("neo_hookean", 0.5, poisson_ratio=nu),
    "mooney_rivlin": lambda nu: IsochoricMaterial("mooney_rivlin", 1.0, 0.3, poisson_ratio=nu),
    "yeoh": lambda nu: IsochoricMaterial("yeoh", 1.0, C20=0.2, C30=0.01, poisson_ratio=nu),
}
SCENES = Path(tp.__file__).parent / "scenes"


ORDER = {"nodal": 1, "mixed": 2}  # the element order each volumetric grouping takes


def mesh_of(dim: int, order: int = 1):
    return shell_octant(2, 1, order) if dim == 3 else BeamGeometry(max_area=0.2, chamber_points=12, order=order).mesh()


def term_of(mesh, law: str, nu: float, term=VOLUMETRIC["nodal"], vary: float = 0.5):
    """The elastic term alone on the mesh, its elements' parameters varied by up to `vary` (several materials)."""
    m = mesh.n_elements
    parameters = MATERIALS[law](nu).row() * (1 + vary * np.random.default_rng(1).random((m, 1)))
    model = EnergyModel(mesh.vertices, 1.0, 1e-12)
    return model, model.add(term(model.config, mesh.elements, IsochoricPolynomial, parameters))


def hessian(term, n: int, psd_only: bool = False) -> np.ndarray:
    rows, cols = term.hessian_pattern()
    return sp.coo_matrix((term.hessian_values(psd_only), (rows, cols)), shape=(n, n)).toarray()


@pytest.mark.parametrize(
    "dim, law, volumetric",
    [
        (3, "neo_hookean", "nodal"),
        (3, "yeoh", "nodal"),
        (2, "mooney_rivlin", "nodal"),
        (3, "neo_hookean", "mixed"),
        (3, "yeoh", "mixed"),
        (2, "mooney_rivlin", "mixed"),
    ],
)
def test_energy_forces_and_hessian_agree_with_finite_differences(dim, law, volumetric):
    mesh = mesh_of(dim, ORDER[volumetric])
    model, term = term_of(mesh, law, 0.45, VOLUMETRIC[volumetric])
    rng = np.random.default_rng(0)
    scale = 0.01 if (dim, volumetric) == (2, "mixed") else 0.05  # these quadratic triangles invert at 0.05
    u = scale * rng.standard_normal(mesh.vertices.shape)
    v, h, n = rng.standard_normal(u.size), 1e-6, u.size
    model.set_displacements(u)
    g, H, projected = term.gradient().ravel(), hessian(term, n), hessian(term, n, psd_only=True)

    def at(s):
        model.set_displacements(u.ravel() + s * v)
        return term.energy(), term.gradient().ravel()

    (e_plus, g_plus), (e_minus, g_minus) = at(h), at(-h)
    assert (e_plus - e_minus) / (2 * h) == pytest.approx(g @ v, rel=1e-7)
    assert np.abs((g_plus - g_minus) / (2 * h) - H @ v).max() < 1e-7 * np.abs(H @ v).max()
    assert np.abs(H - H.T).max() < 1e-12 * np.abs(H).max()
    assert np.linalg.eigvalsh(H).min() < 0  # this state's exact Hessian is indefinite, the projected one is not
    assert np.linalg.eigvalsh(projected).min() > -1e-12 * np.abs(projected).max()


@pytest.mark.parametrize("volumetric, interior, offset", [("nodal", 9, 0.02), ("mixed", 147, 2e-4)])
def test_a_homogeneous_deformation_is_reproduced_exactly(volumetric, interior, offset, law="mooney_rivlin"):
    """Boundary nodes held at x = A X, interior nodes started off it: Newton on the interior DOFs returns them to
    A X (every J_P = det A, every point's stress the same: the patch is in equilibrium), at nu = 0.499, on linear
    tetrahedra with nodal volumes and on quadratic ones with one pressure per element; there the energy and forces
    are the plain elastic term's. The start's offset is within plain Newton's reach: at K = 500 mu an element's
    pressure K (Theta - 1) soon passes mu, and its Hessian turns indefinite (quadratic ones: 1e-3 diverged)."""
    mesh = shell_octant(4, 4, ORDER[volumetric])
    model, term = term_of(mesh, law, 0.499, VOLUMETRIC[volumetric], vary=0.0)
    A = np.array([[1.1, 0.05, 0.0], [-0.03, 0.95, 0.02], [0.01, 0.0, 0.97]])
    inner = np.ones(mesh.n_vertices, dtype=bool)
    inner[mesh.surface] = False
    assert inner.sum() == interior
    free = np.repeat(inner, 3)
    exact = (mesh.vertices @ A.T - mesh.vertices).ravel()
    u = exact + offset * free * np.random.default_rng(2).standard_normal(exact.size)
    for _ in range(10):
        model.set_displacements(u)
        g, H = term.gradient().ravel(), hessian(term, u.size)
        u[free] -= np.linalg.solve(H[np.ix_(free, free)], g[free])
    assert np.abs(u - exact).max() < 1e-12
    model.set_displacements(exact)
    plain = term_of(mesh, law, 0.499, Elasticity, vary=0.0)[1]
    plain.config.u[:] = exact.reshape(-1, 3)
    assert term.energy() == pytest.approx(plain.energy(), rel=1e-12)
    assert np.abs(term.gradient() - plain.gradient()).max() < 1e-10 * np.abs(plain.gradient()).max()


def inner_stretch_growth_errors(nu: float, runs) -> dict:
    """r(A) - A of each run (order, volumetric, divisions) of the octant of the thick sphere under the exact answer's
    pressure, isochoric neo-Hookean (C10 = 1/2, so mu = 1), relative to the exact incompressible growth."""
    material = IsochoricMaterial("neo_hookean", 0.5, poisson_ratio=nu)
    exact = exact_inner_stretch(3) - 1
    errors = {}
    for order, volumetric, n in runs:
        mesh = shell_octant(n, n // 2, order=order, curved=order == 2)
        scene = scene_of(mesh, [ChamberSchedule("pressure", ((0, 0.0), (4, PRESSURE)))], 4, material)
        result = tp.simulate(dataclasses.replace(scene, volumetric=volumetric))
        assert result.converged
        inner = np.abs(np.linalg.norm(mesh.vertices, axis=1) - 1) < 1e-9
        stretch = np.linalg.norm((mesh.vertices + result.displacements[-1])[inner], axis=1).mean()
        errors[order, volumetric, n] = (stretch - 1) / exact - 1
    return errors


def test_linear_tetrahedra_with_nodal_volumes_do_not_lock_on_the_incompressible_sphere():
    """nu = 0.499 (K = 500 mu): plain linear tetrahedra -28 % on 768 (measured; -26 % on 2592, -24 % on 6144),
    nodal averaging -3.0 % on 2592 (-24 % on 96, -6.8 % on 768, -1.6 % on 6144: order 2)."""
    errors = inner_stretch_growth_errors(0.499, [(1, "element", 8), (1, "nodal", 12)])
    assert errors[1, "element", 8] < -0.2 and abs(errors[1, "nodal", 12]) < 0.04


def test_at_nu_045_nodal_volumes_converge_to_the_quadratic_answer():
    """Against curved quadratic tetrahedra (324 of them: 0.1 % from 768 of them, measured): nodal averaging
    -19 % on 96 tetrahedra, -5.4 % on 768 (order 1.8; plain linear ones -31 % and -14 %)."""
    errors = inner_stretch_growth_errors(0.45, [(2, "element", 6), (1, "nodal", 4), (1, "nodal", 8)])
    quadratic = 1 + errors[2, "element", 6]
    coarse, fine = ((1 + errors[1, "nodal", n]) / quadratic - 1 for n in (4, 8))
    assert abs(fine) < 0.06 and np.log2(coarse / fine) > 1.5


def test_quadratic_tetrahedra_with_one_pressure_per_element_reach_the_incompressible_sphere():
    """nu = 0.499 (K = 500 mu), curved quadratic tetrahedra, plain ("element") against one pressure per element
    ("mixed"), measured: -5.9 % against -3.6 % on 12 tetrahedra, -1.34 % against -0.25 % on 96, -0.49 % against
    +0.0003 % on 324, -0.22 % against +0.047 % on 768 (the nearly incompressible body's own answer is a little
    above the incompressible one)."""
    errors = inner_stretch_growth_errors(0.499, [(2, v, n) for n in (4, 6) for v in ("element", "mixed")])
    for n, tolerance in ((4, 0.004), (6, 0.001)):
        plain, mixed = errors[2, "element", n], errors[2, "mixed", n]
        assert abs(mixed) < tolerance and abs(mixed) < abs(plain) / 3


def test_the_scene_file_chooses_nodal_volumes_for_linear_elements_of_the_isochoric_laws(tmp_path):
    """mesh.volumetric = "nodal" on the shipped beam_3d of neo-Hookean rubber: read, written and read back; refused
    with quadratic elements and with the stable neo-Hookean law (E and nu), whose elements invert without their own
    volume stiffness (terms/nodal_volume.py)."""
    shutil.copy(SCENES / "beam_3d.msh", tmp_path)
    rubber = 'law = "neo_hookean"\nC10 = 1700.0\nnu = 0.499'
    text = (SCENES / "beam_3d.toml").read_text().replace("E = 1e4\nnu = 0.45", rubber)
    (tmp_path / "rubber.toml").write_text(text.replace("[mesh]\n", '[mesh]\nvolumetric = "nodal"\n'))
    scene = tp.load_scene(tmp_path / "rubber.toml")
    assert scene.volumetric == "nodal" and 'volumetric = "nodal"' in scene.to_toml()
    (tmp_path / "again.toml").write_text(scene.to_toml())
    assert tp.load_scene(tmp_path / "again.toml") == scene
    assert scene.with_value("mesh.volumetric", "element").volumetric == "element"
    with pytest.raises(PneumaInputError, match="volumetric = 'nodal' takes linear elements"):
        scene.with_value("mesh.order", 2)
    assert "volumetric" not in tp.load_scene("beam_3d").to_toml()  # the default is not written
    with pytest.raises(PneumaInputError, match="not 'stable_neo_hookean'"):
        tp.load_scene("beam_3d").with_value("mesh.volumetric", "nodal")
    with pytest.raises(PneumaInputError, match="mesh.volumetric"):
        scene.with_value("mesh.volumetric", "bubble")


def test_the_scene_file_chooses_one_pressure_per_element_for_quadratic_elements(tmp_path):
    """mesh.volumetric = "mixed" on the shipped beam_3d of neo-Hookean rubber, quadratic: read, written and read
    back; on linear elements it is "element" (a preset or --order 1 may make them linear); refused with the stable
    neo-Hookean law."""
    shutil.copy(SCENES / "beam_3d.msh", tmp_path)
    rubber = 'law = "neo_hookean"\nC10 = 1700.0\nnu = 0.499'
    text = (SCENES / "beam_3d.toml").read_text().replace("E = 1e4\nnu = 0.45", rubber)
    (tmp_path / "rubber.toml").write_text(text)
    scene = tp.load_scene(tmp_path / "rubber.toml").with_values({"mesh.order": 2, "mesh.volumetric": "mixed"})
    assert scene.volumetric == "mixed" and 'volumetric = "mixed"' in scene.to_toml()
    (tmp_path / "again.toml").write_text(scene.to_toml())
    assert tp.load_scene(tmp_path / "again.toml") == scene
    linear = scene.with_value("mesh.order", 1)  # one J per element already: plain elements, the same energy
    assert type(linear.build().elastic) is Elasticity
    with pytest.raises(PneumaInputError, match="not 'stable_neo_hookean'"):
        tp.load_scene("beam_3d").with_values({"mesh.order": 2, "mesh.volumetric": "mixed"})


@pytest.mark.parametrize("volumetric", ["nodal", "mixed"])
def test_patch_volumes_compile_once(volumetric):
    """After a run with nodal volumes (one pressure per element), other meshes and materials compile no kernel."""
    order = ORDER[volumetric]
    runs = [
        (shell_octant(2, 1, order), MATERIALS["neo_hookean"](0.49)),
        (shell_octant(3, 2, order), MATERIALS["yeoh"](0.499)),
        (shell_octant(3, 1, order), IsochoricMaterial("mooney_rivlin", 0.4, 0.1, bulk_modulus=300.0)),
    ]
    for i, (mesh, material) in enumerate(runs):
        if i == 1:
            before = compiled_instances()
        schedule = ChamberSchedule("pressure", ((0, 0.0), (1, 0.05)))
        scene = scene_of(mesh, [schedule], 1, material, volumetric=volumetric)
        assert tp.simulate(scene).converged
    assert compiled_instances() == before


@pytest.mark.parametrize("law", ["yeoh", "mooney_rivlin"])
def test_the_exact_hessian_of_quadratic_tetrahedra_is_d2psi_dF2_itself(law):
    """The exact Hessian takes d2psi/dF2 as the law gives it, no eigensystem (terms/elastic.py; the projected one
    alone takes the eigenpairs, Jacobi's for these laws): against central differences of the forces on curved
    quadratic tetrahedra, and against the projected one, which differs only where an eigenvalue is negative."""
    mesh = shell_octant(2, 1, order=2, curved=True)
    model, term = term_of(mesh, law, 0.49, Elasticity)
    rng = np.random.default_rng(3)
    u = 0.05 * rng.standard_normal(mesh.vertices.shape)
    v, h = rng.standard_normal(u.size), 1e-6
    model.set_displacements(u)
    H, projected = hessian(term, u.size), hessian(term, u.size, psd_only=True)

    def forces(s):
        model.set_displacements(u.ravel() + s * v)
        return term.gradient().ravel()

    assert np.abs((forces(h) - forces(-h)) / (2 * h) - H @ v).max() < 1e-7 * np.abs(H @ v).max()
    assert np.linalg.eigvalsh(H).min() < 0 <= np.linalg.eigvalsh(projected).min() + 1e-12 * np.abs(projected).max()
