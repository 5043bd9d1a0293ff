"""What a material law is, and the Taichi functions every kernel uses to evaluate one.

A law is a hyperelastic energy density psi(F) per unit rest volume, written once, as Taichi functions
of a 3 x 3 deformation gradient F and a small per-element parameter vector p:

    energy(F, p) = psi,   stress(F, p) = P = dpsi/dF (3 x 3),
    stress_derivative(F, p) = d2psi/dF2 (9 x 9 over vec(F) = (F00, F01, F02, F10, ..., F22)),
    volumetric(J, p) = (U, U', U'') of the law's volumetric part U(J), the one whose modulus grows without
                       bound as nu -> 1/2, where psi - U(J) is isochoric and grows without bound as J -> 0 (a
                       barrier against inverted elements): optional, for elements that do not lock
                       (volumetric_split, terms/nodal_volume.py: nodal volumes, one pressure per element).

Plane strain (d = 2) is the 3D law at F = [[F2, 0], [0, 1]]: the energy and the in-plane block of P are
those of the 2D body, and its d2psi/dF2 is the in-plane 4 x 4 block of the 3D one; the out-of-plane
entries of P give the stress that holds the thickness fixed. So a 2D kernel embeds its 2 x 2 F in a
3 x 3 one and calls the same functions as a 3D kernel would.

The projected-Newton Hessian needs the eigenpairs of d2psi/dF2 restricted to the d x d block. A law
may give them in closed form (eigensystem(F, p, d) for the d in analytic_dims, its fast path); in 3D an
isotropic law's come from F's SVD and its stress_derivative (materials.eigen.isotropic_eigensystem); for any
other d they come from materials.eigen's Jacobi iteration on stress_derivative. Either way
stress_eigensystem() returns d^2 eigenvalues and unit eigenvectors (rows).

The output fields use the same stress: the Cauchy stress sigma = P F^T / J (3 x 3, with sigma_zz of
plane strain), by the kernel cauchy_stresses.
"""

import functools
from typing import ClassVar

import numpy as np

from ..backend import ti
from ..io.registry import Registry
from .eigen import isotropic_eigensystem, symmetric_eigensystem
from .invariants import cofactor, determinant_hessian, flat


class Law:
    """Base of the laws. A law is a class of Taichi functions (static methods), passed to kernels as a
    template argument: each kernel compiles once per law and dimension.

    name: its registry key; parameter_names: the entries of its per-element parameter vector;
    analytic_dims: the dimensions d in which eigensystem() gives the eigenpairs of d2psi/dF2 in closed form;
    isotropic: psi(R F Q^T) = psi(F) for rotations R, Q, so that in 3D F's SVD gives the eigenvectors
    (eigen.isotropic_eigensystem).
    """

    name: ClassVar[str] = "law"
    parameter_names: tuple[str, ...] = ()
    analytic_dims: tuple[int, ...] = ()
    isotropic = True

    @staticmethod
    def parameters(youngs_modulus: np.ndarray, poisson_ratio: np.ndarray) -> np.ndarray:
        """The (m, len(parameter_names)) parameter vectors of m elements of the given moduli."""
        raise NotImplementedError

    @staticmethod
    def modulus(parameters: np.ndarray) -> np.ndarray:
        """A stiffness scale per element (m,), for the solver's round-off floors."""
        raise NotImplementedError

    @staticmethod
    def poisson_ratio(parameters: np.ndarray) -> np.ndarray | None:
        """The small-strain Poisson's ratio per parameter vector (m,), how near incompressible each is (what tells
        whether linear elements lock); None where the law does not tell it."""
        return None


LAWS: Registry[type[Law]] = Registry("law")  # name -> the law, filled by @LAWS.register (io/registry.py)


