"""A permanent magnet (a point dipole) acting on the paper's soft wire, magnetised along its
tangent: the Zeeman energy is an exact derivative along the rod and reduces to the endpoint
potential M Phi(X) of the tip X = int_0^1 d3 ds (paper, section "Conservative field from a
permanent magnet", eq. permanent_magnet_energy):

    Phi(x) = p . (x - D p) / |x - D p|^3,   p = (sin a cos b, sin a sin b, cos a),

the magnet centre at D p on the sphere of radius D (rod lengths) about the clamp, its moment
along p (radially outward); alpha = a from the vertical e3 towards e1, beta = b the azimuth
(0 in the paper's plane). M is the paper's dipole group.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from jaxrod.scenes.terms import term


def unit_vector(alpha, beta=0.0):
    """p = (sin a cos b, sin a sin b, cos a)."""
    return jnp.stack([jnp.sin(alpha) * jnp.cos(beta), jnp.sin(alpha) * jnp.sin(beta),
                      jnp.cos(alpha)])


@term("dipole")
class Dipole:
    """Dipole group M, clearance D (> 1: the magnet is beyond the rod's reach) and the
    magnet's angles alpha, beta (radians) on its sphere round the clamp."""

    M: jax.Array | float
    D: jax.Array | float
    alpha: jax.Array | float = 0.0
    beta: jax.Array | float = 0.0

    def centre(self):
        """The magnet's centre D p (rod lengths from the clamp)."""
        return self.D * unit_vector(self.alpha, self.beta)

    def endpoint(self, X):
        """M Phi(X)."""
        p = unit_vector(self.alpha, self.beta)
        r = X - self.D * p
        return self.M * jnp.dot(p, r) / jnp.dot(r, r) ** 1.5

    def planar_endpoint(self, X):
        """M Phi at a tip in the plane, X = (X1, X3) (e1, e3 components): with |p| = 1,
        p . r = p . X - D and |r|^2 = |X|^2 - 2 D p . X + D^2, where only p's in-plane
        components enter p . X."""
        px = jnp.dot(jnp.stack([jnp.sin(self.alpha) * jnp.cos(self.beta), jnp.cos(self.alpha)]),
                     X)
        r2 = jnp.dot(X, X) - 2.0 * self.D * px + self.D * self.D
        return self.M * (px - self.D) * jax.lax.rsqrt(r2) ** 3
