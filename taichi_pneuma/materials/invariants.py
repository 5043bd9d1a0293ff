"""Invariants of a 3 x 3 deformation gradient F and their first and second derivatives, as Taichi functions.

Derivatives are over vec(F) = (F00, F01, F02, F10, ..., F22): a gradient is a 9-vector, a second
derivative a 9 x 9 matrix, with (ij) the row index 3 i + j. With C = F^T F, B = F F^T,

    J = det F          dJ/dF = g = cof F          (d2J/dF2)_(ij)(kl) = e_ikm e_jln F_mn   (e: permutation symbol)
    I1 = |F|^2         dI1/dF = 2 F               d2I1/dF2 = 2 Id
    I2 = (I1^2 - |C|^2) / 2      dI2/dF = 2 (I1 F - F C)
                                 d2I2/dF2 = dI1 dI1^T + 2 I1 Id - 2 (d_ik C_lj + F_il F_kj + B_ik d_jl)

and the isochoric invariants Ibar1 = c1 I1, Ibar2 = c2 I2 with c1 = |J|^(-2/3), c2 = |J|^(-4/3). For
c = |J|^k,

    dc/dF = k c / J g,   d2c/dF2 = k (k - 1) c / J^2 g g^T + k c / J d2J/dF2,

and by the product rule d(c I) = c dI + I dc, d2(c I) = c d2I + dI dc^T + dc dI^T + I d2c.

Using |J| extends the invariants smoothly to inverted F (J < 0), which the solver never accepts (its line
search keeps det F > 0) but finite differences through J = 0's neighbourhood may visit; they are
singular at J = 0 only.
"""

from ..backend import ti


@ti.func
def cofactor(F):
    """cof F = dJ/dF of a 3 x 3 matrix: (cof F)_ij = F_(i+1)(j+1) F_(i+2)(j+2) - F_(i+1)(j+2) F_(i+2)(j+1), mod 3."""
    C = ti.Matrix.zero(ti.f64, 3, 3)
    for i, j in ti.static(ti.ndrange(3, 3)):
        C[i, j] = (
            F[(i + 1) % 3, (j + 1) % 3] * F[(i + 2) % 3, (j + 2) % 3]
            - F[(i + 1) % 3, (j + 2) % 3] * F[(i + 2) % 3, (j + 1) % 3]
        )
    return C


@ti.func
def flat(M):
    """vec(M) of a 3 x 3 matrix: the 9-vector of its rows."""
    return ti.Vector([M[i, j] for i, j in ti.static(ti.ndrange(3, 3))], dt=ti.f64)


@ti.func
def determinant_hessian(F):
    """d2J/dF2 (9 x 9): (ij, kl) entry e_ikm e_jln F_mn, nonzero for i != k and j != l (m, n the third indices)."""
    H = ti.Matrix.zero(ti.f64, 9, 9)
    for i, j, k, l in ti.ndrange(3, 3, 3, 3):
        if i != k and j != l:
            sign = (1.0 if (k - i + 3) % 3 == 1 else -1.0) * (1.0 if (l - j + 3) % 3 == 1 else -1.0)
            H[3 * i + j, 3 * k + l] = sign * F[3 - i - k, 3 - j - l]
    return H


@ti.func
def second_invariant_hessian(F):
    """d2I2/dF2 (9 x 9) (module docstring)."""
    C, B = F.transpose() @ F, F @ F.transpose()
    dI1 = 2.0 * flat(F)
    M = dI1.outer_product(dI1)
    I1 = F.norm_sqr()
    for i, j, k, l in ti.ndrange(3, 3, 3, 3):
        term = F[i, l] * F[k, j]
        if i == k:
            term += C[l, j]
        if j == l:
            term += B[i, k]
        M[3 * i + j, 3 * k + l] -= 2.0 * term
        if i == k and j == l:
            M[3 * i + j, 3 * k + l] += 2.0 * I1
    return M


@ti.func
def isochoric_invariants(F):
    """(Ibar1, Ibar2, J)."""
    J = F.determinant()
    I1 = F.norm_sqr()
    C = F.transpose() @ F
    I2 = 0.5 * (I1 * I1 - C.norm_sqr())
    c1 = ti.abs(J) ** (-2.0 / 3.0)
    return c1 * I1, c1 * c1 * I2, J


@ti.func
def isochoric_gradients(F):
    """(dIbar1/dF, dIbar2/dF, dJ/dF), each a 9-vector."""
    I1, J, g = F.norm_sqr(), F.determinant(), flat(cofactor(F))
    C = F.transpose() @ F
    I2 = 0.5 * (I1 * I1 - C.norm_sqr())
    c1 = ti.abs(J) ** (-2.0 / 3.0)
    c2 = c1 * c1
    dI1, dI2 = 2.0 * flat(F), 2.0 * flat(I1 * F - F @ C)
    return c1 * dI1 - (2.0 / 3.0) * c1 * I1 / J * g, c2 * dI2 - (4.0 / 3.0) * c2 * I2 / J * g, g


@ti.func
def power_times(k: ti.template(), J, g, HJ, I, dI, d2I):
    """d2(|J|^k I)/dF2 = c d2I + dI dc^T + dc dI^T + I d2c, c = |J|^k (module docstring)."""
    c = ti.abs(J) ** k
    dc = k * c / J * g
    d2c = k * (k - 1.0) * c / (J * J) * g.outer_product(g) + k * c / J * HJ
    return c * d2I + dI.outer_product(dc) + dc.outer_product(dI) + I * d2c


@ti.func
def isochoric_hessians(F):
    """(d2Ibar1/dF2, d2Ibar2/dF2, d2J/dF2), each 9 x 9 (module docstring)."""
    I1, J, g = F.norm_sqr(), F.determinant(), flat(cofactor(F))
    C = F.transpose() @ F
    I2 = 0.5 * (I1 * I1 - C.norm_sqr())
    HJ = determinant_hessian(F)
    dI1, dI2 = 2.0 * flat(F), 2.0 * flat(I1 * F - F @ C)
    return (
        power_times(-2.0 / 3.0, J, g, HJ, I1, dI1, 2.0 * ti.Matrix.identity(ti.f64, 9)),
        power_times(-4.0 / 3.0, J, g, HJ, I2, dI2, second_invariant_hessian(F)),
        HJ,
    )
