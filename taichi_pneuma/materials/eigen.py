"""Eigen-decomposition of a small symmetric matrix in a Taichi function: cyclic Jacobi, runtime loops.

For a law without an analytic eigensystem of its d2psi/dF2 (d^2 x d^2), the projected Hessian needs
M = V diag(lambda) V^T at every quadrature point. Cyclic Jacobi zeroes each off-diagonal entry A_pq in
turn by a plane rotation, A <- J^T A J, with (Golub & Van Loan, algorithm 8.4.2)

    theta = (A_qq - A_pp) / (2 A_pq),   t = sign(theta) / (|theta| + sqrt(theta^2 + 1)),
    c = 1 / sqrt(t^2 + 1),   s = t c,

accumulating V <- V J; sweeps repeat until the off-diagonal part is below EPSILON of the whole (it
converges quadratically: 5-8 sweeps for 9 x 9). The loops are runtime loops over a matrix indexed at
run time, so Taichi traces the body once: compiling it costs well under a second, where the unrolled
version (every rotation written out) cost 16 s.
"""

from ..backend import ti

EPSILON = 1e-15
MAX_SWEEPS = 50


@ti.func
def rotate(A, V, p, q):
    """One Jacobi rotation zeroing A[p, q]; returns the rotated (A, V)."""
    n = ti.static(A.n)
    theta = (A[q, q] - A[p, p]) / (2.0 * A[p, q])
    t = 1.0 / (ti.abs(theta) + ti.sqrt(theta * theta + 1.0))
    if theta < 0:
        t = -t
    c = 1.0 / ti.sqrt(t * t + 1.0)
    s = t * c
    for k in range(n):  # columns p, q of A and V
        akp, akq = A[k, p], A[k, q]
        A[k, p], A[k, q] = c * akp - s * akq, s * akp + c * akq
        vkp, vkq = V[k, p], V[k, q]
        V[k, p], V[k, q] = c * vkp - s * vkq, s * vkp + c * vkq
    for k in range(n):  # rows p, q of A
        apk, aqk = A[p, k], A[q, k]
        A[p, k], A[q, k] = c * apk - s * aqk, s * apk + c * aqk
    return A, V


@ti.func
def symmetric_eigensystem(M):
    """Eigenvalues (an n-vector) and unit eigenvectors (the rows of an n x n matrix) of symmetric M."""
    n = ti.static(M.n)
    A, V = M, ti.Matrix.identity(ti.f64, n)
    for _ in range(MAX_SWEEPS):
        off, whole = 0.0, 0.0
        for i, j in ti.ndrange(n, n):
            whole += A[i, j] * A[i, j]
            if i != j:
                off += A[i, j] * A[i, j]
        if off <= EPSILON * EPSILON * whole:
            break
        for p in range(n - 1):
            for q in range(p + 1, n):
                if A[p, q] != 0:
                    A, V = rotate(A, V, p, q)
    values = ti.Vector.zero(ti.f64, n)
    for i in range(n):
        values[i] = A[i, i]
    return values, V.transpose()
