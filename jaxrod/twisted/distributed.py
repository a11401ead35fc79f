"""Loads that act on the positions along a rod that carries its frame: a magnet's
non-uniform field on a remanence programmed at an angle to the tangent.

Such a load is no density of the local jet and no potential of the far end: its energy is a
functional of the positions r(s) = int_0^s d3 and of the frames F(s) = (d1, d2, d3) at the
quadrature nodes s_j (weights w_j),

    E_d = sum over terms  Q_t(r, F, s, w)        (``framed_distributed`` of each term),

with r at the nodes by the quadrature grid's cumulative integration (mapped like the
fields' grid: ``jaxrod.discretise.grid_map``). Its data (``QuadPositions``) travel among a
program's loads under ``POSITIONS_KEY``; its gradient and Hessian in the fields are taken by
autodiff of E_d as a whole (``jaxrod.twisted.equations``).
"""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp

from jaxrod.discretise import grid_map
from jaxrod.discretise.framed import FramedDiscretisation, frame

#: The key of the positions' data among a program's loads (no scene term's name).
POSITIONS_KEY = "positions along the rod"


@jax.tree_util.register_dataclass
@dataclasses.dataclass(frozen=True)
class QuadPositions:
    """``cumint``: int_0^{s_j} on the fields' quadrature grid (its nodes s_j). Carried among
    a program's loads; no density and no end term of its own."""

    cumint: jax.Array

    term_name = "positions"
    density = None
    endpoint = None
    framed = None


def acts_on_positions(t) -> bool:
    """Whether the load term ``t`` acts on the positions along a framed rod."""
    return getattr(t, "framed_distributed", None) is not None


def quad_positions(disc: FramedDiscretisation, layer_width: float | None) -> QuadPositions:
    """The positions' data on ``disc``'s quadrature grid (gathered by ``layer_width``)."""
    degree = int(disc.quad_nodes.shape[0]) - 1
    cumint = grid_map.cumulative_integration(degree, layer_width)
    return QuadPositions(jax.device_put(cumint))


def distributed_energy(x, turns, disc: FramedDiscretisation, inputs, loads: dict
                       ) -> jax.Array:
    """E_d (module docstring) times the load scale inputs[4]; 0 without such loads."""
    terms = [t for t in loads.values() if acts_on_positions(t)]
    if not terms:
        return jnp.zeros((), x.dtype)
    F = jax.vmap(lambda a: frame(a[0], a[1], a[2]))(disc.jets(x, turns))
    r = loads[POSITIONS_KEY].cumint @ F[:, :, 2]
    s, w = disc.quad_nodes, disc.field.quad_weights
    return inputs[4] * sum(t.framed_distributed(r, F, s, w) for t in terms)
