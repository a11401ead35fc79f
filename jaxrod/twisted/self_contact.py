"""Self-contact of a twisted rod: its strands may not come closer than its diameter.

A rod of diameter h (in rod lengths) that writhes into a loop meets itself; a centreline
model without contact passes through itself there, changing its linking number by 2. The
contact is a penalty, a repulsion between every two points of the centreline far apart
along the rod,

    E_c = (kappa / 2) int int_{|s - s'| > l} (1 - |r(s) - r(s')| / h)_+^3 ds ds',

l = ``EXCLUSION`` h (nearby points of one strand are never in contact: a bend of radius
above h / 2 keeps the chord over l above h), kappa the stiffness (in B1 / L per L^2). The
penalty is twice continuously differentiable, so Newton and the count of unstable
directions see a continuous Hessian; the hard rod is its limit kappa -> infinity, the strands'
overlap falling like kappa^(-1/3) (check it by raising kappa: ``TwistedRod.contact_stiffness``).

The double integral is evaluated on its own grid (``CONTACT_DEGREE_FACTOR`` times the
fields' degree, mapped like the fields' grid: a contact zone is narrower than the fields'
features), from the centreline r = int_0^s d3 there: d3 depends on the bending angles v
only, interpolated exactly from the fields' nodal values. The Hessian is assembled from the
pairs' 3 x 3 blocks (``contact_terms``), the same numbers as autodiff of ``contact_energy``
(checked in the tests) without its cost.
"""

from __future__ import annotations

import dataclasses
from functools import lru_cache

import jax
import jax.numpy as jnp
import numpy as np

from jaxrod import spectral
from jaxrod.discretise import grid_map
from jaxrod.discretise.director import director

#: Pairs closer along the rod than this many diameters are never in contact.
EXCLUSION = 3.0

#: The contact grid's degree, in units of the fields' degree.
CONTACT_DEGREE_FACTOR = 2


@jax.tree_util.register_dataclass
@dataclasses.dataclass(frozen=True)
class SelfContact:
    """The contact penalty's data (module docstring): ``diameter`` h and ``stiffness``
    kappa; on the contact grid, ``interp`` (the fields' free values of v1 or v2 to the
    grid's nodes), ``cumint`` (cumulative integration there) and ``pair_weights``
    (w_i w_j where |s_i - s_j| > l, else 0). Carried among a program's loads, it acts on
    the positions along the rod, not as a density or an end term."""

    diameter: jax.Array
    stiffness: jax.Array
    interp: jax.Array
    cumint: jax.Array
    pair_weights: jax.Array

    term_name = "self_contact"
    density = None
    endpoint = None
    framed = None


@lru_cache(maxsize=16)
def _contact_arrays(n: int, layer_width: float | None, diameter: float, degree: int):
    xi = spectral.chebyshev_nodes(degree)
    s = grid_map.arclength(xi, layer_width)
    stretch = grid_map.stretch(xi, layer_width)
    weights = spectral.clenshaw_curtis_weights(degree) * stretch
    interp = spectral.interpolation_matrix(n, xi)[:, 1:n]  # both ends held: v = 0 there
    cumint = grid_map.cumulative_integration(degree, layer_width)
    apart = np.abs(s[:, None] - s[None, :]) > EXCLUSION * diameter
    return interp, cumint, np.outer(weights, weights) * apart


def self_contact(n: int, layer_width: float | None, diameter: float, stiffness: float,
                 degree: int | None = None) -> SelfContact:
    """The penalty's data for a clamped-clamped rod of degree ``n`` on the grid of
    ``layer_width`` (``jaxrod.discretise.grid_map``); ``degree``: the contact grid's
    (default ``CONTACT_DEGREE_FACTOR`` n)."""
    degree = CONTACT_DEGREE_FACTOR * int(n) if degree is None else int(degree)
    interp, cumint, pairs = _contact_arrays(int(n), layer_width, float(diameter), degree)
    return SelfContact(jnp.asarray(float(diameter)), jnp.asarray(float(stiffness)),
                       *(jax.device_put(a) for a in (interp, cumint, pairs)))


def _bending_angles(x, contact: SelfContact) -> jax.Array:
    """(M + 1, 2): v1, v2 at the contact grid's nodes."""
    free = contact.interp.shape[1]
    return contact.interp @ jnp.stack([x[:free], x[free:2 * free]], axis=1)


