"""Linear triangles and tetrahedra that do not lock: the volumetric energy on nodal volume ratios (the average
nodal pressure element of Bonet and Burton 1998, also called nodally averaged F-bar).

A nearly incompressible law psi(F) = psi_s(F) + U(J) (materials/law.py: volumetric, U's modulus growing without
bound as nu -> 1/2, psi_s isochoric) on linear simplices locks: one J per element cannot stay near 1 under a
bending field. Here U takes the ratio of current to rest volume of each node's patch of elements instead,

    E = sum_e V_e psi_s(F_e) + sum_e sum_(a in e) s_e U_e(J_a),   s_e = V_e / (d + 1),
    J_a = v_a / V_a,   v_a = sum_(e at a) v_e / (d + 1),   V_a = sum_(e at a) s_e,   v_e = V_e det F_e,

with U_e the volumetric part of element e's parameters (one material: the sum is sum_a V_a U(J_a)). It is an
energy of the displacements like any other, so Newton's gradient and Hessian are its exact derivatives: with
the nodal pressure p_a = sum_(e at a) s_e U_e'(J_a) / V_a and the elements' mean of their nodes' pressures
pbar_e = mean_(a in e) p_a,

    dE/dx = sum_e V_e [dpsi_s/dF_e + pbar_e cof F_e] : dF_e/dx,
    d2E/dx2 = sum_e V_e dF_e/dx^T [d2psi_s/dF2 + pbar_e d2J/dF2] dF_e/dx + sum_a C_a / V_a^2 g_a g_a^T,

where C_a = sum_(e at a) s_e U_e''(J_a) and g_a = dv_a/dx, whose entry at node b is
g_ab = sum_(e at a and b) V_e cof F_e G_eb / (d + 1). The element part is the elastic term's kernels on the law
without U plus the pressure's work pbar J (volumetric_split), so it is projected per element as any law is; the
nodal part is a rank-1 matrix per node, PSD wherever C_a >= 0 (U convex), and the projected Hessian clamps C_a at
0. It couples every two nodes of a node's patch (two rings apart): its blocks (b, c) are found once per mesh,
with the triplets (a, ab, ac) that add C_a / V_a^2 g_ab g_ac^T into them.

A homogeneous deformation has J_a = det F at every node, so the element reproduces it exactly (the patch test);
at nu -> 1/2 the constraint is one per node instead of one per element, which linear simplices can satisfy
without locking. An element's own volume is then held by psi_s alone: the isochoric laws' psi_s grows without
bound as J -> 0 (Ibar1 = J^(-2/3) I1), a barrier Newton's steps never cross. The stable neo-Hookean law has no
such part (its psi - lam/2 (J - 1)^2 is finite through J = 0), and on the beam of benchmarks/accuracy_3d.py its
elements turned inside out at nu = 0.45 and 0.499: it names no volumetric part, and nodal volumes refuse it.
"""

from typing import TypeAlias

import numpy as np

from ..backend import ti
from ..errors import require
from ..materials.invariants import cofactor
from ..materials.law import element_parameters, embedded, volumetric_split
from .base import Nodal, Scalars, Table, block_pattern, vertex_dofs
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
    """volumes[e] = v_e = V_e det F_e and out[e, b] = dv_e/dx_b = V_e cof F_e G_eb of each linear element."""
    for e in range(nodes.shape[0]):
        F = embedded(deformation_gradient(rest, u, nodes, grads, e, 0, d), d)
        C = weights[e, 0] * cofactor(F)
        volumes[e] = weights[e, 0] * F.determinant()
        for b in range(nodes.shape[1]):
            for i in ti.static(range(d)):
                entry = 0.0
                for j in ti.static(range(d)):
                    entry += C[i, j] * grads[e, 0, b, j]
                out[e, b, i] = entry


@ti.kernel
def nodal_volumetric(
    law: ti.template(), nodes: Nodes, weights: Weights, parameters: Parameters, ratios: Scalars, out: PerNode
):
    """out[e, a] = s_e (U_e, U_e', U_e'') at J_a = ratios[node a], s_e = V_e / (number of nodes)."""
    for e, a in ti.ndrange(nodes.shape[0], nodes.shape[1]):
        U = law.volumetric(ratios[nodes[e, a]], element_parameters(law, parameters, e))
        for i in ti.static(range(3)):
            out[e, a, i] = weights[e, 0] / nodes.shape[1] * U[i]


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


def require_nodal(law, order: int) -> None:
    """Refuse (PneumaInputError) nodal volumes on elements of order 2 or under a law without a volumetric part."""
    require(order == 1, f"volumetric = 'nodal' takes linear elements (order = 1), not order {order}")
    require(
        hasattr(law, "volumetric"),
        f"volumetric = 'nodal' takes a law split into an isochoric part and a volumetric one (law = neo_hookean, "
        f"mooney_rivlin, yeoh or a preset), not {law.name!r} (E and nu): its elements, left with no volume "
        f"stiffness of their own, turn inside out",
    )


