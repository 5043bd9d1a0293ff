"""Linear elements that do not lock: the volumetric part of the law on nodal volume ratios (terms/nodal_volume.py,
Scene.volumetric = "nodal", the scene file's mesh.volumetric).

- Its energy, forces and Hessian are exact derivatives of each other (finite differences), in 2D and 3D, for the
  isochoric laws; the projected Hessian is positive semi-definite.
- The patch test: with the boundary held at a homogeneous deformation, the interior nodes settle exactly there.
- The incompressible thick-walled sphere (test_trust_supports' exact answer: neo-Hookean, inner radius 1, outer 2,
  pressure 0.4429 mu): at nu = 0.499 linear tetrahedra lock (the inner radius' growth r(A) - A is a quarter short
  on every mesh), with nodal averaging they converge to the exact answer; at nu = 0.45 they converge to the answer
  of curved quadratic tetrahedra.
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
from taichi_pneuma.terms import Elasticity, NodalVolumeElasticity
from taichi_pneuma.terms.model import EnergyModel

MATERIALS = {
    "neo_hookean": lambda nu: IsochoricMaterial("neo_hookean", 0.5, poisson_ratio=nu),
    "mooney_rivlin": lambda nu: IsochoricMaterial("mooney_rivlin", 1.0, 0.3, poisson_ratio=nu),
    "yeoh": lambda nu: IsochoricMaterial("yeoh", 1.0, C20=0.2, C30=0.01, poisson_ratio=nu),
}
SCENES = Path(tp.__file__).parent / "scenes"


def mesh_of(dim: int):
    return shell_octant(2, 1) if dim == 3 else BeamGeometry(max_area=0.2, chamber_points=12).mesh()


def term_of(mesh, law: str, nu: float, term=NodalVolumeElasticity, vary: float = 0.5):
    """The elastic term alone on the mesh, its elements' parameters varied by up to `vary` (several materials)."""
    m = mesh.n_elements
    parameters = MATERIALS[law](nu).row() * (1 + vary * np.random.default_rng(1).random((m, 1)))
    model = EnergyModel(mesh.vertices, 1.0, 1e-12)
    return model, model.add(term(model.config, mesh.elements, IsochoricPolynomial, parameters))


def hessian(term, n: int, psd_only: bool = False) -> np.ndarray:
    rows, cols = term.hessian_pattern()
    return sp.coo_matrix((term.hessian_values(psd_only), (rows, cols)), shape=(n, n)).toarray()


@pytest.mark.parametrize("dim, law", [(3, "neo_hookean"), (3, "yeoh"), (2, "mooney_rivlin")])
def test_energy_forces_and_hessian_agree_with_finite_differences(dim, law):
    mesh = mesh_of(dim)
    model, term = term_of(mesh, law, 0.45)
    rng = np.random.default_rng(0)
    u = 0.05 * rng.standard_normal(mesh.vertices.shape)
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


def test_a_homogeneous_deformation_is_reproduced_exactly(law="mooney_rivlin"):
    """Boundary nodes held at x = A X, interior nodes started off it: Newton on the interior DOFs returns them to
    A X (every J_a = det A, every element's stress the same: the patch is in equilibrium), at nu = 0.499."""
    mesh = shell_octant(4, 4)
    model, term = term_of(mesh, law, 0.499, vary=0.0)
    A = np.array([[1.1, 0.05, 0.0], [-0.03, 0.95, 0.02], [0.01, 0.0, 0.97]])
    radius = np.linalg.norm(mesh.vertices, axis=1)
    inner = (np.abs(radius - 1) > 1e-9) & (np.abs(radius - 2) > 1e-9) & np.all(mesh.vertices > 1e-9, axis=1)
    assert inner.sum() == 9
    free = np.repeat(inner, 3)
    exact = (mesh.vertices @ A.T - mesh.vertices).ravel()
    u = exact + 0.02 * free * np.random.default_rng(2).standard_normal(exact.size)
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


def test_nodal_volumes_compile_once():
    """After a run with nodal volumes, other meshes and materials compile no kernel."""
    runs = [
        (shell_octant(2, 1), MATERIALS["neo_hookean"](0.49)),
        (shell_octant(3, 2), MATERIALS["yeoh"](0.499)),
        (shell_octant(3, 1), IsochoricMaterial("mooney_rivlin", 0.4, 0.1, bulk_modulus=300.0)),
    ]
    for i, (mesh, material) in enumerate(runs):
        if i == 1:
            before = compiled_instances()
        scene = scene_of(mesh, [ChamberSchedule("pressure", ((0, 0.0), (1, 0.05)))], 1, material, volumetric="nodal")
        assert tp.simulate(scene).converged
    assert compiled_instances() == before
