"""Chebyshev discretisation of the director d3(s) on the unit sphere (3D rods).

Chart: the exponential map of the sphere at e3,

    d3(v) = cos|v| e3 + (sin|v| / |v|) (v1 e1 + v2 e2),      v = (v1, v2),

with v1, v2 each discretised like the planar angle (``PlanarDiscretisation``: free nodal
values on the Chebyshev grid, the support built in). Why this chart: it is smooth wherever
the director is not pointing straight down (|v| < pi), which holds on every branch computed
here (the rods stand up against gravity; the largest tilt on the magnet branches is below
90 degrees), it has no pole at the upright state (unlike polar angles, singular at e3), and on
the plane v2 = 0 it is exactly the planar parametrisation, d3 = sin(v1) e1 + cos(v1) e3 with
v1 = theta, so planar equilibria are 3D states without conversion. The unit-length constraint
holds identically; at an equilibrium the Hessian in the chart is the constrained second
variation (the Lagrange-multiplier term of the paper's formulas is produced by the chart's
curvature), evaluated on the tangent variation eta = (d d3 / dv) dv. At v2 = 0 the
out-of-plane chart direction maps to eta = (sin v1 / v1) dv2 e2, i.e. b = sinc(theta) dv2.

Twist decouples (paper) and is not discretised.
"""

from __future__ import annotations

import dataclasses
import math

import jax
import jax.numpy as jnp

from jaxrod import spectral
from jaxrod.discretise.planar import PlanarDiscretisation, planar_discretisation

#: Below this |v|^2 the chart functions use their Taylor series (7 terms, error < 1e-24);
#: above it the closed forms, whose derivatives are accurate there.
_SERIES_BELOW = 1e-2


def _series_or(x, coefficients, closed):
    small = x < _SERIES_BELOW
    xs = jnp.where(small, 1.0, x)  # keeps the closed form's derivatives finite at x = 0
    series = sum(c * x**k for k, c in enumerate(coefficients))
    return jnp.where(small, series, closed(xs))


_COS_SQRT = [(-1) ** k / math.factorial(2 * k) for k in range(7)]
_SINC_SQRT = [(-1) ** k / math.factorial(2 * k + 1) for k in range(7)]


def _cos_sqrt(x):
    """cos(sqrt(x)), analytic at x = 0."""
    return _series_or(x, _COS_SQRT, lambda y: jnp.cos(jnp.sqrt(y)))


def _sinc_sqrt(x):
    """sin(sqrt(x)) / sqrt(x), analytic at x = 0."""
    return _series_or(x, _SINC_SQRT, lambda y: jnp.sin(jnp.sqrt(y)) / jnp.sqrt(y))


def director(v1, v2):
    """d3 = (sinc|v| v1, sinc|v| v2, cos|v|) (arrays of any shape; last axis = component)."""
    r2 = v1 * v1 + v2 * v2
    c = _sinc_sqrt(r2)
    return jnp.stack([c * v1, c * v2, _cos_sqrt(r2)], axis=-1)


@jax.tree_util.register_dataclass
@dataclasses.dataclass(frozen=True)
class DirectorDiscretisation:
    """d3(s) by the nodal values of v1 and v2, stacked as x = [v1; v2] (2 x planar size)."""

    planar: PlanarDiscretisation

    @property
    def size(self) -> int:
        return 2 * self.planar.size

    @property
    def support(self) -> str:
        return self.planar.support

    @property
    def quad_weights(self):
        return self.planar.quad_weights

    @property
    def quad_nodes(self):
        return self.planar.quad_nodes

    @property
    def jet_matrix(self) -> jax.Array:
        """(m + 1, 4, size): rows taking x = [v1; v2] to the jet (v1, v2, v1', v2') at each
        quadrature node (``jaxrod.derivatives``)."""
        P, Pd = self.planar.to_quad, self.planar.to_quad_diff
        Z = jnp.zeros_like(P)
        rows = [jnp.concatenate(pair, axis=1) for pair in ((P, Z), (Z, P), (Pd, Z), (Z, Pd))]
        return jnp.stack(rows, axis=1)

    def split(self, x):
        m = self.planar.size
        return x[:m], x[m:]

    def at_quadrature(self, x):
        """(d3, d3') at the quadrature nodes, each (m + 1, 3)."""
        v1, v2 = self.split(x)
        V = jnp.stack([self.planar.to_quad @ v1, self.planar.to_quad @ v2], axis=-1)
        dV = jnp.stack([self.planar.to_quad_diff @ v1, self.planar.to_quad_diff @ v2], axis=-1)
        d3, dd3 = jax.jvp(lambda W: director(W[:, 0], W[:, 1]), (V,), (dV,))
        return d3, dd3

    def integrate(self, f_quad):
        return self.planar.integrate(f_quad)

    def inner(self, x, y):
        """L2(0, 1) inner product of two chart fields, int (x1 y1 + x2 y2) ds."""
        (x1, x2), (y1, y2) = self.split(x), self.split(y)
        return self.planar.inner(x1, y1) + self.planar.inner(x2, y2)

    def centreline(self, x, s) -> jax.Array:
        """r(s) = int_0^s d3 (rod lengths) at the points s in [0, 1], shape (len(s), 3), for
        plots: d3 at the Chebyshev nodes, integrated and interpolated spectrally."""
        v1, v2 = (self.planar.full_values(v) for v in self.split(x))
        r_nodes = self.planar.cumint @ director(v1, v2)
        return jnp.asarray(spectral.interpolation_matrix(self.planar.n, s)) @ r_nodes

    def from_planar(self, theta):
        """The 3D state of a planar one (v1 = theta, v2 = 0)."""
        return jnp.concatenate([theta, jnp.zeros_like(theta)])


def director_jet(a):
    """(d3, d3') at one node from its jet a = (v1, v2, v1', v2')."""
    return jax.jvp(lambda v: director(v[0], v[1]), (a[:2],), (a[2:],))


def director_discretisation(n: int, support: str = "clamped") -> DirectorDiscretisation:
    """Degree-n discretisation of d3 for a support ("clamped": d3(0) = e3; "pinned": free).

    Paper: the director d3 on the unit sphere of eq. ``nondimensional_master_energy``
    (section ``sec:model``), clamped as in eq. ``clamped_bc``.
    """
    return DirectorDiscretisation(planar_discretisation(n, support))
