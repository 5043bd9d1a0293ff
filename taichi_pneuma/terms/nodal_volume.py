"""Simplices that do not lock: the law's volumetric part on the volume ratios of patches of quadrature points, as
an energy of the displacements. Two groupings: each node's patch of linear elements ("nodal": the average nodal
pressure element of Bonet and Burton 1998, also called nodally averaged F-bar) and each quadratic element's own
points ("mixed": the mean-dilatation, Hu-Washizu element with a constant pressure and dilatation per element,
condensed per element: P2/P0, the "hybrid" element of rubber analysis; Simo, Taylor and Pister 1985).

A nearly incompressible law psi(F) = psi_s(F) + U(J) (materials/law.py: volumetric, U's modulus growing without
bound as nu -> 1/2, psi_s isochoric) locks where too few J can stay near 1 under a bending field: one J per linear
element, and the four (three) points of a quadratic one hold more constraints than its nodes can meet. Here U takes
the ratio of current to rest volume of each patch P instead. Every element e (rest volume V_e = sum_q W_eq, current
v_e = sum_q W_eq det F_eq) lies in s patches P(e, 1..s) with the share 1/s of its volume in each (nodal: its s = d + 1
nodes; mixed: s = 1, itself):

    E = sum_e sum_q W_eq psi_s(F_eq) + sum_e sum_(P of e) s_e U_e(J_P),   s_e = V_e / s,
    J_P = v_P / V_P,   v_P = sum_(e in P) v_e / s,   V_P = sum_(e in P) s_e,

with U_e the volumetric part of element e's parameters (one material: the sum is sum_P V_P U(J_P); mixed: sum_e V_e
U_e(Theta_e), Theta_e = v_e / V_e). It is an energy of the displacements like any other, so Newton's gradient and
Hessian are its exact derivatives: with the patch pressure p_P = sum_(e in P) s_e U_e'(J_P) / V_P and the mean of an
element's patches' pressures pbar_e = mean_(P of e) p_P (mixed: pbar_e = U_e'(Theta_e), at all its points),

    dE/dx = sum_e sum_q W_eq [dpsi_s/dF_eq + pbar_e cof F_eq] : dF_eq/dx,
    d2E/dx2 = sum_e sum_q W_eq dF_eq/dx^T [d2psi_s/dF2 + pbar_e d2J/dF2] dF_eq/dx + sum_P C_P / V_P^2 g_P g_P^T,

where C_P = sum_(e in P) s_e U_e''(J_P) and g_P = dv_P/dx = sum_(e in P) g_e / s, g_e = dv_e/dx, whose entry at node
b is g_eb = sum_q W_eq cof F_eq G_eqb. The element part is the elastic term's kernels on the law without U plus the
pressure's work pbar J (volumetric_split), so it is projected per point as any law is; the patch part is a rank-1
matrix per patch, PSD wherever C_P >= 0 (U convex), and the projected Hessian clamps C_P at 0. A node's patch
couples every two nodes of it (two rings apart): its blocks (b, c) are found once per mesh, with the triplets
(a, ab, ac) that add C_a / V_a^2 g_ab g_ac^T into them. An element's patch is the element: U_e''(Theta_e) / V_e g_e
g_e^T adds into the element's own block, and the pattern is the plain element one.

A homogeneous deformation has J_P = det F in every patch, so the element reproduces it exactly (the patch test);
at nu -> 1/2 the constraint is one per node (linear) or one per element (quadratic: a large mesh of quadratic
tetrahedra has about 12 freedoms per element, against 4 constraints at its points, 1 here), which they meet without
locking. A point's own volume is then held by psi_s alone: the isochoric laws' psi_s grows without bound as J -> 0
(Ibar1 = J^(-2/3) I1), a barrier Newton's steps never cross. The stable neo-Hookean law has no such part (its
psi - lam/2 (J - 1)^2 is finite through J = 0), and on the beam of benchmarks/accuracy_3d.py its elements turned
inside out at nu = 0.45 and 0.499: it names no volumetric part, and patch volumes refuse it.
"""

from typing import TypeAlias

import numpy as np

