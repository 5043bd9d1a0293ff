"""Central finite differences, the yardstick of every energy, gradient and Hessian test, and the dense Hessians
they are compared with.

A derivative by central differences: column i is (f(x + h e_i) - f(x - h e_i)) / 2h, with error O(h^2) f''' and
round-off O(eps |f| / h); h = H = 1e-6 balances the two for the O(1) states the tests use.
"""

import numpy as np
import pytest
import scipy.sparse as sp

H = 1e-6


def central(f, set_state, x, h: float = H) -> np.ndarray:
    """The central-difference derivative of f() (a number or an array, flattened) with respect to the flat state
    x: (x.size,) for a number (a gradient), (f.size, x.size) for an array (a Jacobian: the Hessian of the function
    whose gradient f is). set_state(y) puts the state at y (flat); it is left at x."""
    x = np.asarray(x, dtype=float).ravel()
    columns = []
    for i in range(x.size):
        step = np.zeros(x.size)
        step[i] = h
        set_state(x + step)
        plus = np.asarray(f(), dtype=float).ravel()
        set_state(x - step)
        columns.append((plus - np.asarray(f(), dtype=float).ravel()) / (2 * h))
    set_state(x)
    derivative = np.array(columns).T
    return derivative[0] if derivative.shape[0] == 1 else derivative


def at_config(config):
    """set_state for central: writes a term's Configuration's displacements config.u (n, d) in place."""

    def set_state(y):
        config.u[:] = y.reshape(config.u.shape)

    return set_state


def fd_gradient(model, term, u) -> np.ndarray:
    """dE/du of the term's energy (flat) by central differences, the model's displacements moved about u."""
    return central(term.energy, model.set_displacements, u)


def fd_hessian(model, terms, u) -> np.ndarray:
    """The Hessian of the terms' summed energy by central differences of their summed gradient about u."""
    return central(lambda: sum(t.gradient().ravel() for t in terms), model.set_displacements, u)


def term_derivatives(term, u) -> tuple[np.ndarray, np.ndarray]:
    """(gradient, Hessian) of a term by central differences of its energy and gradient about u, moving its
    configuration's displacements (no model)."""
    set_state = at_config(term.config)
    return central(term.energy, set_state, u), central(term.gradient, set_state, u)


def dense_hessian(n: int, parts, psd_only: bool = False) -> np.ndarray:
    """The dense (n, n) matrix of the given terms' sparse Hessian triplets (the PSD-projected ones if psd_only) plus
    their rank-1 parts (low_rank: c v v^T)."""
    hessian = np.zeros((n, n))
    for term in parts:
        rows, cols = term.hessian_pattern()
        hessian += sp.coo_matrix((term.hessian_values(psd_only), (rows, cols)), shape=(n, n)).toarray()
        for dofs, u, c in term.low_rank():
            v = np.zeros(n)
            v[dofs] = u
            hessian += c * np.outer(v, v)
    return hessian


def term_hessian(term, psd_only: bool = False) -> np.ndarray:
    """One term's dense Hessian (dense_hessian) over every DOF of its configuration."""
    return dense_hessian(term.config.u.size, [term], psd_only)


def random_state(built, scale: float = 0.02, seed: int = 0) -> np.ndarray:
    """Random displacements (n, d) of a built scene's nodes, normal with standard deviation `scale` (seeded)."""
    rng = np.random.default_rng(seed)
    return scale * rng.standard_normal(built.mesh.vertices.shape)


def check_reduced_derivatives(model, q: np.ndarray, direction: np.ndarray, h: float) -> None:
    """A reduced model's (reduce/model.py) E_r, g_r and H_r at coordinates q agree with central differences of E_r
    and g_r along `direction`, step h, to 1e-6."""

    def at(x):
        model.set_coordinates(x)
        return model.energy(), model.gradient()[0]

    (e_plus, g_plus), (e_minus, g_minus) = at(q + h * direction), at(q - h * direction)
    _, g = at(q)
    H = model.hessian()
    assert (e_plus - e_minus) / (2 * h) == pytest.approx(g @ direction, rel=1e-6)
    assert np.linalg.norm((g_plus - g_minus) / (2 * h) - H @ direction) <= 1e-6 * np.linalg.norm(H @ direction)
