"""Gravity: G int_0^1 (1 - s) d3 . (-g) ds for gravity along the unit vector g.

The potential of a uniform rod clamped at the origin, int_0^1 r(s) . (-g) ds with r(s) =
int_0^s d3, integrated by parts (paper, eq. gravity_director; G = rho g A L^3 / (E I)).
The default g = -e3 is the paper's rod standing up against gravity.
"""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp

from jaxrod.scenes.terms import term


@term("gravity")
class Gravity:
    """Gravity group G and direction (a unit 3-vector; default -e3, the rod upright)."""

    G: jax.Array | float
    direction: jax.Array = dataclasses.field(default_factory=lambda: jnp.array([0.0, 0.0, -1.0]))

    def density(self, d3, dd3, s):
        """-G (1 - s) d3 . g (= G (1 - s) cos(theta) for g = -e3)."""
        return -self.G * (1.0 - s) * jnp.dot(d3, self.direction)

    def planar(self, theta, dtheta, s):
        """The density on the planar rod, d3 = (sin theta, 0, cos theta)."""
        g = self.direction
        return -self.G * (1.0 - s) * (jnp.sin(theta) * g[0] + jnp.cos(theta) * g[2])
