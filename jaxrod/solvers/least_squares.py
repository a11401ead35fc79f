"""Nonlinear least squares over a subset of the parameters, in one compiled loop.

Minimises 0.5 |r(p)|^2 over the entries of p marked ``free`` (a boolean array: which
entries are free is data, not program structure, so one compiled program serves every
subset). The direction is optax's L-BFGS (``optax.scale_by_lbfgs``) with a backtracking
line search on the sufficient-decrease (Armijo) condition, in scaled coordinates

    p = p0 + P u,   P = (J0^T J0 + F)^(-1/2),   F = diag(1 - free),

from the first Jacobian J0 (columns of fixed entries zeroed), so the first direction is the
Gauss-Newton step and u is in units of the Gauss-Newton standard deviations. Convergence:
the gradient J^T r vanishes (|J^T r|_inf <= gtol), or its scaled form g_u = P^T J^T r (the
Gauss-Newton step, in standard deviations) is below ``utol`` = 1e-10, or no decrease is
visible along a step of 1e-7 standard deviations. Near the minimum the loss itself stops
resolving the distance (a step of d standard deviations changes it by d^2 / 2, lost in its
round-off ~1e4 eps |r|^2 once d ~ 1e-6 sqrt(|r|^2)): there a step that leaves the loss
within its round-off is accepted when it lowers the gradient, so that the gradient, which
is still resolved, brings the point to within ``utol`` of the minimiser.

``evaluate(p, aux) -> (r, J, aux_new, ok)`` gives the residuals and their Jacobian and may
carry state ``aux`` from the last accepted point (fold states for a warm start); a trial
point with ``ok`` False, or non-finite residuals, is rejected by the line search.
``forward_mode(residuals)`` builds ``evaluate`` from ``residuals(p, aux) -> (r, aux_new,
ok)`` by forward-mode differentiation (one tangent per parameter); a model with fewer
inner inputs than parameters can supply its own chain rule instead.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import optax

#: Round-off of the loss, in units of its value's eps: changes below it are not decreases.
#: A loss of inner solves (fold values to Newton's 1e-12) is noisy at ~1e3-1e4 eps; within
#: this floor, which a Gauss-Newton step reaches only within ~1e-6 standard deviations of
#: the minimiser, the gradient decides.
FLOOR_ULPS = 16384.0


class LeastSquaresResult(NamedTuple):
    """The accepted point p, its residuals r and Jacobian J (fixed columns zeroed), the
    carried state, ok (the model evaluated there), the iterations, |J^T r|_inf and
    converged (the gradient vanished or the loss reached its round-off floor)."""

    p: jax.Array
    r: jax.Array
    J: jax.Array
    aux: Any
    ok: jax.Array
    iterations: jax.Array
    grad_norm: jax.Array
    converged: jax.Array

    def covariance(self, free) -> jax.Array:
        """The Gauss-Newton covariance (J^T J)^-1 of the free entries (zero elsewhere)."""
        fixed = jnp.diag(1.0 - jnp.asarray(free, self.J.dtype))
        return jnp.linalg.inv(self.J.T @ self.J + fixed) - fixed


class _Search(NamedTuple):
    u: jax.Array
    aux: Any
    value: jax.Array
    grad_u: jax.Array
    r: jax.Array
    J: jax.Array
    ok: jax.Array
    opt_state: Any
    direction: jax.Array
    t: jax.Array
    P: jax.Array
    k: jax.Array
    evals: jax.Array
    converged: jax.Array
    done: jax.Array


def _inverse_sqrt(A):
    lam, V = jnp.linalg.eigh(A)
    return (V / jnp.sqrt(jnp.maximum(lam, 1e-12 * jnp.max(lam) + 1e-300))) @ V.T


def forward_mode(residuals: Callable) -> Callable:
    """``evaluate`` for ``least_squares_run`` from ``residuals(p, aux) -> (r, aux, ok)``."""

    def evaluate(p, aux):
        def at(q):
            r, aux_new, ok = residuals(q, aux)
            return r, (r, aux_new, ok)

        J, (r, aux_new, ok) = jax.jacfwd(at, has_aux=True)(p)
        return r, J, aux_new, ok

    return evaluate


def least_squares_run(evaluate: Callable, p0, aux0, free, n_residuals: int,
                      start_ok=True, max_iter: int = 40,
                      gtol: float = 1e-9, utol: float = 1e-10) -> LeastSquaresResult:
    """Minimise 0.5 |r|^2, (r, J, aux, ok) = evaluate(p, aux), over the ``free`` entries of
    p from p0 (module docstring). ``n_residuals`` is the length of r; ``start_ok`` False
    (the carried state could not be built) returns at once, not converged. jit/vmap
    friendly."""
    p0 = jnp.asarray(p0)
    columns = jnp.asarray(free, p0.dtype)
    fixed = jnp.diag(1.0 - columns)

    opt = optax.scale_by_lbfgs(scale_init_precond=False)  # in u: unit initial preconditioner

    def step(s: _Search) -> _Search:
        first = s.evals == 0
        u = s.u + s.t * s.direction
        p = p0 + s.P @ u
        r, J, aux, ok = evaluate(p, s.aux)
        J = J * columns
        good = ok & jnp.all(jnp.isfinite(r)) & jnp.all(jnp.isfinite(J))
        value = jnp.where(good, 0.5 * jnp.dot(r, r), jnp.inf)
        P = jnp.where(first, _inverse_sqrt(J.T @ J + fixed), s.P)
        grad_u = P.T @ (J.T @ r)
        armijo = value <= s.value + 1e-4 * s.t * jnp.dot(s.grad_u, s.direction)
        # at the loss's round-off floor a decrease cannot be seen: where the Gauss-Newton
        # decrease 0.5 |grad_u|^2 (unit Hessian in u) is below the loss's round-off and the
        # loss did not change beyond it, a smaller gradient decides
        floor = FLOOR_ULPS * jnp.finfo(r.dtype).eps * jnp.maximum(s.value, value)
        at_floor = (jnp.abs(value - s.value) <= floor) \
            & (0.5 * jnp.dot(s.grad_u, s.grad_u) <= floor) \
            & (jnp.max(jnp.abs(grad_u)) < jnp.max(jnp.abs(s.grad_u)))
        accept = good & (first | armijo | at_floor)
        update, opt_state = opt.update(grad_u, s.opt_state, u)
        direction = jnp.where(jnp.dot(update, grad_u) > 0.0, -update, -grad_u)
        pick = lambda new, old: jax.tree_util.tree_map(
            lambda a, b: jnp.where(accept, a, b), new, old)
        u, aux, value, grad_u, r, J, ok, opt_state, direction = pick(
            (u, aux, value, grad_u, r, J, ok, opt_state, direction),
            (s.u, s.aux, s.value, s.grad_u, s.r, s.J, s.ok, s.opt_state, s.direction))
        k = s.k + (accept & ~first)
        at_round_off = ~accept & ~first & good & (s.t * jnp.max(jnp.abs(s.direction)) <= 1e-7)
        converged = (accept & ((jnp.max(jnp.abs(J.T @ r)) <= gtol)
                               | (jnp.max(jnp.abs(grad_u)) <= utol))) | at_round_off
        stalled = ~accept & (s.t < 1e-10)
        done = converged | stalled | (first & ~good) | (k >= max_iter) \
            | (s.evals + 1 >= 4 * max_iter)
        t = jnp.where(accept, 1.0, 0.5 * s.t)
        return _Search(u, aux, value, grad_u, r, J, ok, opt_state, direction, t, P, k,
                       s.evals + 1, converged, done)

    m = p0.shape[0]
    zero = jnp.zeros(m, p0.dtype)
    init = _Search(zero, aux0, jnp.asarray(jnp.inf, p0.dtype), zero,
                   jnp.zeros(n_residuals, p0.dtype), jnp.zeros((n_residuals, m), p0.dtype),
                   jnp.asarray(False), opt.init(zero), zero, jnp.zeros((), p0.dtype),
                   jnp.eye(m, dtype=p0.dtype), jnp.asarray(0), jnp.asarray(0),
                   jnp.asarray(False), ~jnp.asarray(start_ok))
    s = jax.lax.while_loop(lambda s: ~s.done, step, init)
    return LeastSquaresResult(p0 + s.P @ s.u, s.r, s.J, s.aux, s.ok, s.k,
                              jnp.max(jnp.abs(s.J.T @ s.r)), s.converged)