from ..backend import ti
from ..errors import require
from ..materials.invariants import cofactor
from ..materials.law import element_parameters, embedded, volumetric_split
from .base import Nodal, Scalars, Table, block_pattern, int32s, vertex_dofs
from .elastic import (
    Elasticity,
    Gradients,
    Nodes,
    Parameters,
    Weights,
    deformation_gradient,
    elastic_energy,
    elastic_gradient,
    elastic_hessian,
)

PerNode: TypeAlias = ti.types.ndarray(dtype=ti.f64, ndim=3)  # (m, k, j) float64: j values per node of each element

# the element order each grouping takes, and what to use instead on the other order
GROUPINGS = {
    "nodal": (1, "linear elements (order = 1)", "for quadratic ones use volumetric = 'mixed'"),
    "mixed": (
        2,
        "quadratic elements (order = 2)",
        "a linear element has one J already, so it would be volumetric = 'element'; for linear elements that do not "
        "lock use volumetric = 'nodal'",
    ),
}


@ti.kernel
def volume_gradients(
    d: ti.template(),
    rest: Nodal,
    u: Nodal,
    nodes: Nodes,
    grads: Gradients,
    weights: Weights,
    volumes: Scalars,
    out: PerNode,
):
    """volumes[e] = v_e = sum_q W_eq det F_eq and out[e, b] = dv_e/dx_b = sum_q W_eq cof F_eq G_eqb."""
    for e in range(nodes.shape[0]):
        volumes[e] = 0.0
        for b in range(nodes.shape[1]):
            for i in ti.static(range(d)):
                out[e, b, i] = 0.0
        for q in range(weights.shape[1]):
            F = embedded(deformation_gradient(rest, u, nodes, grads, e, q, d), d)
            C = weights[e, q] * cofactor(F)
            volumes[e] += weights[e, q] * F.determinant()
            for b in range(nodes.shape[1]):
                for i in ti.static(range(d)):
                    entry = 0.0
                    for j in ti.static(range(d)):
                        entry += C[i, j] * grads[e, q, b, j]
                    out[e, b, i] += entry


@ti.kernel
def patch_volumetric(
    law: ti.template(), patches: Nodes, shares: Scalars, parameters: Parameters, ratios: Scalars, out: PerNode
):
    """out[e, j] = s_e (U_e, U_e', U_e'') at J_P = ratios[P], P = patches[e, j] (the j-th patch of element e)."""
    for e, j in ti.ndrange(patches.shape[0], patches.shape[1]):
        U = law.volumetric(ratios[patches[e, j]], element_parameters(law, parameters, e))
        for i in ti.static(range(3)):
            out[e, j, i] = shares[e] * U[i]


@ti.kernel
def star_hessian(d: ti.template(), coefficients: Scalars, g: Nodal, triplets: Nodes, out: Table):
    """out[block] = sum over its triplets (a, ab, ac, block) of coefficients[a] g[ab] g[ac]^T (d x d, row-major)."""
    for b, i in ti.ndrange(out.shape[0], out.shape[1]):
        out[b, i] = 0.0
    for t in range(triplets.shape[0]):
        c = coefficients[triplets[t, 0]]
        ab, ac, block = triplets[t, 1], triplets[t, 2], triplets[t, 3]
        for i, j in ti.static(ti.ndrange(d, d)):
            out[block, d * i + j] += c * g[ab, i] * g[ac, j]


