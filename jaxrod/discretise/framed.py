"""Chebyshev discretisation of the framed rod: the cross-section's frame (d1, d2, d3)(s).

Chart: the frame is

    F(v, psi) = Q(v) R3(psi),

Q(v) the rotation by |v| about e3 x v / |v| = (-v2, v1, 0) / |v| (it takes e3 to the director
chart's d3(v) = cos|v| e3 + (sin|v| / |v|) (v1 e1 + v2 e2), ``jaxrod.discretise.director``),
R3(psi) the rotation by psi about e3: psi turns the cross-section about its tangent. The
columns of F are (d1, d2, d3). Like the director chart it is smooth wherever d3 does not point
straight down (|v| < pi), with no pole at the straight, axis-aligned state; psi is an angle on
the real line, so an end turned by 27 turns is psi(1) = 54 pi, with no singularity.

The Darboux vector in the material frame, u = (d2' . d3, d3' . d1, d1' . d2) (F^T F' = [u]x),
is for this chart

    u = R3(psi)^T w + psi' e3,   w3 = -(1 - cos|v|) / |v|^2 (v1 v2' - v2 v1'),

w the body angular velocity of Q (its first two components the director's bending:
u1^2 + u2^2 = |d3'|^2). Along a helix of cone angle alpha, v = alpha (cos ks, sin ks),
the frame Q twists at -(1 - cos alpha) k: over a turn, minus the cone's solid angle (the
holonomy of the sphere; checked in the tests).

Each of v1, v2, psi is discretised like the planar angle (free nodal values on the Chebyshev
grid of degree n, integrals by Clenshaw-Curtis on a finer grid). Supports: "clamped" (F(0) =
I: the three fields vanish at s = 0) and "clamped-clamped" (also F(1) = R3(2 pi turns): v(1) =
0 and psi(1) = 2 pi turns, the turns lifted, psi = 2 pi turns s + the free part).
"""

from __future__ import annotations

import dataclasses
import math

import jax
import jax.numpy as jnp

from jaxrod.discretise.director import _series_or, _sinc_sqrt
from jaxrod.discretise.planar import PlanarDiscretisation, field_discretisation
from jaxrod.params import ParameterError

#: The framed rod's supports: the frame held at s = 0, or at both ends.
FRAMED_SUPPORTS = ("clamped", "clamped-clamped")

_ONE_MINUS_COS = [(-1) ** k / math.factorial(2 * k + 2) for k in range(7)]


def _one_minus_cos_over(x):
    """(1 - cos(sqrt(x))) / x, analytic at x = 0."""
    return _series_or(x, _ONE_MINUS_COS, lambda y: (1.0 - jnp.cos(jnp.sqrt(y))) / y)


def frame(v1, v2, psi):
    """F = Q(v) R3(psi), (3, 3), columns (d1, d2, d3) (module docstring; scalars)."""
    r2 = v1 * v1 + v2 * v2
    w = jnp.stack([-v2, v1, jnp.zeros_like(v1)])
    W = jnp.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])
    Q = jnp.eye(3) + _sinc_sqrt(r2) * W + _one_minus_cos_over(r2) * (W @ W)
    c, s = jnp.cos(psi), jnp.sin(psi)
    R3 = jnp.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    return Q @ R3


def framed_jet(a):
    """(F, u) at one node from its jet a = (v1, v2, psi, v1', v2', psi'): the frame and the
    Darboux vector in the material frame, u = (d2' . d3, d3' . d1, d1' . d2)."""
    F, dF = jax.jvp(lambda q: frame(q[0], q[1], q[2]), (a[:3],), (a[3:],))
    d1, d2, d3 = F[:, 0], F[:, 1], F[:, 2]
    return F, jnp.stack([jnp.dot(dF[:, 1], d3), jnp.dot(dF[:, 2], d1), jnp.dot(dF[:, 0], d2)])


