"""Chebyshev spectral toolkit on the unit interval s in [0, 1].

Every rod quantity in jaxrod is a function of the arclength s in [0, 1], represented by
its values at the n + 1 Chebyshev points of the second kind

    s_j = (1 - cos(j pi / n)) / 2,    j = 0, ..., n,

so s_0 = 0 is the supported end and s_n = 1 the free end. The polynomial interpolant p of
degree n through these values is the object the operators below act on:

* ``differentiation_matrix``: (D f)_j = p'(s_j), exact for polynomials of degree <= n
  (Trefethen, *Spectral Methods in MATLAB*, ch. 6, with the negative-sum trick for the
  diagonal, mapped by ds = -dx / 2).
* ``clenshaw_curtis_weights``: sum_j w_j f(s_j) = int_0^1 p(s) ds, exact for degree <= n.
  The weights are the integrals of the Lagrange basis: with c_0 = c_n = 1, c_j = 2
  otherwise, and b_k = 1 for k = n / 2, b_k = 2 otherwise,

      w_j = (c_j / 2n) [1 - sum_{k=1}^{floor(n/2)} b_k cos(2 k j pi / n) / (4 k^2 - 1)]

  (Waldvogel, BIT 46 (2006) 195-202; the factor 1/2 maps [-1, 1] to [0, 1]). All w_j > 0.
* ``cumulative_integration_matrix``: (S f)_j = int_0^{s_j} p(s) ds, exact for degree <= n,
  built from the Chebyshev coefficients of p and int T_k = T_{k+1}/(2(k+1)) -
  T_{k-1}/(2(k-1)).
* ``interpolation_matrix``: barycentric formula of the second kind with weights
  (-1)^j delta_j (delta_0 = delta_n = 1/2), evaluating p at arbitrary points in [0, 1].

The matrices are built once per grid size in NumPy float64 and stored as JAX arrays; they
are constants of every compiled program that uses the grid.
"""

from __future__ import annotations

import dataclasses
from functools import lru_cache

import jax
import jax.numpy as jnp
import numpy as np

MIN_DEGREE = 2


def _check_degree(n: int) -> int:
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)):
        raise TypeError(f"n (polynomial degree) must be an integer, got {n!r}")
    if n < MIN_DEGREE:
        raise ValueError(f"n (polynomial degree) must be >= {MIN_DEGREE}, got {n}")
    return int(n)


def _reference_points(n: int) -> np.ndarray:
    """x_j = cos(j pi / n) on [-1, 1], in the sin form that makes x_{n-j} = -x_j exactly."""
    return np.sin(np.pi * (n - 2 * np.arange(n + 1)) / (2 * n))


def chebyshev_nodes(n: int) -> np.ndarray:
    """The n + 1 Chebyshev points of the second kind on [0, 1], ascending from s = 0."""
    return 0.5 * (1.0 - _reference_points(_check_degree(n)))


def barycentric_weights(n: int) -> np.ndarray:
    """Barycentric weights (-1)^j delta_j of the second-kind Chebyshev points.

    The sign is that of the points x_j = cos(j pi / n); a common scale factor of the
    weights cancels in the barycentric formula.
    """
    n = _check_degree(n)
    w = (-1.0) ** np.arange(n + 1)
    w[0] *= 0.5
    w[-1] *= 0.5
    return w


def differentiation_matrix(n: int) -> np.ndarray:
    """(n+1) x (n+1) matrix D with (D f)_j = p'(s_j) for the interpolant p of f."""
    n = _check_degree(n)
    x = _reference_points(n)
    c = np.ones(n + 1)
    c[0] = c[-1] = 2.0
    c *= (-1.0) ** np.arange(n + 1)
    dx = x[:, None] - x[None, :]
    d = np.outer(c, 1.0 / c) / (dx + np.eye(n + 1))
    d -= np.diag(d.sum(axis=1))
    return -2.0 * d  # s = (1 - x)/2  =>  d/ds = -2 d/dx


