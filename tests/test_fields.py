"""Per-triangle output fields: Cauchy stress (from the material law's own P), largest stretch and det F against
hand formulas and against the elastic term's own gradient."""

import numpy as np
import pytest

from taichi_pneuma.fem.fields import cauchy_stress, determinants, element_fields, max_stretch, von_mises
from taichi_pneuma.materials import StableNeoHookean, lame_parameters
from taichi_pneuma.scene.build import reference_scene

MU, LAM = lame_parameters(1e4, 0.45)


def neo_hookean_stress(F):
    """The fields' Cauchy stress of each F (N, d, d) under the reference material."""
    return cauchy_stress(F, StableNeoHookean, np.tile([MU, LAM], (len(F), 1)))


def test_uniaxial_plane_strain_stretch_matches_the_closed_form():
    """F = diag(s, 1, 1), J = s: P = mu F - (mu + lam (1 - J)) cof F with cof F = diag(1, s, s), so
    sigma = P F^T / J = diag(mu s - c, mu / s - c, mu / s - c), c = mu + lam (1 - s); the same from the 2D
    and the 3D form of F."""
    for s in (0.7, 1.0, 1.3):
        c = MU + LAM * (1 - s)
        expected = np.diag([MU * s - c, MU / s - c, MU / s - c])
        assert neo_hookean_stress(np.diag([s, 1.0])[None])[0] == pytest.approx(expected, rel=1e-12, abs=1e-9)
        assert neo_hookean_stress(np.diag([s, 1.0, 1.0])[None])[0] == pytest.approx(expected, rel=1e-12, abs=1e-9)


def hand_von_mises(xx, yy, zz, xy):
    return np.sqrt(((xx - yy) ** 2 + (yy - zz) ** 2 + (zz - xx) ** 2) / 2 + 3 * xy**2)


def test_simple_shear_and_biaxial_stretch_match_hand_formulas():
    g, a, b = 0.3, 1.4, 0.8
    F = np.array([[[1.0, g], [0.0, 1.0]], [[a, 0.0], [0.0, b]]])
    s = neo_hookean_stress(F)
    # simple shear, J = 1: sigma = mu (F F^T - I) = mu [[g^2, g], [g, 0]], no out-of-plane stress
    assert s[0] == pytest.approx(np.array([[MU * g * g, MU * g, 0], [MU * g, 0, 0], [0, 0, 0]]), abs=1e-9)
    # stretch diag(a, b), J = ab: sigma_ii = mu (F_ii^2 / J - 1) + lam (J - 1); zz with F_zz = 1
    J = a * b
    xx, yy, zz = (MU * (f * f / J - 1) + LAM * (J - 1) for f in (a, b, 1.0))
    assert s[1] == pytest.approx(np.diag([xx, yy, zz]), rel=1e-12)
    assert von_mises(s) == pytest.approx([hand_von_mises(MU * g * g, 0, 0, MU * g), hand_von_mises(xx, yy, zz, 0)])
    assert max_stretch(F) == pytest.approx([(g + np.sqrt(g * g + 4)) / 2, a], rel=1e-12)
    assert np.all(neo_hookean_stress(np.eye(2)[None]) == 0)  # stress-free at rest


def test_fields_are_objective():
    rng = np.random.default_rng(1)
    F = np.eye(2) + 0.3 * rng.standard_normal((20, 2, 2))
    F = F[np.linalg.det(F) > 0.2]
    t = 0.7
    R = np.array([[np.cos(t), -np.sin(t)], [np.sin(t), np.cos(t)]])
    s, s_rot = neo_hookean_stress(F), neo_hookean_stress(R @ F)
    assert s_rot[:, :2, :2] == pytest.approx(R @ s[:, :2, :2] @ R.T, abs=1e-8)
    assert von_mises(s_rot) == pytest.approx(von_mises(s), rel=1e-10)
    assert max_stretch(R @ F) == pytest.approx(np.linalg.svd(F, compute_uv=False)[:, 0], rel=1e-12)


@pytest.mark.parametrize("order", [1, 2])
def test_stress_matches_the_elastic_terms_gradient_under_a_homogeneous_deformation(order):
    """For x = F X on every vertex and a virtual displacement w = G X, the elastic gradient gives
    sum_i g_i . (G X_i) = (body area) P : G; P = J sigma F^-T, so the Taichi term's gradient measures
    the first Piola stress that the Cauchy stress above implies."""
    built = reference_scene(cy=0.15, max_area=0.01, steps=3, order=order).build()
    X = built.mesh.vertices
    F = np.array([[1.15, 0.2], [-0.05, 0.9]])
    positions = X @ F.T
    built.model.set_displacements(positions - X)
    g = built.elastic.gradient()
    measured = (
        np.array([[np.sum(g * (X @ np.outer(np.eye(2)[a], np.eye(2)[b]).T)) for b in range(2)] for a in range(2)])
        / built.mesh.area
    )
    fields = element_fields(X, positions, built.mesh.triangles, *built.scene.element_material(built.mesh))
    sigma = fields["stress"][0, :2, :2]
    J = np.linalg.det(F)
    assert fields["det_F"] == pytest.approx(J, rel=1e-12) and len(fields["det_F"]) == built.mesh.n_triangles
    assert J * sigma @ np.linalg.inv(F).T == pytest.approx(measured, rel=1e-8)


def test_the_3d_largest_stretch_is_the_largest_singular_value():
    """The closed form (the trigonometric eigenvalue of F^T F) against LAPACK's SVD: general F, near the identity,
    rotations, repeated stretches (a double and a triple eigenvalue) and a flattened F."""
    rng = np.random.default_rng(3)
    rotations = np.linalg.qr(rng.standard_normal((200, 3, 3)))[0]
    F = np.concatenate(
        [
            rng.standard_normal((2000, 3, 3)),
            np.eye(3) + 1e-9 * rng.standard_normal((200, 3, 3)),
            rotations,
            rotations @ np.diag([2.0, 2.0, 0.5]),
            1.7 * rotations,
            rotations @ np.diag([3.0, 1e-6, 1e-6]),
        ]
    )
    assert max_stretch(F) == pytest.approx(np.linalg.svd(F, compute_uv=False)[:, 0], rel=1e-12)


@pytest.mark.parametrize("d", [2, 3])
def test_determinants_are_lapacks(d):
    F = np.random.default_rng(4).standard_normal((500, d, d))
    assert determinants(F) == pytest.approx(np.linalg.det(F), rel=1e-12, abs=1e-14)
