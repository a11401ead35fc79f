"""The two scenes in three dimensions, on a ``DirectorDiscretisation`` (paper, eqs.
nondimensional_master_energy_reduced and permanent_magnet_energy_reduced, before restriction to
the plane):

    uniform field   E = 1/2 int |d3'|^2 + G int (1 - s) d3 . e3 + A/2 int [1 - (d3 . e3)^2]
    permanent magnet E = 1/2 int |d3'|^2 + G int (1 - s) d3 . e3 + M Phi_p(X),  X = int d3,
                    Phi_p(x) = p . (x - D p) / |x - D p|^3,  p any unit vector.

Restricted to d3 = sin(theta) e1 + cos(theta) e3 they are the planar scenes' energies.
"""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp

from jaxrod.discretise.director import DirectorDiscretisation, director, director_jet


def magnet_position(alpha, beta=0.0):
    """p = (sin a cos b, sin a sin b, cos a): polar angle alpha from e3, azimuth beta from e1
    (beta = 0 is the experiment's plane).

    Paper: the magnet's position on the sphere of radius D, eq. ``permanent_magnet_energy``.
    """
    return jnp.stack([jnp.sin(alpha) * jnp.cos(beta), jnp.sin(alpha) * jnp.sin(beta),
                      jnp.cos(alpha)])


def _common(x, disc: DirectorDiscretisation, G):
    d3, dd3 = disc.at_quadrature(x)
    lever = 1.0 - disc.planar.quad_nodes
    bend = 0.5 * disc.integrate(jnp.sum(dd3 * dd3, axis=-1))
    return d3, bend + G * disc.integrate(lever * d3[:, 2])


@jax.tree_util.register_dataclass
@dataclasses.dataclass(frozen=True)
class UniformField3D:
    """Scene parameters (G, A) of the uniform field on the director discretisation (traced).

    Energy: E = 1/2 int norm(d3')^2 + G int (1 - s) d3 . e3 + A/2 int [1 - (d3 . e3)^2].
    Paper: eq. ``uniform_field_energy``.
    """

    G: jax.Array | float
    A: jax.Array | float

    tip_map = None  # no endpoint term (``jaxrod.derivatives``)

    def density(self, a, s):
        """|d3'|^2 / 2 + G (1 - s) d3 . e3 + A [1 - (d3 . e3)^2] / 2 at one node."""
        d3, dd3 = director_jet(a)
        return 0.5 * jnp.dot(dd3, dd3) + self.G * (1.0 - s) * d3[2] \
            + 0.5 * self.A * (1.0 - d3[2] ** 2)

    def energy(self, x, disc: DirectorDiscretisation):
        d3, e = _common(x, disc, self.G)
        return e + 0.5 * self.A * disc.integrate(1.0 - d3[:, 2] ** 2)


@jax.tree_util.register_dataclass
@dataclasses.dataclass(frozen=True)
class DipoleMagnet3D:
    """(G, M, D) and the magnet direction p (a unit 3-vector; see ``magnet_position``).

    Energy: E = 1/2 int norm(d3')^2 + G int (1 - s) d3 . e3 + M Phi_p(X), X = int d3. Paper:
    eq. ``permanent_magnet_energy``.
    """

    G: jax.Array | float
    M: jax.Array | float
    D: jax.Array | float
    p: jax.Array

    def density(self, a, s):
        """|d3'|^2 / 2 + G (1 - s) d3 . e3 at one node."""
        d3, dd3 = director_jet(a)
        return 0.5 * jnp.dot(dd3, dd3) + self.G * (1.0 - s) * d3[2]

    def tip_map(self, a):
        """Integrand of the tip position: d3."""
        return director(a[0], a[1])

    def endpoint(self, X):
        """M Phi_p(X)."""
        r = X - self.D * self.p
        return self.M * jnp.dot(self.p, r) / jnp.dot(r, r) ** 1.5

    def energy(self, x, disc: DirectorDiscretisation):
        d3, e = _common(x, disc, self.G)
        X = disc.integrate(d3.T)
        r = X - self.D * self.p
        return e + self.M * jnp.dot(self.p, r) / jnp.dot(r, r) ** 1.5
