"""Chebyshev discretisation of the planar tangent angle theta(s).

In the plane (e1, e3) the director is d3 = sin(theta) e1 + cos(theta) e3. The unknowns are
the values of theta at the Chebyshev nodes s_0 = 0 < ... < s_n = 1 that the support leaves
free:

* ``clamped``: theta(0) = 0 is built in (node s_0 removed), n unknowns;
* ``pinned``:  theta(0) free, n + 1 unknowns.

The free-end condition theta'(1) = 0 (and theta'(0) = 0 when pinned) is *natural*: it is not
imposed but emerges from stationarity of the discrete energy, exactly as in the continuous
variational problem. This is why jaxrod takes residuals and Hessians by automatic
differentiation of the discrete energy (a Ritz-Galerkin method in the polynomials of degree n)
instead of collocating the Euler-Lagrange equation: natural boundary conditions need no
boundary rows, the Hessian is symmetric by construction, and its inertia is the stability of
the discrete equilibrium.

Integrals are evaluated by Clenshaw-Curtis quadrature on a finer Chebyshev grid of degree
m = 2n + 2 (default), onto which theta and theta' are interpolated. Quadratic functionals such
as int theta'^2 and int (1 - s) theta^2 are then integrated exactly, so the linearised
problem is an exact Rayleigh-Ritz method: its eigenvalues are upper bounds that converge
spectrally from above.
"""

from __future__ import annotations

import dataclasses
from functools import lru_cache

import jax
import jax.numpy as jnp
import numpy as np

from jaxrod import spectral
from jaxrod.discretise import grid_map
from jaxrod.params import ParameterError, check_degree

SUPPORTS = ("clamped", "pinned")


def check_support(support: str) -> str:
    if support not in SUPPORTS:
        raise ParameterError(f"support must be one of {SUPPORTS}, got {support!r}")
    return support


@jax.tree_util.register_dataclass
@dataclasses.dataclass(frozen=True)
class PlanarDiscretisation:
    """theta(s) by its free nodal values on the degree-n Chebyshev grid.

    Attributes:
      n, support: static; they fix the shapes of the compiled programs.
      nodes: the n + 1 nodes s_j.
      quad_nodes, quad_weights: the fine Clenshaw-Curtis rule on [0, 1].
      to_quad: (m + 1, n_free) interpolation of the free values to the fine nodes.
      to_quad_diff: (m + 1, n_free) the same for theta'.
      to_full: (n + 1, n_free) free values -> all nodal values (zero row at s = 0 if clamped).
      cumint: (n + 1, n + 1) cumulative integration on the degree-n grid.
    """

    n: int = dataclasses.field(metadata=dict(static=True))
    support: str = dataclasses.field(metadata=dict(static=True))
    nodes: jax.Array
    quad_nodes: jax.Array
    quad_weights: jax.Array
    to_quad: jax.Array
    to_quad_diff: jax.Array
    to_full: jax.Array
    cumint: jax.Array

    @property
    def size(self) -> int:
        """Number of unknowns."""
        return self.to_full.shape[1]

    @property
    def jet_matrix(self) -> jax.Array:
        """(m + 1, 2, size): rows taking the unknowns to the jet (theta, theta') at each
        quadrature node (``jaxrod.derivatives``)."""
        return jnp.stack([self.to_quad, self.to_quad_diff], axis=1)

    def full_values(self, theta: jax.Array) -> jax.Array:
        """All n + 1 nodal values from the free ones."""
        return self.to_full @ theta

    def at_quadrature(self, theta: jax.Array) -> tuple[jax.Array, jax.Array]:
        """(theta, theta') at the fine quadrature nodes."""
        return self.to_quad @ theta, self.to_quad_diff @ theta

    def integrate(self, f_quad: jax.Array) -> jax.Array:
        """int_0^1 f ds from values at the quadrature nodes."""
        return f_quad @ self.quad_weights

    def mass_matrix(self) -> jax.Array:
        """Gram matrix of the L2(0, 1) inner product in the free nodal basis."""
        return self.to_quad.T @ (self.quad_weights[:, None] * self.to_quad)

    def inner(self, u: jax.Array, v: jax.Array) -> jax.Array:
        """int_0^1 u v ds for free nodal vectors u, v."""
        return self.integrate((self.to_quad @ u) * (self.to_quad @ v))

    def mean(self, theta: jax.Array) -> jax.Array:
        """q = int_0^1 theta ds."""
        return self.integrate(self.to_quad @ theta)


@lru_cache(maxsize=64)
def _planar_arrays(n: int, support: str, quad_degree: int, layer_width: float | None = None):
    """The arrays on the Chebyshev grid in xi, mapped to s (``jaxrod.discretise.grid_map``;
    the identity without a layer width): d/ds = (d/dxi) / s', ds = s' dxi."""
    nodes = spectral.chebyshev_nodes(n)
    quad_nodes = spectral.chebyshev_nodes(quad_degree)
    interp = spectral.interpolation_matrix(n, quad_nodes)
    diff = spectral.differentiation_matrix(n)
    # the free nodes: all, all but s = 0 (clamped), all but both ends (clamped-clamped)
    free = slice(0 if support == "pinned" else 1, n if support == "clamped-clamped" else n + 1)
    quad_stretch = grid_map.stretch(quad_nodes, layer_width)
    return (
        grid_map.arclength(nodes, layer_width),
        grid_map.arclength(quad_nodes, layer_width),
        spectral.clenshaw_curtis_weights(quad_degree) * quad_stretch,
        interp[:, free],
        (interp @ diff)[:, free] / quad_stretch[:, None],
        np.eye(n + 1)[:, free],
        grid_map.cumulative_integration(n, layer_width),
    )


def planar_discretisation(n: int, support: str = "clamped",
                          quad_degree: int | None = None) -> PlanarDiscretisation:
    """The planar discretisation of degree ``n`` (n >= 4) for a ``support``.

    ``quad_degree`` (default 2n + 2) is the degree of the fine Clenshaw-Curtis grid.

    Paper: the planar ansatz d3 = sin(theta) e1 + cos(theta) e3 with the supports of eq.
    ``clamped_bc`` (clamped: theta(0) = 0).
    """
    check_support(support)
    return field_discretisation(n, support, quad_degree)


def field_discretisation(n: int, support: str, quad_degree: int | None = None,
                         layer_width: float | None = None) -> PlanarDiscretisation:
    """One scalar field on the degree-n grid with the ends that ``support`` holds at zero
    ("pinned": none, "clamped": s = 0, "clamped-clamped": both; the last for a framed
    rod's fields, ``jaxrod.discretise.framed``); ``layer_width``: the grid gathered about
    the middle (``jaxrod.discretise.grid_map``)."""
    n = check_degree(n)
    m = 2 * int(n) + 2 if quad_degree is None else int(quad_degree)
    arrays = _planar_arrays(int(n), support, m, grid_map.check_layer_width(layer_width))
    # device_put, not jnp.asarray: the latter compiles a copy program per new shape
    return PlanarDiscretisation(int(n), support, *(jax.device_put(a) for a in arrays))
