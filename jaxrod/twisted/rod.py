"""A rod twisted with both ends held: inputs, energy and constraints.

The framed Kirchhoff rod (``jaxrod.discretise.framed``; inextensible, unshearable, length L,
bending stiffnesses B1 <= or >= B2, twist stiffness C) is clamped at s = 0 and, at s = 1, held
by a second clamp that keeps the far end on the rod's axis e3 with its frame turned by
``turns`` about it. In units of B1 and L the energy is

    E = 1/2 int_0^1 (u1^2 + beta u2^2 + gamma u3^2) ds - t int_0^1 d3 . e3 ds,

beta = B2 / B1, gamma = C / B1 (``twist_ratio``), u the Darboux vector in the material frame,
t = T L^2 / B1 a dead tension pulling the far end along the axis (tension control); under
shortening control (``shortening`` e) the far end is held at height 1 - e instead. The
constraints g(x) = 0 are the far end's position, int d3_x ds = int d3_y ds = 0 (and
int d3_z ds = 1 - e), with multipliers mu (``jaxrod.solvers.constrained``): the reactions.
The end reactions reported:

    twist moment  m = M L / B1 = (1 / 2 pi) dE/d(turns)   (the moment about the axis that
                                                          the far clamp applies),
    tension       t = T L^2 / B1 = the input, or -mu_z under shortening control.

The isotropic rod (beta = 1) has a symmetry: turning the bent shape about the axis (the
fields v = (v1, v2) rotated at every s, psi unchanged) keeps the energy and both clamps, so
every bent equilibrium belongs to a circle of them and has a zero eigenvalue. The branch
pins it by a phase condition (``jaxrod.twisted.branch``): ``orbit_direction`` is its
generator, (-v2, v1, 0).
"""

from __future__ import annotations

import dataclasses
import math

import jax
import jax.numpy as jnp
import numpy as np

from jaxrod.discretise.framed import (
    FramedDiscretisation,
    frame,
    framed_discretisation,
    framed_jet,
)
from jaxrod.params import ParameterError

#: Multipliers are solved for in units of the clamped-clamped Euler load 4 pi^2 B1 / L^2, so
#: that the continuation's inner product weighs them like the shape's values.
MULTIPLIER_UNIT = 4.0 * math.pi**2

#: C / B1 of a circular section of Poisson ratio 1/2 (C / B = 1 / (1 + nu)).
DEFAULT_TWIST_RATIO = 2.0 / 3.0


@dataclasses.dataclass(frozen=True)
class TwistedRod:
    """A rod clamped at both ends, the far end turned (module docstring).

    twist_ratio: gamma = C / B1 > 0 (default 2/3: a circular section with Poisson ratio 1/2;
      ``from_poisson_ratio``). bending_ratio: B2 / B1 > 0. Exactly one of ``tension`` (T L^2 /
      B1, a dead load along the axis; any sign) and ``shortening`` (the far end at
      (1 - shortening) L, 0 < shortening < 1). n: the Chebyshev degree of each of the three
      fields (>= 8)."""

    twist_ratio: float = DEFAULT_TWIST_RATIO
    bending_ratio: float = 1.0
    tension: float | None = None
    shortening: float | None = None
    n: int = 48

    def __post_init__(self):
        for name in ("twist_ratio", "bending_ratio"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
                raise ParameterError(f"{name}: a finite number > 0, got {value!r}")
        if (self.tension is None) == (self.shortening is None):
            raise ParameterError("tension, shortening: give exactly one (the far end pulled by "
                                 "a dead tension, or held at 1 - shortening)")
        if self.tension is not None and not math.isfinite(self.tension):
            raise ParameterError(f"tension: a finite number, got {self.tension!r}")
        if self.shortening is not None and not (0.0 < self.shortening < 1.0):
            raise ParameterError(f"shortening: in (0, 1), got {self.shortening!r}")
        if not isinstance(self.n, (int, np.integer)) or self.n < 8:
            raise ParameterError(f"n: an integer >= 8, got {self.n!r}")

    @classmethod
    def from_poisson_ratio(cls, poisson_ratio: float, **kwargs) -> TwistedRod:
        """A circular section: C / B = 1 / (1 + nu), -1 < nu <= 1/2."""
        if not (-1.0 < poisson_ratio <= 0.5):
            raise ParameterError(f"poisson_ratio: in (-1, 0.5], got {poisson_ratio!r}")
        return cls(twist_ratio=1.0 / (1.0 + poisson_ratio), **kwargs)

    @property
    def control(self) -> str:
        """"tension" or "shortening"."""
        return "tension" if self.tension is not None else "shortening"

    @property
    def constraints(self) -> int:
        """How many constraints hold the far end: 2 (on the axis) or 3 (and its height)."""
        return 2 if self.tension is not None else 3

    def discretisation(self, n: int | None = None) -> FramedDiscretisation:
        return framed_discretisation(self.n if n is None else n, "clamped-clamped")

    def inputs(self) -> jax.Array:
        """(gamma, beta, t, e): the traced inputs of ``lagrangian``."""
        return jnp.array([self.twist_ratio, self.bending_ratio, self.tension or 0.0,
                          self.shortening or 0.0])


def energy(x, turns, disc: FramedDiscretisation, inputs) -> jax.Array:
    """E(x; turns) (module docstring)."""
    gamma, beta, tension = inputs[0], inputs[1], inputs[2]

    def density(a):
        F, u = framed_jet(a)
        return 0.5 * (u[0] ** 2 + beta * u[1] ** 2 + gamma * u[2] ** 2) - tension * F[2, 2]

    return disc.integrate(jax.vmap(density)(disc.jets(x, turns)))


def far_end(x, disc: FramedDiscretisation, inputs, count: int) -> jax.Array:
    """g(x): the far end's offset from the axis (and from height 1 - e: ``count`` = 3)."""
    d3 = jax.vmap(lambda a: frame(a[0], a[1], a[2])[:, 2])(disc.jets(x))
    g = jnp.stack([disc.integrate(d3[:, 0]), disc.integrate(d3[:, 1]),
                   disc.integrate(d3[:, 2]) - (1.0 - inputs[3])])
    return g[:count]


def orbit_direction(x, disc: FramedDiscretisation) -> jax.Array:
    """The symmetry's generator at x: (-v2, v1, 0) (module docstring)."""
    f = disc.free
    return jnp.concatenate([-x[f:2 * f], x[:f], jnp.zeros(f, x.dtype)])


def centreline(disc: FramedDiscretisation, x) -> np.ndarray:
    """(n + 1, 3): r(s) = int_0^s d3 at the Chebyshev nodes of the fields' grid."""
    field = disc.field
    values = np.asarray(field.to_full) @ np.asarray(x).reshape(3, disc.free).T
    d3 = np.asarray(jax.vmap(lambda v: frame(v[0], v[1], v[2])[:, 2])(jnp.asarray(values)))
    return np.asarray(field.cumint) @ d3
