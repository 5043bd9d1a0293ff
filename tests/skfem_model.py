"""The 3D model written independently with scikit-fem + SciPy, as a Python user would: the reference the
tests compare taichi-pneuma against, and the rival of benchmarks/skfem_3d.py.

Linear tetrahedra (ElementVector(ElementTetP1)), the stable neo-Hookean law per unit rest volume,

    psi(F) = mu (1 - J) + lam/2 (1 - J)^2 + mu/2 (|F|^2 - 3),
    P = dpsi/dF = mu F + (lam (J - 1) - mu) cof F,                        cof F = J F^-T,
    dP[H] = mu H + lam J tr(F^-1 H) cof F + (lam (J - 1) - mu) dcof[H],   dcof[H] = tr(F^-1 H) cof F - F^-T H^T cof F,

a cavity held at a volume by the penalty 1/2 k (V - V*)^2, with V the volume the deformed wall encloses
(Nanson: n da = cof F N dA on the reference wall; skfem's facet normal N points out of the rubber, into the
cavity, hence the minus sign):

    V = -1/3 int x . cof F N dA,   dV[v] = -int v . cof F N dA,   d2V[v, w] = -int v . dcof[grad w] N dA,

and the clamp as springs 1/2 K |u|^2 on the clamped nodes. Newton: the full (unprojected) Hessian,
k dV dV^T + k (V - V*) d2V for the cavity, solved by scipy.sparse.linalg.spsolve, the step halved until the
gradient's norm decreases; converged when |gradient| <= tol x the sum of the three forces' norms.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import spsolve
from skfem import Basis, BilinearForm, ElementTetP1, ElementVector, FacetBasis, Functional, LinearForm, MeshTet, asm
from skfem.helpers import ddot, det, dot, eye, grad, inv, mul, trace, transpose


def lame(E: float, nu: float) -> tuple[float, float]:
    return E / (2 * (1 + nu)), E * nu / ((1 + nu) * (1 - 2 * nu))


def deformation(w):
    return eye(np.ones_like(w["u"].grad[0, 0]), 3) + grad(w["u"])


def cofactor(F):
    return det(F) * transpose(inv(F))


def dcofactor(F, H):
    Finv = inv(F)
    cof = cofactor(F)
    return trace(mul(Finv, H)) * cof - mul(transpose(Finv), mul(transpose(H), cof))


@Functional
def strain_energy(w):
    F = deformation(w)
    J = det(F)
    return w["mu"] * (1 - J) + w["lam"] / 2 * (1 - J) ** 2 + w["mu"] / 2 * (ddot(F, F) - 3)


@LinearForm
def internal_force(v, w):
    F = deformation(w)
    J = det(F)
    return ddot(w["mu"] * F + (w["lam"] * (J - 1) - w["mu"]) * cofactor(F), grad(v))


@BilinearForm
def tangent(u, v, w):
    F = deformation(w)
    H = grad(u)
    J = det(F)
    cof = cofactor(F)
    dP = w["mu"] * H + w["lam"] * J * trace(mul(inv(F), H)) * cof + (w["lam"] * (J - 1) - w["mu"]) * dcofactor(F, H)
    return ddot(dP, grad(v))


@Functional
def cavity_volume(w):
    return -dot(w.x + w["u"], mul(cofactor(deformation(w)), w.n)) / 3


@LinearForm
def cavity_gradient(v, w):
    return -dot(v, mul(cofactor(deformation(w)), w.n))


@BilinearForm
def cavity_hessian(u, v, w):
    return -dot(v, mul(dcofactor(deformation(w), grad(u)), w.n))


@dataclass
class SkfemBody:
    """A P1 tetrahedral body (vertices (n, 3), tets (m, 4)), one cavity wall (triangles (f, 3)), clamped nodes."""

    vertices: np.ndarray
    tets: np.ndarray
    wall: np.ndarray
    clamped: np.ndarray
    E: float = 1e4
    nu: float = 0.45
    stiffness: float = 1e6
    clamp_stiffness: float = 1e9

    def __post_init__(self):
        mesh = MeshTet(np.ascontiguousarray(self.vertices.T), np.ascontiguousarray(self.tets.T))
        element = ElementVector(ElementTetP1())
        self.basis = Basis(mesh, element)
        index = {tuple(f): i for i, f in enumerate(np.sort(mesh.facets.T, axis=1))}
        facets = np.array([index[tuple(f)] for f in np.sort(self.wall, axis=1)])
        self.wall_basis = FacetBasis(mesh, element, facets=facets)
        self.mu, self.lam = lame(self.E, self.nu)
        # DOF numbering of ElementVector(P1): node i's x, y, z are nodal_dofs[:, i]
        self.clamp_dofs = self.basis.nodal_dofs[:, self.clamped].ravel()
        self.rest_volume = self.volume(np.zeros(self.basis.N))
        self.seconds = {"assembly": 0.0, "solve": 0.0}  # where the Newton iterations' time goes

    def fields(self, u: np.ndarray) -> dict:
        return {"u": self.basis.interpolate(u), "mu": self.mu, "lam": self.lam}

    def volume(self, u: np.ndarray) -> float:
        return float(asm(cavity_volume, self.wall_basis, u=self.wall_basis.interpolate(u)))

    def forces(self, u: np.ndarray, target: float) -> tuple[np.ndarray, float, float]:
        """The energy's gradient at displacements u with the cavity's volume target V*, the sum of the elastic,
        cavity and clamp forces' norms (the scale convergence is measured against), and V - V*."""
        start = time.perf_counter()
        elastic = asm(internal_force, self.basis, **self.fields(u))
        excess = self.volume(u) - target
        dV = asm(cavity_gradient, self.wall_basis, u=self.wall_basis.interpolate(u))
        clamp = np.zeros(self.basis.N)
        clamp[self.clamp_dofs] = self.clamp_stiffness * u[self.clamp_dofs]
        forces = (elastic, self.stiffness * excess * dV, clamp)
        self.seconds["assembly"] += time.perf_counter() - start
        return sum(forces), sum(np.linalg.norm(f) for f in forces), excess

    def hessian(self, u: np.ndarray, excess: float) -> sp.csr_matrix:
        """The energy's Hessian at u, where the cavity's volume exceeds its target by `excess`."""
        start = time.perf_counter()
        on_wall = self.wall_basis.interpolate(u)
        dV = asm(cavity_gradient, self.wall_basis, u=on_wall)
        wall = np.flatnonzero(dV)
        rank_one = sp.coo_matrix(
            (
                self.stiffness * np.outer(dV[wall], dV[wall]).ravel(),
                (np.repeat(wall, len(wall)), np.tile(wall, len(wall))),
            ),
            shape=(len(u), len(u)),
        )
        clamp = np.zeros(self.basis.N)
        clamp[self.clamp_dofs] = self.clamp_stiffness
        hessian = (
            asm(tangent, self.basis, **self.fields(u))
            + self.stiffness * excess * asm(cavity_hessian, self.wall_basis, u=on_wall)
            + rank_one
            + sp.diags(clamp)
        ).tocsr()
        self.seconds["assembly"] += time.perf_counter() - start
        return hessian

    def solve(self, u: np.ndarray, ratio: float, tol: float = 1e-6, max_iterations: int = 40) -> tuple[np.ndarray, int]:
        """Newton from u to the equilibrium at the volume ratio V* / V_rest, until |gradient| <= tol x the sum of
        the forces' norms (taichi-pneuma's criterion), each step halved until |gradient| decreases (at most
        ten times); (displacements, iterations)."""
        target = ratio * self.rest_volume
        gradient, scale, excess = self.forces(u, target)
        for iteration in range(max_iterations):
            if np.linalg.norm(gradient) <= tol * scale:
                return u, iteration
            hessian = self.hessian(u, excess)
            start = time.perf_counter()
            step = spsolve(hessian, gradient)
            self.seconds["solve"] += time.perf_counter() - start
            for halving in range(11):
                trial = u - step / 2**halving
                trial_gradient, trial_scale, trial_excess = self.forces(trial, target)
                if np.linalg.norm(trial_gradient) < np.linalg.norm(gradient):
                    break
            u, gradient, scale, excess = trial, trial_gradient, trial_scale, trial_excess
        raise RuntimeError(f"scikit-fem Newton: no equilibrium at volume ratio {ratio} in {max_iterations} iterations")

    def ramp(self, ratios, tol: float = 1e-6, progress=None) -> tuple[np.ndarray, int]:
        """Equilibria at each volume ratio in turn from rest: the nodal displacements (n, 3) of the last, and
        the Newton iterations in all; progress(ratio, iterations) after each."""
        u, total = np.zeros(self.basis.N), 0
        for ratio in ratios:
            u, iterations = self.solve(u, ratio, tol)
            total += iterations
            if progress is not None:
                progress(ratio, iterations)
        return u[self.basis.nodal_dofs].T, total