def clenshaw_curtis_weights(n: int) -> np.ndarray:
    """Clenshaw-Curtis weights on [0, 1]: sum_j w_j f(s_j) = int_0^1 p(s) ds."""
    n = _check_degree(n)
    theta = np.pi * np.arange(n + 1) / n
    v = np.ones(n + 1)
    for k in range(1, n // 2 + 1):
        b = 1.0 if 2 * k == n else 2.0
        v -= b * np.cos(2 * k * theta) / (4 * k * k - 1)
    c = np.full(n + 1, 2.0)
    c[0] = c[-1] = 1.0
    w = c * v / (2 * n)
    return 0.5 * (w + w[::-1])  # exactly symmetric, as the rule is


def values_to_coefficients_matrix(n: int) -> np.ndarray:
    """Matrix taking values at the nodes to coefficients a_k of p = sum_k a_k T_k(1 - 2s)."""
    n = _check_degree(n)
    theta = np.pi * np.arange(n + 1) / n
    c = np.ones(n + 1)
    c[0] = c[-1] = 2.0  # ends halved: the sum is the trapezoidal (double-primed) one
    t = np.cos(np.outer(np.arange(n + 1), theta))  # t[k, j] = T_k(x_j)
    return (2.0 / n) * t / c[None, :] / c[:, None]


def cumulative_integration_matrix(n: int) -> np.ndarray:
    """(n+1) x (n+1) matrix S with (S f)_j = int_0^{s_j} p(s) ds."""
    n = _check_degree(n)
    a = values_to_coefficients_matrix(n)  # coefficients in x = 1 - 2s
    # Antiderivative in x of sum a_k T_k, as coefficients of T_0..T_{n+1}.
    integ = np.zeros((n + 2, n + 1))
    integ[1, 0] = 1.0  # int T_0 = T_1
    integ[2, 1] = 0.25  # int T_1 = T_2 / 4 (+ const)
    for k in range(2, n + 1):
        integ[k + 1, k] += 1.0 / (2 * (k + 1))
        integ[k - 1, k] -= 1.0 / (2 * (k - 1))
    tk = np.cos(np.outer(np.pi * np.arange(n + 1) / n, np.arange(n + 2)))  # T_k(x_j)
    anti_x = tk @ integ @ a  # F(x_j) with F' = p in x
    # int_0^{s} p ds' = -(1/2) int_{1}^{x} p dx' = (F(1) - F(x)) / 2, and x = 1 at s = 0.
    return 0.5 * (anti_x[0][None, :] - anti_x)


def interpolation_matrix(n: int, points) -> np.ndarray:
    """Matrix P with (P f)_i = p(points_i): barycentric interpolation from the n-grid.

    Points may be anywhere in [0, 1]; a point that coincides with a node gets the
    corresponding unit row exactly.
    """
    n = _check_degree(n)
    points = np.asarray(points, dtype=float).reshape(-1)
    if not np.all(np.isfinite(points)):
        raise ValueError("points must be finite")
    if np.any(points < -1e-14) or np.any(points > 1 + 1e-14):
        raise ValueError("points must lie in [0, 1]")
    s = chebyshev_nodes(n)
    w = barycentric_weights(n)
    diff = points[:, None] - s[None, :]
    exact = diff == 0.0
    diff = np.where(exact, 1.0, diff)
    ratio = w[None, :] / diff
    p = ratio / ratio.sum(axis=1, keepdims=True)
    hit = exact.any(axis=1)
    p[hit] = exact[hit].astype(float)
    return p


@jax.tree_util.register_dataclass
@dataclasses.dataclass(frozen=True)
class ChebyshevGrid:
    """All spectral operators of the degree-n grid on [0, 1], as JAX arrays.

    ``n`` is static (it fixes array shapes); the arrays are PyTree leaves.
    """

    n: int = dataclasses.field(metadata=dict(static=True))
    nodes: jax.Array
    diff: jax.Array
    weights: jax.Array
    cumint: jax.Array

    def integrate(self, f: jax.Array) -> jax.Array:
        """Clenshaw-Curtis quadrature int_0^1 f ds of nodal values f (last axis)."""
        return f @ self.weights

    def derivative(self, f: jax.Array) -> jax.Array:
        return self.diff @ f


def chebyshev_series(coefficients, s):
    """sum_k c_k T_k(2 s - 1) at s in [0, 1] by Clenshaw's recurrence (traceable in the
    coefficients; the profiles' basis, ``jaxrod.scenes.terms``: [1] is the constant 1)."""
    c = jnp.asarray(coefficients)
    x = 2.0 * s - 1.0
    b1 = b2 = jnp.zeros_like(x)
    for d in c[:0:-1]:
        b1, b2 = d + 2.0 * x * b1 - b2, b1
    return c[0] + x * b1 - b2


@lru_cache(maxsize=64)
def _grid_arrays(n: int):
    return (
        chebyshev_nodes(n),
        differentiation_matrix(n),
        clenshaw_curtis_weights(n),
        cumulative_integration_matrix(n),
    )


def chebyshev_grid(n: int) -> ChebyshevGrid:
    """The ``ChebyshevGrid`` of degree n (n + 1 points), cached per n.

    The discretisation behind every result (not in the paper, which uses a sine-series Ritz
    method): nodes s_j = (1 - cos(pi j / n)) / 2, spectral differentiation, Clenshaw-Curtis
    quadrature.
    """
    nodes, diff, weights, cumint = _grid_arrays(_check_degree(n))
    return ChebyshevGrid(
        n=n,
        nodes=jnp.asarray(nodes),
        diff=jnp.asarray(diff),
        weights=jnp.asarray(weights),
        cumint=jnp.asarray(cumint),
    )
