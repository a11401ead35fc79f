"""A uniform field acting on a programmed hard magnetisation: the remanence at an angle
phi(s) to the tangent in the material frame (programmed profiles of magnetic soft robots and
cilia), on the planar rod, where the material frame is (d1, d3) with d1 = (cos theta, 0,
-sin theta): m = cos(phi) d3 + sin(phi) d1 = (sin(theta + phi), 0, cos(theta + phi)), and
the Zeeman energy is the density

    -load b . m = -load cos(theta + phi(s) - a),   load = A_c M_r B L^2 / (E I),

with the field's angle a from +z toward +x and phi(s) = sum_k c_k s^k (radians). Unlike
the tangent magnetisation (``zeeman``), it is no exact derivative along the rod: a density
of the jet. Planar rods only (a 3D rod's director chart carries no d1).
"""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp

from jaxrod.scenes.terms import term


@term("programmed")
class ProgrammedMagnetisation:
    """load, the field's angle a from +z toward +x (radians), and the magnetisation's angle
    to the tangent as polynomial coefficients in s (radians; [phi] for a constant angle)."""

    planar_only = True  # not a field: the 3D rod's chart carries no d1

    load: jax.Array | float
    angle: jax.Array | float = 0.0
    profile: jax.Array = dataclasses.field(default_factory=lambda: jnp.zeros(1))

    def phi(self, s):
        """phi(s) = sum_k c_k s^k."""
        return jnp.polyval(jnp.asarray(self.profile)[::-1], s)

    def planar(self, theta, dtheta, s):
        """-load cos(theta + phi(s) - a)."""
        return -self.load * jnp.cos(theta + self.phi(s) - self.angle)

    def density(self, d3, dd3, s):
        """The planar density from d3 = (sin theta, 0, cos theta) (in-plane rods only)."""
        return self.planar(jnp.arctan2(d3[0], d3[2]), None, s)
