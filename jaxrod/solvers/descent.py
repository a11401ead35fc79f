"""Energy descent to a local minimum: what a rod does when its equilibrium disappears.

At a fold the followed equilibrium ceases to exist and the rod snaps, dynamically, to
another stable state. Quasi-statically that state is the local minimum reached by descending
the energy from the last configuration. ``descend`` takes modified Newton steps

    (H + mu I) d = -g,    mu = max(0, shift - lambda_min(H)),

(H the Hessian, so H + mu I is positive definite and d a descent direction) with Armijo
backtracking on the energy, in one ``lax.while_loop``, until |g| <= tol.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp

from jaxrod.derivatives import EnergyModel


class DescentResult(NamedTuple):
    x: jax.Array
    converged: jax.Array
    gradient_norm: jax.Array
    iterations: jax.Array


def descend(energy: Callable[[jax.Array, Any], jax.Array] | EnergyModel, x0: jax.Array,
            args: Any = None, *, tol: float = 1e-12, max_steps: int = 500, shift: float = 1e-3,
            lam=0.0) -> DescentResult:
    """Descend ``energy(x, args)`` from x0 to a point with |grad|_inf <= tol.

    ``energy`` may also be an ``EnergyModel`` (assembled derivatives), evaluated at ``lam``.
    """
    if isinstance(energy, EnergyModel):
        model = energy
        energy = lambda x, a: model.energy(x, lam, a)
        grad = lambda x, a: model.gradient(x, lam, a)
        hess = lambda x, a: model.hessian(x, lam, a)
    else:
        grad = jax.grad(energy)
        hess = jax.hessian(energy)

    def step(state):
        x, _, k = state
        g = grad(x, args)
        H = hess(x, args)
        lam_min = jnp.linalg.eigvalsh(0.5 * (H + H.T))[0]
        mu = jnp.maximum(0.0, shift * (1.0 + jnp.abs(lam_min)) - lam_min)
        d = jnp.linalg.solve(H + mu * jnp.eye(x.shape[0]), -g)
        e0 = energy(x, args)
        g0 = jnp.max(jnp.abs(g))
        slope = jnp.dot(g, d)

        def trial(t):
            x1 = x + t * d
            return t, energy(x1, args), jnp.max(jnp.abs(grad(x1, args)))

        def bad(c):
            t, e, gn = c
            armijo = e <= e0 + 1e-4 * t * slope
            # Near the minimum the energy decrease (~|g|^2) drowns in round-off of E; there a
            # full Newton step on a positive definite Hessian is accepted if |g| drops.
            quadratic = (mu == 0.0) & (t == 1.0) & (gn < 0.5 * g0)
            return ~(armijo | quadratic) & (t > 1e-12)

        t, _, gnorm = jax.lax.while_loop(bad, lambda c: trial(0.5 * c[0]), trial(1.0))
        return x + t * d, gnorm, k + 1

    def go_on(state):
        _, gnorm, k = state
        return (gnorm > tol) & (k < max_steps) & jnp.isfinite(gnorm)

    g0 = jnp.max(jnp.abs(grad(x0, args)))
    x, gnorm, k = jax.lax.while_loop(go_on, step, (x0, g0, jnp.asarray(0)))
    return DescentResult(x, gnorm <= tol, gnorm, k)