def star_structure(nodes: np.ndarray, n: int):
    """The nodal part's fixed structure (module docstring): pair_of (m, k, k), the index of the pair (a, b) of each
    element's nodes a, b among the sorted distinct pairs; triplets (t, 4) (a, ab, ac, block) for every node a and
    every two pairs ab, ac of its patch; blocks (B, 2) the distinct node pairs (b, c) they add into."""
    keys = (nodes[:, :, None].astype(np.int64) * n + nodes[:, None, :]).ravel()
    pairs, pair_of = np.unique(keys, return_inverse=True)
    first, second = pairs // n, pairs % n
    start = np.searchsorted(first, np.arange(n + 1))
    size = np.diff(start)
    a = np.repeat(np.arange(n), size**2)
    local = np.arange(len(a)) - np.repeat(np.cumsum(size**2) - size**2, size**2)
    ab, ac = start[a] + local // size[a], start[a] + local % size[a]
    blocks, block = np.unique(second[ab] * n + second[ac], return_inverse=True)
    triplets = np.ascontiguousarray(np.column_stack([a, ab, ac, block]), dtype=np.int32)
    return pair_of.reshape(*nodes.shape, -1), triplets, np.column_stack([blocks // n, blocks % n])


def grouping_for(volumetric: str, order: int) -> str:
    """The grouping a scene's volumetric takes on elements of this order: "mixed" on linear elements is "element"
    (one J per element already: the same energy), so that a preset or a flag that makes a mixed scene's elements
    linear runs it; any other as it is."""
    return "element" if volumetric == "mixed" and order == 1 else volumetric


def require_volumetric(volumetric: str, law, order: int) -> None:
    """Refuse (PneumaInputError) volumetric = "nodal" or "mixed" on elements of the other order (GROUPINGS) or under a
    law without a volumetric part."""
    takes, elements, instead = GROUPINGS[volumetric]
    require(order == takes, f"volumetric = {volumetric!r} takes {elements}, not order {order}: {instead}")
    require(
        hasattr(law, "volumetric"),
        f"volumetric = {volumetric!r} takes a law split into an isochoric part and a volumetric one (law = "
        f"neo_hookean, mooney_rivlin, yeoh or a preset), not {law.name!r} (E and nu): its elements, left with no "
        f"volume stiffness of their own, turn inside out",
    )


class PatchVolumeElasticity(Elasticity):
    """The elastic energy of a mesh with the law's volumetric part on the volume ratios of patches (module
    docstring), each element in the patches of its row of patches() with an equal share; otherwise as Elasticity
    (its max_step, fault and min_determinant are the quadrature points'). A subclass names its grouping
    (volumetric, a key of GROUPINGS), its patches and how the patches' rank-1 parts enter the Hessian."""

    volumetric = ""

    def __init__(self, config, elements: np.ndarray, law, parameters: np.ndarray):
        super().__init__(config, elements, law, parameters)
        require_volumetric(self.volumetric, law, self.family.order)
        self.split = volumetric_split(law)
        self.patches = int32s(self.patches_of())
        self._patch_volumes()

    def _patch_volumes(self) -> None:
        """Each element's share s_e of its volume in each of its patches, and the patches' rest volumes V_P."""
        s = self.patches.shape[1]
        self.share = np.ascontiguousarray(self.weights.sum(axis=1) / s)
        self.rest_volumes = np.bincount(self.patches.ravel(), np.repeat(self.share, s))

    def scale_pieces(self, scale: np.ndarray) -> None:
        super().scale_pieces(scale)
        self._patch_volumes()

    def patches_of(self) -> np.ndarray:
        """(m, s): the patches of each element."""
        raise NotImplementedError

    def patch_hessian(self, coefficients: np.ndarray, gradients: np.ndarray, elements: np.ndarray) -> np.ndarray:
        """The Hessian's values (hessian_pattern's order) from the element blocks (m, (d k)^2) and the patches'
        rank-1 parts coefficients[P] g_P g_P^T (C_P / V_P^2), from the elements' g_e (m, k, d)."""
        raise NotImplementedError

    def _volumes(self):
        """(dv_e/dx_b (m, k, d), J_P)."""
        volumes = np.empty(len(self.nodes))
        gradients = np.empty((*self.nodes.shape, self.dim))
        volume_gradients(
            self.dim, self.config.rest, self.config.u, self.nodes, self.grads, self.weights, volumes, gradients
        )
        s = self.patches.shape[1]
        current = np.bincount(self.patches.ravel(), np.repeat(volumes / s, s), minlength=len(self.rest_volumes))
        return gradients, current / self.rest_volumes

    def _sums(self, ratios):
        """Per patch: (energy sum, c_P = sum s_e U_e'(J_P), C_P = sum s_e U_e''(J_P)) as one (3, P) array."""
        out = np.empty((*self.patches.shape, 3))
        patch_volumetric(self.law, self.patches, self.share, self.parameters, ratios, out)
        return np.array(
            [np.bincount(self.patches.ravel(), out[..., i].ravel(), minlength=len(ratios)) for i in range(3)]
        )

    def _split_arguments(self, pressures):
        """The elastic kernels' arguments for the law without U plus the element pressures' work (pbar_e)."""
        parameters = np.ascontiguousarray(np.column_stack([self.parameters, pressures]))
        return (self.split, self.dim, self.config.rest, self.config.u, self.nodes, self.grads, self.weights, parameters)

    def _pressures(self, ratios):
        """pbar_e, the mean over element e's patches of p_P = c_P / V_P, and the patch sums."""
        sums = self._sums(ratios)
        return (sums[1] / self.rest_volumes)[self.patches].mean(axis=1), sums

    def energy(self) -> float:
        sums = self._sums(self._volumes()[1])
        return elastic_energy(*self._split_arguments(np.zeros(len(self.nodes))))[0] + float(sums[0].sum())

    def gradient(self) -> np.ndarray:
        out = np.empty_like(self.config.rest)
        pressures, _ = self._pressures(self._volumes()[1])
        elastic_gradient(*self._split_arguments(pressures), out)
        return out

    def hessian_values(self, psd_only: bool = False) -> np.ndarray:
        gradients, ratios = self._volumes()
        pressures, sums = self._pressures(ratios)
        n = self.dim * self.nodes.shape[1]
        elements = np.empty((len(self.nodes), n * n))
        elastic_hessian(*self._split_arguments(pressures), int(psd_only), elements)
        coefficients = sums[2] / self.rest_volumes**2
        if psd_only:
            coefficients = np.maximum(coefficients, 0.0)
        return self.patch_hessian(coefficients, gradients, elements)


class NodalVolumeElasticity(PatchVolumeElasticity):
    """Linear triangles or tetrahedra with the law's volumetric part on nodal volume ratios (module docstring): the
    patches are the nodes, the rank-1 parts extra blocks between the nodes two rings apart."""

    volumetric = "nodal"
    piecewise = False  # a node's patch couples its elements

    def __init__(self, config, elements: np.ndarray, law, parameters: np.ndarray):
        super().__init__(config, elements, law, parameters)
        n, d = len(config.rest), self.dim
        self.pair_of, self.triplets, blocks = star_structure(self.nodes, n)
        self.n_pairs = int(self.pair_of.max()) + 1
        star_rows = np.repeat(vertex_dofs(blocks[:, 0], d).reshape(-1, d), d, axis=1).ravel()
        star_cols = np.tile(vertex_dofs(blocks[:, 1], d).reshape(-1, d), (1, d)).ravel()
        rows, cols = block_pattern(self.nodes, d)
        self._rows, self._cols = np.concatenate([rows, star_rows]), np.concatenate([cols, star_cols])
        self.n_blocks = len(blocks)

    def patches_of(self) -> np.ndarray:
        return self.nodes

    def patch_hessian(self, coefficients, gradients, elements):
        k = self.nodes.shape[1]
        contributions = np.broadcast_to(gradients[:, None, :, :] / k, (len(self.nodes), k, k, self.dim))
        g = np.column_stack(
            [
                np.bincount(self.pair_of.ravel(), contributions[..., i].ravel(), minlength=self.n_pairs)
                for i in range(self.dim)
            ]
        )
        star = np.empty((self.n_blocks, self.dim * self.dim))
        star_hessian(self.dim, coefficients, np.ascontiguousarray(g), self.triplets, star)
        return np.concatenate([elements.ravel(), star.ravel()])


class MixedElasticity(PatchVolumeElasticity):
    """Quadratic triangles or tetrahedra with one pressure and dilatation per element (P2/P0, condensed: module
    docstring): each element is its own patch, its rank-1 part U_e''(Theta_e) / V_e g_e g_e^T added into its own
    block."""

    volumetric = "mixed"

    def patches_of(self) -> np.ndarray:
        return np.arange(len(self.nodes))[:, None]

    def patch_hessian(self, coefficients, gradients, elements):
        g = gradients.reshape(len(self.nodes), -1)  # entry d b + i: node b, component i, as the blocks' rows
        blocks = elements.reshape(len(g), g.shape[1], g.shape[1])
        blocks += coefficients[:, None, None] * g[:, :, None] * g[:, None, :]
        return elements.ravel()
