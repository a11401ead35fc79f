"""The jnp LU with partial pivoting against numpy's (LAPACK) solve."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxrod.programs import jit
from jaxrod.solvers import dense


@pytest.mark.parametrize("n", [1, 2, 5, 13])
def test_solves_like_lapack(n):
    rng = np.random.default_rng(n)
    A = rng.standard_normal((20, n, n))
    b = rng.standard_normal((20, n, 3))
    x = jit(jax.vmap(dense.solve))(A, b)
    np.testing.assert_allclose(x, np.linalg.solve(A, b), rtol=1e-9, atol=1e-11)
    v = jit(jax.vmap(dense.solve))(A, b[..., 0])  # one right-hand side as a vector
    np.testing.assert_allclose(v, np.linalg.solve(A, b[..., :1])[..., 0], rtol=1e-9,
                               atol=1e-11)


def test_pivots_where_elimination_without_pivoting_fails():
    # zero leading entries (no pivoting divides by zero), and a tiny one (no pivoting loses
    # every digit of x[0]); a permutation matrix
    A = np.array([[0.0, 2.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 3.0]])
    b = np.array([1.0, 2.0, 3.0])
    np.testing.assert_allclose(dense.solve(jnp.asarray(A), jnp.asarray(b)),
                               np.linalg.solve(A, b), rtol=1e-14)
    A = np.array([[1e-20, 1.0], [1.0, 1.0]])
    np.testing.assert_allclose(dense.solve(jnp.asarray(A), jnp.array([1.0, 2.0])),
                               np.linalg.solve(A, [1.0, 2.0]), rtol=1e-14)
    P = np.eye(6)[[3, 0, 5, 1, 4, 2]]
    np.testing.assert_allclose(dense.solve(jnp.asarray(P), jnp.arange(6.0)),
                               np.linalg.solve(P, np.arange(6.0)), rtol=0, atol=0)


def test_factor_once_solve_twice_and_float32():
    rng = np.random.default_rng(0)
    A = rng.standard_normal((13, 13)) + 13 * np.eye(13)
    f = dense.lu_factor(jnp.asarray(A))
    for k in range(2):
        b = rng.standard_normal(13)
        np.testing.assert_allclose(dense.lu_solve(f, jnp.asarray(b)), np.linalg.solve(A, b),
                                   rtol=1e-12)
    x32 = dense.solve(jnp.asarray(A, jnp.float32), jnp.ones(13, jnp.float32))
    assert x32.dtype == jnp.float32
    np.testing.assert_allclose(x32, np.linalg.solve(A, np.ones(13)), rtol=1e-5)


def test_singular_matrix_gives_nonfinite_not_a_number_that_looks_right():
    A = jnp.array([[1.0, 2.0], [2.0, 4.0]])
    assert not bool(jnp.all(jnp.isfinite(dense.solve(A, jnp.array([1.0, 0.0])))))


def test_smallest_eigenvalue_magnitude_matches_numpy():
    """Inverse iteration with the jnp LU against numpy's symmetric eigensolver: symmetric
    12 x 12 matrices with the eigenvalue nearest zero at 1e-1 ... 1e-6 (either sign), and an
    exactly singular one (0)."""
    import jax

    from jaxrod.solvers.dense import smallest_eigenvalue_magnitude

    rng = np.random.default_rng(3)
    mats, expected = [], []
    for near in (1e-1, -1e-2, 1e-3, -1e-6):
        Q, _ = np.linalg.qr(rng.normal(size=(12, 12)))
        ev = np.concatenate([[near], rng.uniform(0.5, 5.0, 11) * rng.choice([-1, 1], 11)])
        mats.append(Q @ np.diag(ev) @ Q.T)
        expected.append(abs(np.linalg.eigvalsh(mats[-1])).min())
    got = np.asarray(jax.vmap(smallest_eigenvalue_magnitude)(np.stack(mats)))
    np.testing.assert_allclose(got, expected, rtol=1e-6)
    singular = np.diag(np.r_[0.0, np.arange(1.0, 12.0)])
    assert float(smallest_eigenvalue_magnitude(singular)) < 1e-12
