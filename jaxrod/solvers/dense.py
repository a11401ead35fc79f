"""Small dense LU with partial pivoting written in jnp, unrolled over the columns.

For the batched fold solves (the 13 unknowns of the bordered fold matrix, the 2 of the
one-mode system, the 13 of the mode's KKT system), under ``vmap`` on a CPU. LAPACK's
batched LU (what ``jnp.linalg.solve`` calls on a CPU) spreads a batch over XLA's intra-op
thread pool and blocks until it is done; when two programs run at once (two CPU devices of
one process, or two dispatches of one program), the pool's threads can all end up blocked
there, each waiting for work queued behind the others: the process hangs for ever (seen with
two virtual CPU devices, and with two asynchronous dispatches, on a 2-core machine).
Elimination written in jnp has no such call. With static column indices (the loop unrolled
at trace time) and no gathers, scatters or arg-max reductions (slow under vmap on a CPU) it
takes 2-4.5x LAPACK's time for 13 unknowns and less for 2 (``benchmarks/dense_solve.py``),
about 15% of a batched fold pair's time.

Algorithm: Gaussian elimination with partial pivoting, PA = LU (Golub & Van Loan,
Algorithm 3.4.1), with rows left in place: step k takes as pivot the first row of largest
magnitude in column k among the rows that have not pivoted yet, and eliminates column k
from the other such rows. The pivot rows, in order, form U; the same eliminations applied
to b give the right-hand side of the back substitution.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp


class LU(NamedTuple):
    """The elimination of ``lu_factor``, in pivot order: ``upper`` (n, n) is U (row k is
    the pivot row of step k, final once chosen), ``pivots[k]`` the original row that
    pivoted at step k, ``multipliers[i, k]`` what row i lost of the pivot row at step k
    (zero for rows that had pivoted already)."""

    upper: jax.Array
    pivots: jax.Array
    multipliers: jax.Array


def _row(M, p):
    """Row p of M (p traced): a masked sum, no gather."""
    return jnp.sum(jnp.where(jnp.arange(M.shape[0])[:, None] == p, M, 0.0), axis=0)


def lu_factor(A) -> LU:
    """PA = LU of a small square matrix (n static, the loop unrolled). Rows are not moved:
    each step picks its pivot among the rows that have not pivoted yet (the first of
    largest magnitude in the column) and eliminates the column from the others."""
    n = A.shape[0]
    rows = jnp.arange(n)
    M, free = A, jnp.ones(n, bool)
    upper, pivots, multipliers = [], [], []
    for k in range(n):
        size = jnp.where(free, jnp.abs(M[:, k]), -1.0)
        p = jnp.min(jnp.where(size == jnp.max(size), rows, n))
        row = _row(M, p)
        free = free & (rows != p)
        f = jnp.where(free, M[:, k] / row[k], 0.0)
        M = M - f[:, None] * row
        upper.append(row)
        pivots.append(p)
        multipliers.append(f)
    return LU(jnp.stack(upper), jnp.stack(pivots), jnp.stack(multipliers, axis=1))


def lu_solve(factors: LU, b):
    """x = A^-1 b from ``lu_factor(A)``; b is (n,) or (n, r)."""
    U, pivots, F = factors
    n = U.shape[0]
    vector = b.ndim == 1
    y = b[:, None] if vector else b
    z = []
    for k in range(n):  # forward: the same eliminations on b
        zk = _row(y, pivots[k])
        z.append(zk)
        y = y - F[:, k][:, None] * zk
    z = jnp.stack(z)
    x = jnp.zeros_like(z)
    for k in reversed(range(n)):  # back substitution with U (x[j] = 0 for j <= k so far,
        # and U[k, j < k] is zero up to round-off: a whole-row product)
        x = x.at[k].set((z[k] - U[k] @ x) / U[k, k])
    return x[:, 0] if vector else x


def solve(A, b):
    """x = A^-1 b (``lu_factor`` then ``lu_solve``): ``jnp.linalg.solve`` for small
    matrices without LAPACK."""
    return lu_solve(lu_factor(A), b)


def smallest_eigenvalue_magnitude(A, iterations: int = 12):
    """|lambda| of the eigenvalue of the symmetric matrix A nearest zero, by inverse
    iteration with ``lu_factor`` (v <- A^-1 v / |A^-1 v|, then |v^T A v|; the error falls as
    (|lambda_1| / |lambda_2|)^k). No LAPACK call: under vmap on a CPU, LAPACK's batched
    eigensolver blocks like its batched LU (module docstring). A singular A gives 0."""
    factors = lu_factor(A)
    v = jnp.ones(A.shape[0], A.dtype) + 0.1 * jnp.arange(A.shape[0], dtype=A.dtype)

    def step(v, _):
        w = lu_solve(factors, v)
        return w / jnp.linalg.norm(w), None

    v, _ = jax.lax.scan(step, v / jnp.linalg.norm(v), None, length=iterations)
    value = jnp.abs(v @ A @ v)
    return jnp.where(jnp.isfinite(value), value, 0.0)