@functools.cache  # a memo of the class alone: one Split class per law, so its kernels compile once
def volumetric_split(law: type[Law]) -> type[Law]:
    """The law without its volumetric part, plus a given pressure's work: one more parameter pbar (the last),

        psi_s(F) = psi(F) - U(J) + pbar J,   P_s = P - (U'(J) - pbar) cof F,
        d2psi_s/dF2 = d2psi/dF2 - U''(J) cof F cof F^T - (U'(J) - pbar) d2J/dF2,

    the element part of the patch-averaged volumetric energy (terms/nodal_volume.py): at pbar = 0 the energy
    psi - U(J), at the averaged pressure its forces and Hessian. One class per law (so its kernels compile once);
    its eigenpairs (3D) from its SVD, as it is isotropic too."""
    n = len(law.parameter_names)

    @ti.func
    def own(p):
        return ti.Vector([p[i] for i in ti.static(range(n))], dt=ti.f64)

    class Split(Law):
        name = f"{law.name} without U(J)"
        parameter_names = (*law.parameter_names, "pbar")

        @staticmethod
        @ti.func
        def energy(F, p):
            J = F.determinant()
            return law.energy(F, own(p)) - law.volumetric(J, own(p))[0] + p[n] * J

        @staticmethod
        @ti.func
        def stress(F, p):
            return law.stress(F, own(p)) - (law.volumetric(F.determinant(), own(p))[1] - p[n]) * cofactor(F)

        @staticmethod
        @ti.func
        def stress_derivative(F, p):
            U = law.volumetric(F.determinant(), own(p))
            g = flat(cofactor(F))
            return law.stress_derivative(F, own(p)) - U[2] * g.outer_product(g) - (U[1] - p[n]) * determinant_hessian(F)

    return Split


@ti.func
def embedded(F, d: ti.template()):
    """The 3 x 3 deformation gradient whose leading d x d block is F (d x d) and whose rest is the identity."""
    F3 = ti.Matrix.identity(ti.f64, 3)
    for i, j in ti.static(ti.ndrange(d, d)):
        F3[i, j] = F[i, j]
    return F3


@ti.func
def element_parameters(law: ti.template(), parameters: ti.template(), e):
    """The parameter vector of element e from the (m, len(law.parameter_names)) array."""
    return ti.Vector([parameters[e, i] for i in ti.static(range(len(law.parameter_names)))], dt=ti.f64)


@ti.func
def in_plane(M, d: ti.template()):
    """The d^2 x d^2 block of a 9 x 9 d2psi/dF2 over the leading d x d entries of F."""
    R = ti.Matrix.zero(ti.f64, d * d, d * d)
    for i, j, k, l in ti.ndrange(d, d, d, d):
        R[d * i + j, d * k + l] = M[3 * i + j, 3 * k + l]
    return R


@ti.func
def stress_eigensystem(law: ti.template(), F, p, d: ti.template()):
    """Eigenvalues (d^2) and unit eigenvectors (rows, d^2 x d^2) of d2psi/dF2 on the leading d x d block of
    the 3 x 3 F: the law's closed form where it has one, else in 3D an isotropic law's from F's SVD
    (eigen.isotropic_eigensystem), else the Jacobi iteration."""
    if ti.static(d in law.analytic_dims):
        return law.eigensystem(F, p, d)
    elif ti.static(d == 3 and law.isotropic):
        return isotropic_eigensystem(law.stress_derivative(F, p), F)
    else:
        return symmetric_eigensystem(in_plane(law.stress_derivative(F, p), d))


@ti.kernel
def cauchy_stresses(
    law: ti.template(),
    d: ti.template(),
    F: ti.types.ndarray(dtype=ti.f64, ndim=3),
    parameters: ti.types.ndarray(dtype=ti.f64, ndim=2),
    out: ti.types.ndarray(dtype=ti.f64, ndim=3),
):
    """out[i] = sigma = P F^T / J (3 x 3) of each F[i] (d x d, embedded in 3 x 3) under parameters[i]."""
    for i in range(F.shape[0]):
        Fd = ti.Matrix.zero(ti.f64, d, d)
        for a, b in ti.static(ti.ndrange(d, d)):
            Fd[a, b] = F[i, a, b]
        F3 = embedded(Fd, d)
        sigma = law.stress(F3, element_parameters(law, parameters, i)) @ F3.transpose() / F3.determinant()
        for a, b in ti.static(ti.ndrange(3, 3)):
            out[i, a, b] = sigma[a, b]
