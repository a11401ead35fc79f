"""The moving rod's Lagrangian pieces, shared by the integrators: the loads at time t, the
kinetic energy T(q, v) and the Kelvin-Voigt dissipation's form.

T = 1/2 int_0^1 |dr/dt|^2 ds (lateral inertia, ``jaxrod.dynamics.modes``) on the quadrature
nodes; the Kelvin-Voigt dissipation 1/2 eta int |dkappa/dt|^2 ds with kappa = d3 x d3'
(``Scene.curvatures``); an input ``vary`` moving at a constant ``rate`` from ``start``.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from jaxrod.dynamics.modes import positions


def scene_at(path, start, rate, t):
    """The scene on ``path`` (``jaxrod.scenes.path``) at the value start + rate t of its
    parameter (a path that moves nothing: the scene as it is)."""
    return path.at(jnp.reshape(start + rate * t, (1,)))


def kinetic(scene, disc, q, v):
    """T(q, v) = 1/2 sum_j w_j |J_j(q) v|^2 (J = dr/dq)."""
    _, rdot = jax.jvp(lambda y: positions(scene, y, disc), (q,), (v,))
    return 0.5 * jnp.sum(disc.quad_weights[:, None] * rdot**2)


def curvature_rate_form(scene, disc, q, v):
    """K(q) v = J_k^T W J_k v: the Kelvin-Voigt dissipation 1/2 int |d kappa/dt|^2 ds as a
    form in the velocity (on the planar rod the bending energy's Hessian)."""
    _, kdot = jax.jvp(lambda y: scene.curvatures(y, disc), (q,), (v,))
    _, pull = jax.vjp(lambda y: scene.curvatures(y, disc), q)
    return pull(disc.quad_weights[:, None] * kdot)[0]
