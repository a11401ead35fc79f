"""The permanent-magnet scene: a clamped rod pulled by a dipole moving on a circle.

A uniformly magnetised sphere is, outside itself, a point dipole. With the rod's
magnetisation locked to its tangent (m = d3) the Zeeman energy is an exact derivative along
the centreline and reduces to M Phi(X) at the tip X = int_0^1 d3 ds (paper, section
"Conservative field from a permanent magnet"), so the planar energy is

    E_perm[theta] = 1/2 int theta'^2 + G int (1 - s) cos(theta) + M Phi_alpha(X),
    X = int_0^1 (sin(theta) e1 + cos(theta) e3) ds,

    Phi_alpha(x) = p . (x - D p) / |x - D p|^3,   p = sin(alpha) e1 + cos(alpha) e3,

with the magnet centre at D p on a circle of radius D (in rod lengths) about the clamp and
its moment along p (radially outward); alpha is measured from the vertical e3 towards e1.
The demagnetising term vanishes identically (m = d3) and the support is clamped.
"""

from __future__ import annotations

import dataclasses
import math

import jax
import jax.numpy as jnp

from jaxrod.derivatives import Structured
from jaxrod.design_point import DesignPoint
from jaxrod.discretise.planar import PlanarDiscretisation
from jaxrod.params import ParameterError
from jaxrod.scenes.functionals import bending_energy, gravity_energy
from jaxrod.scenes.scene import Scene
from jaxrod.scenes.terms import Bending, Dipole, Gravity


def magnet_direction(alpha):
    """p(alpha) = sin(alpha) e1 + cos(alpha) e3 as the (e1, e3) pair."""
    return jnp.stack([jnp.sin(alpha), jnp.cos(alpha)])


def dipole_potential(x, p, D):
    """Phi(x) = p . (x - D p) / |x - D p|^3 (dimensionless, singular at the magnet centre)."""
    r = x - D * p
    return jnp.dot(p, r) / jnp.dot(r, r) ** 1.5


def tip_position(theta: jax.Array, disc: PlanarDiscretisation) -> jax.Array:
    """X = int_0^1 (sin theta, cos theta) ds as the (e1, e3) pair.

    Paper: the tip X = int d3 at which the dipole potential is evaluated, eq.
    ``permanent_magnet_energy``.
    """
    th, _ = disc.at_quadrature(theta)
    return jnp.stack([disc.integrate(jnp.sin(th)), disc.integrate(jnp.cos(th))])


def tip_angle(theta: jax.Array, disc: PlanarDiscretisation) -> jax.Array:
    """Polar angle of the tip from the vertical, atan(X1 / X3) (radians).

    Paper: the experiment's tip displacement angle, Corollary ``cor:tip_angle_fold``.
    """
    X = tip_position(theta, disc)
    return jnp.arctan2(X[0], X[1])


@jax.tree_util.register_dataclass
@dataclasses.dataclass(frozen=True)
class DipoleMagnet:
    """Scene parameters (G, M, D, alpha), all traced: no recompilation when they change.

    ``alpha`` is the magnet angle in radians. Validate user input with
    ``jaxrod.params.check_groups`` before building a scene (this object is also built
    inside traced code, where no Python check can run).

    Energy (planar): E_perm[theta] = 1/2 int theta'^2 + G int (1 - s) cos(theta) + M
    Phi_alpha(X), X = int_0^1 (sin theta, cos theta) ds, Phi_alpha(x) = p . (x - D p) /
    norm(x - D p)^3, p = (sin alpha, cos alpha). Paper: eq.
    ``permanent_magnet_energy_reduced``.
    """

    G: jax.Array | float
    M: jax.Array | float
    D: jax.Array | float
    alpha: jax.Array | float

    @property
    def scene(self) -> Scene:
        """The same energy as a scene of terms (bending, gravity, the dipole) for the generic
        analyses. The methods below are the same energy written out for the planar rod: the
        paper's analyses compile and run faster with them (tests/test_engine.py checks that
        both agree)."""
        return Scene({"bending": Bending(), "gravity": Gravity(self.G),
                      "magnet": Dipole(self.M, self.D, self.alpha)})

    def density(self, a, s):
        """Energy density at one node, a = (theta, theta'): theta'^2 / 2 + G (1 - s) cos."""
        return 0.5 * a[1] ** 2 + self.G * (1.0 - s) * jnp.cos(a[0])

    def tip_map(self, a):
        """Integrand of the tip position, d3 = (sin theta, cos theta)."""
        return jnp.stack([jnp.sin(a[0]), jnp.cos(a[0])])

    def endpoint(self, X):
        """M Phi_alpha(X)."""
        return self.M * dipole_potential(X, magnet_direction(self.alpha), self.D)

    def energy(self, theta: jax.Array, disc: PlanarDiscretisation) -> jax.Array:
        X = tip_position(theta, disc)
        return (bending_energy(theta, disc) + gravity_energy(theta, disc, self.G)
                + self.M * dipole_potential(X, magnet_direction(self.alpha), self.D))

    def with_alpha(self, alpha) -> DipoleMagnet:
        return dataclasses.replace(self, alpha=alpha)


def _at_alpha(alpha, args):
    scene, disc = args
    return scene.with_alpha(alpha), disc


#: E_perm as a function of (theta, alpha) with args = (scene, disc), its derivatives assembled
#: from the scene's structure (``jaxrod.derivatives``): the model the magnet solvers use.
ALPHA_MODEL = Structured(_at_alpha)


def preset_or_scene(scene, vary, paper, generic, need: str):
    """``paper(scene)`` for the paper's rig (a ``DipoleMagnet``) without ``vary``: the
    paper's question on its preset; else ``generic(scene)`` on the scene (the paper's rig as
    its scene of terms). ``need`` says what ``vary`` is for in the error without one."""
    if vary is None:
        if not isinstance(scene, DipoleMagnet):
            raise ParameterError(f"vary: name the input {need} (a key of the scene, or any "
                                 "number of a rig file)")
        return paper(scene)
    return generic(scene.scene if isinstance(scene, DipoleMagnet) else scene)


#: The paper's name of each input -> (the rig's key, the name's value per unit of the key).
KEYS = {"E": ("rod.youngs_modulus", 1.0), "density": ("rod.density", 1.0),
        "gravity": ("gravity.g", 1.0), "diameter": ("rod.radius", 2.0),
        "length": ("rod.length", 1.0), "rod-magnetisation": ("magnetisation.saturation", 1.0),
        "remanence": ("field.0.remanence", 1.0), "magnet-diameter": ("field.0.diameter", 1.0),
        "track-radius": ("field.0.radius", 1.0)}
#: The groups' keys in the paper's scene (its magnet angle in radians).
GROUP_KEYS = {"G": ("gravity.G", 1.0), "M": ("magnet.M", 1.0), "D": ("magnet.D", 1.0)}


def rig_of(point: DesignPoint):
    """(scene or rig, the magnet angle's key, its range, degrees per its unit, the names'
    keys) of a design point: the shipped rig at a physical point's values, or the paper's
    scene of the groups."""
    if point.kind == "groups":
        G, M, D = point.groups()
        return (DipoleMagnet(G, M, D, 0.0).scene, "magnet.alpha", (0.0, 0.5 * math.pi),
                180.0 / math.pi, GROUP_KEYS)
    from jaxrod.scenes.files import load

    rig = load("permanent-magnet", [f"{KEYS[n][0]}={v / KEYS[n][1]!r}"
                                    for n, v in zip(point.names, point.values)])
    return rig, "field.0.angle_deg", (0.0, 90.0), 1.0, KEYS
