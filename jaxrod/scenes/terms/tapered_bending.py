"""Bending of a tapered rod: 1/2 int_0^1 beta(s) |d3'|^2 ds, the stiffness E I(s) relative to
the scale E I of the energies, beta(s) = sum_k b_k T_k(2 s - 1) (Chebyshev polynomials on
[0, 1], as a remanence's strength; [1] is the uniform rod's ``bending``). Its moment balance
with a load's torque density tau(s) is (beta theta')' + tau = 0, beta theta'(1) = 0.
"""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp

from jaxrod.scenes.terms import term
from jaxrod.spectral import chebyshev_series


@term("tapered_bending")
class TaperedBending:
    """The rod's bending energy density beta(s) |d3'|^2 / 2, beta by its Chebyshev
    coefficients ``stiffness`` (the scale E I / L of the energies at beta = 1)."""

    elastic = True

    stiffness: jax.Array = dataclasses.field(default_factory=lambda: jnp.ones(1))

    def relative(self, s):
        """beta(s) = E I(s) / E I."""
        return chebyshev_series(self.stiffness, s)

    def density(self, d3, dd3, s):
        return 0.5 * self.relative(s) * jnp.dot(dd3, dd3)

    def planar(self, theta, dtheta, s):
        """The density on the planar rod: beta(s) theta'^2 / 2."""
        return 0.5 * self.relative(s) * dtheta**2
