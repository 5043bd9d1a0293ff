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

The rotation-variant SVD of a 3 x 3 F (F = U diag(sigma) V^T with U, V rotations, sigma_3 negative when
det F < 0) comes from the same iteration on C = F^T F = V diag(sigma^2) V^T (eigenvalues sorted down,
v_3 flipped to make det V = 1): u_1 = F v_1 / |F v_1|, u_2 the unit part of F v_2 normal to u_1,
u_3 = u_1 x u_2, and sigma_i = u_i . F v_i (signed). Unlike Taichi's own ti.svd (a fixed number of
approximate rotations: |U S V^T - F| up to 4e-10 |F| in float64) it is exact to round-off.

For an isotropic law (psi(R F Q^T) = psi(F) for rotations R, Q) the SVD gives the 9 x 9 d2psi/dF2's eigenvectors
without iterating (isotropic_eigensystem; Smith et al. 2019, "Analytic eigensystems for isotropic distortion
energies"): in the frame of U and V the Hessian at diag(sigma) keeps each pair {e_ij, e_ji} (i != j) apart from the
rest (reflections diag(+-1) on both sides fix diag(sigma)) and is symmetric in the two (psi(F^T) = psi(F)), so

    twist_k = (u_i v_j^T - u_j v_i^T) / sqrt 2,   flip_k = (u_i v_j^T + u_j v_i^T) / sqrt 2    ((i, j, k) cyclic)

are eigenvectors, for repeated singular values too; the other three lie in the span of D_i = u_i v_i^T, the
eigenvectors of the 3 x 3 A_ij = D_i : M : D_j. Each eigenvalue is its vector's Rayleigh quotient q . M q (exact
for an eigenvector), so any isotropic law's M serves: 9 matrix-vector products and a 3 x 3 Jacobi instead of the
9 x 9 one.
"""

from ..backend import ti

EPSILON = 1e-15
MAX_SWEEPS = 50
SQRT_HALF = 0.7071067811865476


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


@ti.func
def unit_or(v, fallback):
    """v / |v|, or fallback (a unit vector) where v vanishes."""
    out = fallback
    length = v.norm()
    if length > 1e-150:
        out = v / length
    return out


@ti.func
def rotation_variant_svd(F):
    """(U, sigma, V) of a 3 x 3 F: F = U diag(sigma) V^T, U and V rotations, sigma_1 >= sigma_2 >= |sigma_3|
    (module docstring)."""
    values, rows = symmetric_eigensystem(F.transpose() @ F)
    order = ti.Vector([0, 1, 2])
    for i in ti.static(range(2)):  # sort the three eigenvalues down
        for j in ti.static(range(2 - i)):
            if values[order[j]] < values[order[j + 1]]:
                order[j], order[j + 1] = order[j + 1], order[j]
    V = ti.Matrix.zero(ti.f64, 3, 3)
    for i, k in ti.ndrange(3, 3):
        V[k, i] = rows[order[i], k]
    if V.determinant() < 0:
        for k in ti.static(range(3)):
            V[k, 2] = -V[k, 2]
    v1 = ti.Vector([V[0, 0], V[1, 0], V[2, 0]])
    v2 = ti.Vector([V[0, 1], V[1, 1], V[2, 1]])
    v3 = ti.Vector([V[0, 2], V[1, 2], V[2, 2]])
    u1 = unit_or(F @ v1, ti.Vector([1.0, 0.0, 0.0]))
    w = F @ v2
    across = ti.Vector([1.0, 0.0, 0.0]) if ti.abs(u1[0]) < 0.9 else ti.Vector([0.0, 1.0, 0.0])
    u2 = unit_or(w - u1.dot(w) * u1, u1.cross(across).normalized())
    u3 = u1.cross(u2)
    U = ti.Matrix.cols([u1, u2, u3])
    return U, ti.Vector([u1.dot(F @ v1), u2.dot(w), u3.dot(F @ v3)]), V


@ti.func
def isotropic_eigensystem(M, F):
    """Eigenvalues (9) and unit eigenvectors (rows of a 9 x 9 matrix, over vec(F) row by row) of the d2psi/dF2 M of
    an isotropic law at the 3 x 3 F: twists, flips, then scalings (module docstring)."""
    U, _, V = rotation_variant_svd(F)
    values = ti.Vector.zero(ti.f64, 9)
    vectors = ti.Matrix.zero(ti.f64, 9, 9)
    D = ti.Matrix.zero(ti.f64, 3, 9)
    for k in ti.static(range(3)):
        i, j = (k + 1) % 3, (k + 2) % 3
        for a, b in ti.static(ti.ndrange(3, 3)):
            vectors[k, 3 * a + b] = SQRT_HALF * (U[a, i] * V[b, j] - U[a, j] * V[b, i])
            vectors[3 + k, 3 * a + b] = SQRT_HALF * (U[a, i] * V[b, j] + U[a, j] * V[b, i])
            D[k, 3 * a + b] = U[a, k] * V[b, k]
    for m in ti.static(range(6)):
        q = ti.Vector([vectors[m, c] for c in ti.static(range(9))], dt=ti.f64)
        values[m] = q.dot(M @ q)
    scalings, rows = symmetric_eigensystem(D @ M @ D.transpose())
    for m in ti.static(range(3)):
        values[6 + m] = scalings[m]
        for c in ti.static(range(9)):
            vectors[6 + m, c] = rows[m, 0] * D[0, c] + rows[m, 1] * D[1, c] + rows[m, 2] * D[2, c]
    return values, vectors
