"""Planar energy terms, each a functional of theta(s) on a ``PlanarDiscretisation``.

With d3 = sin(theta) e1 + cos(theta) e3 the terms of the nondimensional energy
(paper, eq. nondimensional_master_energy_reduced) become

    bending      1/2 int_0^1 |d3'|^2 ds          = 1/2 int theta'^2 ds
    gravity      G int_0^1 (1 - s) d3 . e3 ds     = G int (1 - s) cos(theta) ds
    anisotropy   A/2 int_0^1 [1 - (e3 . d3)^2] ds = A/2 int sin(theta)^2 ds
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from jaxrod.discretise.planar import PlanarDiscretisation


def bending_energy(theta: jax.Array, disc: PlanarDiscretisation) -> jax.Array:
    """1/2 int_0^1 theta'(s)^2 ds."""
    _, dtheta = disc.at_quadrature(theta)
    return 0.5 * disc.integrate(dtheta**2)


def gravity_energy(theta: jax.Array, disc: PlanarDiscretisation, G) -> jax.Array:
    """G int_0^1 (1 - s) cos(theta(s)) ds (eq. gravity_director, scaled by B / L)."""
    th, _ = disc.at_quadrature(theta)
    return G * disc.integrate((1.0 - disc.quad_nodes) * jnp.cos(th))


def anisotropy_energy(theta: jax.Array, disc: PlanarDiscretisation, A) -> jax.Array:
    """A/2 int_0^1 sin(theta(s))^2 ds: the demagnetising term with m = e3 (uniform field)."""
    th, _ = disc.at_quadrature(theta)
    return 0.5 * A * disc.integrate(jnp.sin(th) ** 2)