@jax.tree_util.register_dataclass
@dataclasses.dataclass(frozen=True)
class FramedDiscretisation:
    """The frame by the nodal values of v1, v2 and psi, stacked as x = [v1; v2; psi], each a
    ``field`` (``jaxrod.discretise.planar.field_discretisation``); ``jet_matrix`` (m + 1,
    6, size) takes x to the jets, ``lift(turns)`` adds the far end's turns
    (clamped-clamped)."""

    field: PlanarDiscretisation

    @property
    def support(self) -> str:
        return self.field.support

    @property
    def quad_nodes(self) -> jax.Array:
        return self.field.quad_nodes

    @property
    def free(self) -> int:
        """Free nodal values of one field."""
        return self.field.size

    @property
    def size(self) -> int:
        return 3 * self.free

    @property
    def jet_matrix(self) -> jax.Array:
        P, Pd = self.field.to_quad, self.field.to_quad_diff
        Z = jnp.zeros_like(P)
        blocks = [(P, Z, Z), (Z, P, Z), (Z, Z, P), (Pd, Z, Z), (Z, Pd, Z), (Z, Z, Pd)]
        return jnp.stack([jnp.concatenate(b, axis=1) for b in blocks], axis=1)

    def lift(self, turns) -> jax.Array:
        """(m + 1, 6): the jets' offset of psi = 2 pi turns s (zero for "clamped")."""
        if self.support == "clamped":
            return jnp.zeros((self.quad_nodes.shape[0], 6))
        rate = 2.0 * jnp.pi * turns
        zero = jnp.zeros_like(self.quad_nodes)
        return jnp.stack([zero, zero, rate * self.quad_nodes, zero, zero,
                          rate + zero], axis=1)

    def jets(self, x, turns=0.0) -> jax.Array:
        """(m + 1, 6): (v1, v2, psi, v1', v2', psi') at the fine nodes."""
        return jnp.einsum("jrm,m->jr", self.jet_matrix, x) + self.lift(turns)

    def integrate(self, f_quad):
        """int_0^1 f ds from values at the fine nodes."""
        return self.field.integrate(f_quad)


def framed_discretisation(n: int, support: str = "clamped", quad_degree: int | None = None,
                          layer_width: float | None = None) -> FramedDiscretisation:
    """Degree-n discretisation of the frame (n >= 4) for a support of ``FRAMED_SUPPORTS``;
    ``quad_degree`` (default 2n + 2) the fine Clenshaw-Curtis grid's degree; ``layer_width``
    gathers the grid about the middle (``jaxrod.discretise.grid_map``; None: the plain
    grid)."""
    if support not in FRAMED_SUPPORTS:
        raise ParameterError(f"support: one of {', '.join(FRAMED_SUPPORTS)} for a framed rod, "
                             f"got {support!r}")
    return FramedDiscretisation(field_discretisation(n, support, quad_degree, layer_width))


def twist_and_writhe(disc: FramedDiscretisation, x, turns=0.0) -> tuple[jax.Array, jax.Array]:
    """(Tw, Wr) of the state x: the twist Tw = (1 / 2 pi) int_0^1 u3 ds and the writhe by
    Fuller's formula relative to the straight rod along e3,

        Wr = (1 / 2 pi) int_0^1 (e3 x d3) . d3' / (1 + e3 . d3) ds,

    valid while d3 never points along -e3 (the chart's |v| < pi). Their sum is the linking
    number, which a rod clamped at both ends keeps at the far end's turns
    (Calugareanu-White-Fuller; checked in the tests)."""
    jets = disc.jets(x, turns)

    def densities(a):
        _, u = framed_jet(a)
        d3, dd3 = jax.jvp(lambda q: frame(q[0], q[1], q[2])[:, 2], (a[:3],), (a[3:],))
        return jnp.stack([u[2], jnp.dot(jnp.cross(jnp.array([0.0, 0.0, 1.0]), d3), dd3)
                          / (1.0 + d3[2])])

    tw, wr = (disc.integrate(c) / (2.0 * jnp.pi) for c in jax.vmap(densities)(jets).T)
    return tw, wr