def _tangents(V) -> jax.Array:
    return jax.vmap(lambda v: director(v[0], v[1]))(V)


def _pair_potential(delta, h, kappa):
    """kappa (1 - |delta| / h)_+^3 / 2 (the 1/2 of the double count)."""
    d = jnp.sqrt(jnp.dot(delta, delta))
    return 0.5 * kappa * jnp.maximum(1.0 - d / h, 0.0) ** 3


def _separations(r, contact: SelfContact):
    """r_i - r_j for every pair, those that never touch replaced by a vector of length 2h
    (their potential and its derivatives vanish; no 0 / 0 at i = j)."""
    delta = r[:, None, :] - r[None, :, :]
    far = jnp.zeros(3).at[0].set(2.0 * contact.diameter)
    return jnp.where((contact.pair_weights > 0)[..., None], delta, far)


def _energy_of_positions(r, contact: SelfContact):
    phi = jax.vmap(jax.vmap(_pair_potential, in_axes=(0, None, None)),
                   in_axes=(0, None, None))(_separations(r, contact), contact.diameter,
                                            contact.stiffness)
    return jnp.sum(contact.pair_weights * phi)


def contact_energy(x, contact: SelfContact) -> jax.Array:
    """E_c(x) (module docstring)."""
    r = contact.cumint @ _tangents(_bending_angles(x, contact))
    return _energy_of_positions(r, contact)


def contact_terms(x, contact: SelfContact, size: int) -> tuple[jax.Array, jax.Array]:
    """(dE_c/dx, d^2E_c/dx^2), x the framed rod's unknowns (``size`` of them: v1, v2, psi).

    With r = C d3(V), V = P v: the Hessian is J^T K J + sum_k P_k^T (h_k . d3_VV(V_k)) P_k,
    J = dr/dv, K the pairs' Hessian in the positions (blocks A_ij = grad^2 phi(r_i - r_j):
    -w_ij A_ij off the diagonal, sum_j w_ij A_ij on it) and h = C^T dE_c/dr."""
    V = _bending_angles(x, contact)
    free = contact.interp.shape[1]
    nodes = V.shape[0]
    d3, D = jax.vmap(lambda v: (director(v[0], v[1]), jax.jacfwd(
        lambda u: director(u[0], u[1]))(v)))(V)  # (M+1, 3), (M+1, 3, 2)
    T = jax.vmap(jax.hessian(lambda v: director(v[0], v[1])))(V)  # (M+1, 3, 2, 2)
    C, P = contact.cumint, contact.interp
    r = C @ d3
    g_r = jax.grad(_energy_of_positions)(r, contact)
    A = jax.vmap(jax.vmap(jax.hessian(_pair_potential), in_axes=(0, None, None)),
                 in_axes=(0, None, None))(_separations(r, contact), contact.diameter,
                                          contact.stiffness)
    A = 2.0 * contact.pair_weights[..., None, None] * A  # d^2 / dr_i dr_j of both halves
    K = -A + jnp.einsum("ij,jab->ijab", jnp.eye(nodes), A.sum(axis=1))
    K = K.transpose(0, 2, 1, 3).reshape(3 * nodes, 3 * nodes)
    J = jnp.einsum("ik,kab,kf->iabf", C, D, P).reshape(3 * nodes, 2 * free)
    h = C.T @ g_r
    local = jnp.einsum("ka,kabc->kbc", h, T)
    H_v = J.T @ K @ J + jnp.einsum("kf,kbc,kg->bfcg", P, local, P).reshape(2 * free,
                                                                             2 * free)
    g_v = jnp.einsum("ka,kab,kf->bf", h, D, P).reshape(2 * free)
    grad = jnp.zeros(size, x.dtype).at[:2 * free].set(g_v)
    hess = jnp.zeros((size, size), x.dtype).at[:2 * free, :2 * free].set(H_v)
    return grad, hess


def self_distance(x, contact: SelfContact) -> jax.Array:
    """The least distance between two points of the centreline that may touch (farther
    apart along the rod than l), on the contact grid: above the diameter, no contact."""
    r = contact.cumint @ _tangents(_bending_angles(x, contact))
    delta = r[:, None, :] - r[None, :, :]
    d2 = jnp.where(contact.pair_weights > 0, jnp.sum(delta * delta, axis=-1), jnp.inf)
    return jnp.sqrt(jnp.min(d2))
