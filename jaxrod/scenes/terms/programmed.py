"""A uniform field acting on a programmed hard magnetisation: the remanence at an angle
phi(s) to the tangent in the material frame, of strength mu(s) relative to the load
(programmed profiles of magnetic soft robots, catheters and cilia), on the planar rod, where
the material frame is (d1, d3) with d1 = (cos theta, 0, -sin theta):
m = mu(s) (cos(phi) d3 + sin(phi) d1) = mu(s) (sin(theta + phi), 0, cos(theta + phi)), and
the Zeeman energy is the density

    -load b . m = -load mu(s) cos(theta + phi(s) - a),   load = A_c M_r B L^2 / (E I),

with the field's angle a from +z toward +x, phi(s) = sum_k c_k s^k (radians) and
mu(s) = sum_k d_k T_k(2 s - 1) (Chebyshev polynomials on [0, 1]: well conditioned as free
inputs of a design; [1] is the uniform remanence). Its moment balance is
theta'' + load mu(s) sin(a - theta - phi(s)) = 0 with theta'(1) = 0. Unlike the tangent
magnetisation (``zeeman``), it is no exact derivative along the rod: a density of the jet.
Planar rods, and rods that carry their frame (``framed``); the 3D director chart carries no
d1.
"""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp

from jaxrod.scenes.terms import term
from jaxrod.spectral import chebyshev_series


@term("programmed")
class ProgrammedMagnetisation:
    """load, the field's angle a from +z toward +x (radians), the magnetisation's angle to
    the tangent as polynomial coefficients in s (radians; [phi] for a constant angle), its
    strength relative to the load as Chebyshev coefficients in 2 s - 1 ([1]: uniform), and
    the field's azimuth c about +z from +x (radians; a rod that carries its frame only: the
    planar rod's field lies in its plane, c = 0)."""

    planar_only = True  # not a field: the 3D rod's chart carries no d1

    load: jax.Array | float
    angle: jax.Array | float = 0.0
    profile: jax.Array = dataclasses.field(default_factory=lambda: jnp.zeros(1))
    strength: jax.Array = dataclasses.field(default_factory=lambda: jnp.ones(1))
    azimuth: jax.Array | float = 0.0

    def phi(self, s):
        """phi(s) = sum_k c_k s^k."""
        return jnp.polyval(jnp.asarray(self.profile)[::-1], s)

    def mu(self, s):
        """mu(s) = sum_k d_k T_k(2 s - 1)."""
        return chebyshev_series(self.strength, s)

    def planar(self, theta, dtheta, s):
        """-load mu(s) cos(theta + phi(s) - a)."""
        return -self.load * self.mu(s) * jnp.cos(theta + self.phi(s) - self.angle)

    def framed(self, F, dF, s):
        """-load mu(s) b . (cos(phi) d3 + sin(phi) d1) on a rod that carries its frame
        F = (d1, d2, d3) (``jaxrod.twisted``): the remanence in the material plane (d1, d3),
        b = (sin a cos c, sin a sin c, cos a). In the plane (c = 0, d1 = (cos theta, 0,
        -sin theta)) it is ``planar``."""
        phi = self.phi(s)
        m = jnp.cos(phi) * F[:, 2] + jnp.sin(phi) * F[:, 0]
        b = jnp.stack([jnp.sin(self.angle) * jnp.cos(self.azimuth),
                       jnp.sin(self.angle) * jnp.sin(self.azimuth), jnp.cos(self.angle)])
        return -self.load * self.mu(s) * jnp.dot(b, m)

    def density(self, d3, dd3, s):
        """The planar density from d3 = (sin theta, 0, cos theta) (in-plane rods only)."""
        return self.planar(jnp.arctan2(d3[0], d3[2]), None, s)
