"""Shape anisotropy of a soft wire in a uniform saturating field along the unit vector h:
A/2 int_0^1 |d3 x h|^2 ds = A/2 int [1 - (d3 . h)^2] ds (paper, eq. uniform_field_energy,
the demagnetising term; A the anisotropy group).

Written as |d3 x h|^2, not 1 - (d3 . h)^2: the same function, without the cancellation
near d3 = h (in the plane with h = e3 it is sin(theta)^2 exactly).
"""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp

from jaxrod.scenes.terms import term


@term("anisotropy")
class Anisotropy:
    """Anisotropy group A and the field direction h (a unit 3-vector; default e3)."""

    A: jax.Array | float
    direction: jax.Array = dataclasses.field(default_factory=lambda: jnp.array([0.0, 0.0, 1.0]))

    def density(self, d3, dd3, s):
        """A |d3 x h|^2 / 2."""
        c = jnp.cross(d3, self.direction)
        return 0.5 * self.A * jnp.dot(c, c)

    def planar(self, theta, dtheta, s):
        """The density on the planar rod: with h = (h1, h2, h3) and d3 = (sin, 0, cos),
        |d3 x h|^2 = (cos h2)^2 + (cos h1 - sin h3)^2 + (sin h2)^2."""
        h = self.direction
        sn, cs = jnp.sin(theta), jnp.cos(theta)
        return 0.5 * self.A * (h[1] ** 2 + (cs * h[0] - sn * h[2]) ** 2)
