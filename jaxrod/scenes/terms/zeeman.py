"""A uniform field acting on a magnetisation along the tangent (a hard-magnetic rod with
axial remanence, or a soft wire saturated with polarity +d3): the Zeeman energy

    -A_c M_r int_0^L d3 . B ds = -(A_c M_r B L^2 / (E I)) b . X,   X = int_0^1 d3 ds,

an exact derivative along the rod, so the endpoint potential -load b . X of the tip
(nondimensional, lengths in rod lengths). load = A_c M_r B L^2 / (E I) (the hard-magnetic
elastica's lambda, Wang et al., JMPS 2020); b = (sin a cos c, sin a sin c, cos a), the
field's angle a from +z toward +x and its azimuth c. With the field opposite the
magnetisation (a = pi) the clamped rod is the tip-loaded elastica: it buckles at
load = pi^2 / 4.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from jaxrod.scenes.terms import term


@term("zeeman")
class Zeeman:
    """load (A_c M_r B L^2 / (E I)), the field's angle from +z toward +x and its azimuth
    (radians)."""

    load: jax.Array | float
    angle: jax.Array | float = 0.0
    azimuth: jax.Array | float = 0.0

    def endpoint(self, X):
        """-load b . X."""
        b = jnp.stack([jnp.sin(self.angle) * jnp.cos(self.azimuth),
                       jnp.sin(self.angle) * jnp.sin(self.azimuth), jnp.cos(self.angle)])
        return -self.load * jnp.dot(b, X)

    def planar_endpoint(self, X):
        """-load b . X at an in-plane tip X = (X1, X3)."""
        return -self.load * (jnp.sin(self.angle) * jnp.cos(self.azimuth) * X[0]
                             + jnp.cos(self.angle) * X[1])
