"""The smallest eigenvalue (and eigenvector) of a generalised symmetric eigenproblem

    H v = lam M v,    H symmetric, M symmetric positive definite,

by the Cholesky reduction M = L L^T, C = L^-1 H L^-T (symmetrised against round-off) and a
symmetric eigensolver: the stability tests of the straight rod (beta0), of planar states out
of the plane, of the reduced route's coercivity and its Poincare constant.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp


def _reduced(H, M):
    L = jnp.linalg.cholesky(M)
    solve_l = lambda b: jax.scipy.linalg.solve_triangular(L, b, lower=True)
    C = solve_l(solve_l(H).T).T
    return 0.5 * (C + C.T), L


def smallest_generalised_eigenvalue(H, M):
    """The smallest lam of H v = lam M v."""
    C, _ = _reduced(H, M)
    return jnp.linalg.eigvalsh(C)[0]


def smallest_generalised_eigenpair(H, M):
    """(lam, v): the smallest eigenpair of H v = lam M v, normalised by v^T M v = 1."""
    C, L = _reduced(H, M)
    lam, V = jnp.linalg.eigh(C)
    return lam[0], jax.scipy.linalg.solve_triangular(L.T, V[:, 0], lower=False)
