"""A point dipole (a magnet) anywhere, acting on a magnetisation along the tangent: outside
the magnet its field is curl-free, B = -grad psi with psi(x) = mu0 m m_hat . (x - c) /
(4 pi |x - c|^3), so the Zeeman energy -A_c M int d3 . B ds = A_c M (psi(tip) - psi(clamp))
is the endpoint potential (nondimensional, lengths in rod lengths; the clamp's constant
dropped)

    M m_hat . (X - c) / |X - c|^3,   M = A_c M_r mu0 m / (4 pi E I L),

of the tip X = int_0^1 d3 ds, for the magnet's centre c and the unit direction m_hat of its
moment m. A magnet on a straight rail has c = c0 + t u: ``position`` c0, ``rail`` u (a unit
vector) and the distance ``along`` it, t, an input like any other (the rail position is a
load parameter). A sphere of remanence M_m and diameter 2a has m = (4/3) pi a^3 M_m, and then M is
the paper's dipole group (eq. permanent_magnet_energy) for a soft wire with M_r = M_s. The
paper's magnet on its circle (c = D p, m_hat = p) is the term ``dipole``.
"""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp

from jaxrod.scenes.terms import term


@term("point_dipole")
class PointDipole:
    """Dipole group M, the magnet's centre (a 3-vector, rod lengths from the clamp), the
    direction of its moment (a 3-vector, normalised here), and a rail: its direction (a
    3-vector, normalised here) and the distance along it from ``position``."""

    M: jax.Array | float
    position: jax.Array = dataclasses.field(default_factory=lambda: jnp.array([0.0, 0.0, 2.0]))
    moment: jax.Array = dataclasses.field(default_factory=lambda: jnp.array([0.0, 0.0, 1.0]))
    rail: jax.Array = dataclasses.field(default_factory=lambda: jnp.array([1.0, 0.0, 0.0]))
    along: jax.Array | float = 0.0

    def centre(self):
        """c = position + along * rail / |rail|."""
        return self.position + self.along * self.rail / jnp.linalg.norm(self.rail)

    def endpoint(self, X):
        """M m_hat . (X - c) / |X - c|^3."""
        m = self.moment / jnp.linalg.norm(self.moment)
        r = X - self.centre()
        return self.M * jnp.dot(m, r) / jnp.dot(r, r) ** 1.5

    def planar_endpoint(self, X):
        """The same at an in-plane tip X = (X1, X3)."""
        return self.endpoint(jnp.stack([X[0], jnp.zeros_like(X[0]), X[1]]))
