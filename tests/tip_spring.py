"""A new energy term in one file: a linear spring pulling the tip towards an anchor,
k/2 |X - X_a|^2 (X the tip position, rod lengths; k in units of E I / L^3). Its registration
is the decorator; nothing else in jaxrod knows of it."""

import jax
import jax.numpy as jnp

from jaxrod.scenes.terms import term


@term("tip_spring")
class TipSpring:
    """Spring constant k and anchor point (a 3-vector)."""

    k: jax.Array | float
    anchor: jax.Array

    def endpoint(self, X):
        d = X - self.anchor
        return 0.5 * self.k * jnp.dot(d, d)
