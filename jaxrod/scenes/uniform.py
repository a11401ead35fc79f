"""The uniform-field scene: an upright rod in a vertical saturating field m = e3.

Energy (paper, eq. uniform_field_energy), Zeeman term constant and left out:

    E_unif[theta] = 1/2 int theta'^2 + A/2 int sin^2(theta) + G int (1 - s) cos(theta),

with the support (clamped: theta(0) = 0; pinned: free) carried by the discretisation.
The straight rod theta = 0 is an equilibrium for every (G, A); its Hessian is the discrete
form of the second variation int [u'^2 + (A - G (1 - s)) u^2] (Corollary "Second variation
at the gravity-opposed straight state").
"""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp

from jaxrod.discretise.planar import PlanarDiscretisation
from jaxrod.scenes.functionals import anisotropy_energy, bending_energy, gravity_energy
from jaxrod.scenes.scene import Scene
from jaxrod.scenes.terms import Anisotropy, Bending, Gravity


@jax.tree_util.register_dataclass
@dataclasses.dataclass(frozen=True)
class UniformField:
    """Scene parameters (G, A); both are traced, so changing them never recompiles.

    Energy (planar): E_unif[theta] = 1/2 int theta'^2 + A/2 int sin^2(theta) + G int (1 - s)
    cos(theta). Paper: eq. ``uniform_field_energy``.
    """

    G: jax.Array | float
    A: jax.Array | float

    tip_map = None  # no endpoint term (``jaxrod.derivatives``)

    @property
    def scene(self) -> Scene:
        """The same energy as a scene of terms (bending, gravity, the anisotropy) for the
        generic analyses; the methods below write it out for the planar rod (faster to
        compile and run; tests/test_engine.py checks that both agree)."""
        return Scene({"bending": Bending(), "gravity": Gravity(self.G),
                      "field": Anisotropy(self.A)})

    def density(self, a, s):
        """Energy density at one node, a = (theta, theta'):
        theta'^2 / 2 + G (1 - s) cos(theta) + A sin(theta)^2 / 2."""
        return 0.5 * a[1] ** 2 + self.G * (1.0 - s) * jnp.cos(a[0]) \
            + 0.5 * self.A * jnp.sin(a[0]) ** 2

    def energy(self, theta: jax.Array, disc: PlanarDiscretisation) -> jax.Array:
        return (bending_energy(theta, disc) + gravity_energy(theta, disc, self.G)
                + anisotropy_energy(theta, disc, self.A))
