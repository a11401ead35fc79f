"""Bending: 1/2 int_0^1 |d3'|^2 ds (paper, eq. nondimensional_master_energy_reduced).

In the plane |d3'|^2 = theta'^2. Lengths in rod lengths, energies in units of E I / L.
"""

from __future__ import annotations

import jax.numpy as jnp

from jaxrod.scenes.terms import term


@term("bending")
class Bending:
    """The rod's bending energy density |d3'|^2 / 2 (no inputs; the scale E I / L)."""

    elastic = True

    def density(self, d3, dd3, s):
        return 0.5 * jnp.dot(dd3, dd3)

    def planar(self, theta, dtheta, s):
        """The density on the planar rod: theta'^2 / 2."""
        return 0.5 * dtheta**2
