"""A point dipole moved along any parametrised curve: the centre

    c(t) = sum_k a_k t^k   (3-vectors a_k, rod lengths),

with the moment along a fixed direction m_hat, or along the curve's tangent c'(t) /
|c'(t)| (``moment_along_path``). The energy is that of ``point_dipole``,
M m_hat . (X - c) / |X - c|^3 at the tip X; the curve parameter t is an input like any other
(a magnet on a curved guide, moved by a motor). A straight rail is the curve of degree 1.
"""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp

from jaxrod.scenes.terms import term


@term("path_dipole")
class PathDipole:
    """Dipole group M, the curve's coefficients (K, 3) (c(t) = sum_k a_k t^k), the curve
    parameter t, the moment's fixed direction (a 3-vector), and ``moment_along_path`` (1.0:
    the moment along c'(t) instead; 0.0: the fixed direction)."""

    M: jax.Array | float
    coefficients: jax.Array = dataclasses.field(
        default_factory=lambda: jnp.array([[0.0, 0.0, 2.0], [1.0, 0.0, 0.0]]))
    t: jax.Array | float = 0.0
    moment: jax.Array = dataclasses.field(default_factory=lambda: jnp.array([0.0, 0.0, 1.0]))
    moment_along_path: jax.Array | float = 0.0

    def centre(self):
        """c(t)."""
        a = jnp.asarray(self.coefficients)
        powers = self.t ** jnp.arange(a.shape[0])
        return powers @ a

    def tangent(self):
        """c'(t) / |c'(t)|."""
        a = jnp.asarray(self.coefficients)
        k = jnp.arange(1, a.shape[0])
        d = (k * self.t ** (k - 1)) @ a[1:]
        return d / jnp.linalg.norm(d)

    def endpoint(self, X):
        """M m_hat . (X - c) / |X - c|^3."""
        fixed = self.moment / jnp.linalg.norm(self.moment)
        m = jnp.where(self.moment_along_path > 0.5, self.tangent(), fixed)
        r = X - self.centre()
        return self.M * jnp.dot(m, r) / jnp.dot(r, r) ** 1.5

    def planar_endpoint(self, X):
        """The same at an in-plane tip X = (X1, X3)."""
        return self.endpoint(jnp.stack([X[0], jnp.zeros_like(X[0]), X[1]]))
