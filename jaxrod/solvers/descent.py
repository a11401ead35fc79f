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

from jaxrod.derivatives import Autodiff, EnergyModel


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
    One ``lax.while_loop`` whose every pass tries one point x + t d (the first x0 itself): the
    energy, gradient and Hessian are evaluated in one place (the program holds one copy of
    them). An accepted point gives the next direction; a rejected one halves t (Armijo
    backtracking).
    """
    model = energy if isinstance(energy, EnergyModel) else Autodiff(
        lambda x, _, a: energy(x, a))

    def evaluate(x):
        g, H = model.gradient_and_hessian(x, lam, args)
        lam_min = jnp.linalg.eigvalsh(0.5 * (H + H.T))[0]
        mu = jnp.maximum(0.0, shift * (1.0 + jnp.abs(lam_min)) - lam_min)
        d = jnp.linalg.solve(H + mu * jnp.eye(x.shape[0]), -g)
        return model.energy(x, lam, args), jnp.max(jnp.abs(g)), d, mu, jnp.dot(g, d)

    def step(state):
        x, e, gnorm, d, mu, slope, t, k = state
        x1 = x + t * d
        e1, gn1, d1, mu1, slope1 = evaluate(x1)
        armijo = e1 <= e + 1e-4 * t * slope
        # Near the minimum the energy decrease (~|g|^2) drowns in round-off of E; there a full
        # Newton step on a positive definite Hessian is accepted if |g| drops.
        quadratic = (mu == 0.0) & (t == 1.0) & (gn1 < 0.5 * gnorm)
        accept = armijo | quadratic | (t <= 1e-12)
        new = (x1, e1, gn1, d1, mu1, slope1, jnp.ones_like(t), k + 1)
        old = (x, e, gnorm, d, mu, slope, 0.5 * t, k)
        return jax.tree_util.tree_map(lambda u, v: jnp.where(accept, u, v), new, old)

    def go_on(state):
        gnorm, k = state[2], state[7]
        return (k < 0) | ((gnorm > tol) & (k < max_steps) & jnp.isfinite(gnorm))

    # the first pass evaluates x0 itself (t = 0, accepted): one copy of the evaluation
    zero = jnp.zeros((), x0.dtype)
    start = (x0, jnp.asarray(jnp.inf, x0.dtype), zero, jnp.zeros_like(x0), zero, zero, zero,
             jnp.asarray(-1))
    x, _, gnorm, *_, k = jax.lax.while_loop(go_on, step, start)
    return DescentResult(x, gnorm <= tol, gnorm, k)