class NodalVolumeElasticity(Elasticity):
    """The elastic energy of a mesh of linear triangles or tetrahedra with the law's volumetric part on nodal volume
    ratios (module docstring); otherwise as Elasticity (its max_step, fault and min_determinant are the
    elements')."""

    def __init__(self, config, elements: np.ndarray, law, parameters: np.ndarray):
        super().__init__(config, elements, law, parameters)
        require_nodal(law, self.family.order)
        self.split = volumetric_split(law)
        n, k = len(config.rest), self.nodes.shape[1]
        self.share = self.weights[:, 0] / k
        self.rest_volumes = np.bincount(self.nodes.ravel(), np.repeat(self.share, k), minlength=n)
        self.pair_of, self.triplets, blocks = star_structure(self.nodes, n)
        self.n_pairs = int(self.pair_of.max()) + 1
        d = self.dim
        star_rows = np.repeat(vertex_dofs(blocks[:, 0], d).reshape(-1, d), d, axis=1).ravel()
        star_cols = np.tile(vertex_dofs(blocks[:, 1], d).reshape(-1, d), (1, d)).ravel()
        rows, cols = block_pattern(self.nodes, d)
        self._rows, self._cols = np.concatenate([rows, star_rows]), np.concatenate([cols, star_cols])
        self.n_blocks = len(blocks)

    def _volumes(self):
        """(v_e (m,), dv_e/dx_b (m, k, d), J_a (n,))."""
        volumes = np.empty(len(self.nodes))
        gradients = np.empty((*self.nodes.shape, self.dim))
        volume_gradients(
            self.dim, self.config.rest, self.config.u, self.nodes, self.grads, self.weights, volumes, gradients
        )
        k = self.nodes.shape[1]
        nodal = np.bincount(self.nodes.ravel(), np.repeat(volumes / k, k), minlength=len(self.rest_volumes))
        return volumes, gradients, nodal / self.rest_volumes

    def _nodal(self, ratios):
        """Per node: (energy sum, c_a = sum s_e U_e'(J_a), C_a = sum s_e U_e''(J_a)) as one (3, n) array."""
        out = np.empty((*self.nodes.shape, 3))
        nodal_volumetric(self.law, self.nodes, self.weights, self.parameters, ratios, out)
        return np.array([np.bincount(self.nodes.ravel(), out[..., i].ravel(), minlength=len(ratios)) for i in range(3)])

    def _split_arguments(self, pressures):
        """The elastic kernels' arguments for the law without U plus the element pressures' work (pbar_e)."""
        parameters = np.ascontiguousarray(np.column_stack([self.parameters, pressures]))
        return (self.split, self.dim, self.config.rest, self.config.u, self.nodes, self.grads, self.weights, parameters)

    def _pressures(self, ratios):
        """pbar_e, the mean over element e's nodes of p_a = c_a / V_a, and the nodal sums."""
        sums = self._nodal(ratios)
        return (sums[1] / self.rest_volumes)[self.nodes].mean(axis=1), sums

    def energy(self) -> float:
        sums = self._nodal(self._volumes()[2])
        return elastic_energy(*self._split_arguments(np.zeros(len(self.nodes))))[0] + float(sums[0].sum())

    def gradient(self) -> np.ndarray:
        out = np.empty_like(self.config.rest)
        pressures, _ = self._pressures(self._volumes()[2])
        elastic_gradient(*self._split_arguments(pressures), out)
        return out

    def hessian_values(self, psd_only: bool = False) -> np.ndarray:
        _, gradients, ratios = self._volumes()
        pressures, sums = self._pressures(ratios)
        n = self.dim * self.nodes.shape[1]
        elements = np.empty((len(self.nodes), n * n))
        elastic_hessian(*self._split_arguments(pressures), int(psd_only), elements)
        k = self.nodes.shape[1]
        contributions = np.broadcast_to(gradients[:, None, :, :] / k, (len(self.nodes), k, k, self.dim))
        g = np.column_stack(
            [
                np.bincount(self.pair_of.ravel(), contributions[..., i].ravel(), minlength=self.n_pairs)
                for i in range(self.dim)
            ]
        )
        coefficients = sums[2] / self.rest_volumes**2
        if psd_only:
            coefficients = np.maximum(coefficients, 0.0)
        star = np.empty((self.n_blocks, self.dim * self.dim))
        star_hessian(self.dim, coefficients, np.ascontiguousarray(g), self.triplets, star)
        return np.concatenate([elements.ravel(), star.ravel()])
