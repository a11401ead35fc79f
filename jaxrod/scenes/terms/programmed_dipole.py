"""A magnet (point dipole) acting on a programmed hard magnetisation: the remanence at an
angle phi(s) to the tangent (``programmed``), in the magnet's non-uniform field. The Zeeman
energy is no longer an exact derivative along the rod: it is the distributed functional of
the positions r(s) and directors (nondimensional, lengths in rod lengths)

    -M int_0^1 m(s) . b(r(s) - c) ds,   b(rho) = (3 (m_hat . rho_hat) rho_hat - m_hat) / |rho|^3,

m(s) = (sin(theta + phi), 0, cos(theta + phi)) the magnetisation's direction on the planar
rod, c the magnet's centre, m_hat its moment's direction, M the dipole group of
``point_dipole`` (with phi = 0 the two terms differ by a constant: the potential at the
clamp). On a rod that carries its frame (``jaxrod.twisted``) the magnetisation is
m(s) = cos(phi) d3 + sin(phi) d1 in the material frame (``framed_distributed``), which in
the plane (d1 = (cos theta, 0, -sin theta)) is the planar rod's. Not on the 3D director
chart, which carries no d1.
"""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp

from jaxrod.scenes.terms import term


@term("programmed_dipole")
class ProgrammedDipole:
    """Dipole group M, the magnet's centre (3-vector) and moment direction (3-vector,
    normalised here), and the magnetisation's angle to the tangent as polynomial
    coefficients in s (radians)."""

    planar_only = True  # not a field

    M: jax.Array | float
    position: jax.Array = dataclasses.field(default_factory=lambda: jnp.array([0.0, 0.0, 2.0]))
    moment: jax.Array = dataclasses.field(default_factory=lambda: jnp.array([0.0, 0.0, 1.0]))
    profile: jax.Array = dataclasses.field(default_factory=lambda: jnp.zeros(1))

    def centre(self):
        """The magnet's centre (rod lengths from the clamp)."""
        return jnp.asarray(self.position)

    def _phi(self, s):
        return jnp.polyval(jnp.asarray(self.profile)[::-1], s)

    def distributed(self, r, d3, s, w):
        """-M sum_j w_j m_j . b(r_j - c), m_j = d3 turned by phi(s_j) about e2 (in the
        plane)."""
        phi = self._phi(s)
        c, sn = jnp.cos(phi), jnp.sin(phi)
        m = jnp.stack([c * d3[:, 0] + sn * d3[:, 2], d3[:, 1],
                       -sn * d3[:, 0] + c * d3[:, 2]], axis=1)
        return self._zeeman(r, m, w)

    def framed_distributed(self, r, F, s, w):
        """The same with m_j = cos(phi) d3 + sin(phi) d1 of the frames F_j = (d1, d2, d3)
        (n_q, 3, 3) of a rod that carries its frame."""
        phi = self._phi(s)
        m = jnp.cos(phi)[:, None] * F[:, :, 2] + jnp.sin(phi)[:, None] * F[:, :, 0]
        return self._zeeman(r, m, w)

    def _zeeman(self, r, m, w):
        """-M sum_j w_j m_j . b(r_j - c)."""
        u = self.moment / jnp.linalg.norm(self.moment)
        rho = r - self.position
        dist = jnp.linalg.norm(rho, axis=1)
        hat = rho / dist[:, None]
        b = (3.0 * (hat @ u)[:, None] * hat - u) / dist[:, None] ** 3
        return -self.M * jnp.dot(w, jnp.sum(m * b, axis=1))
