"""Damped Newton's method for F(x, args) = 0, as one ``lax.while_loop``.

Each step solves J(x_k) dx = -F(x_k) with the exact Jacobian J = dF/dx from forward-mode
autodiff and a dense LU solve, then backtracks x_{k+1} = x_k + t dx, t = 1, 1/2, 1/4, ...,
until ||F(x_{k+1})|| < (1 - t/4) ||F(x_k)|| (Armijo on the residual norm). It stops when

    ||F(x_k)||_inf <= tol                                  (converged), or
    a full step had ||dx||_inf <= xtol (1 + ||x||_inf)     (converged: quadratic phase), or
    no step length reduces ||F|| and ||dx||_inf <= stall_xtol (1 + ||x||_inf)
                                                           (converged: round-off floor), or
    status becomes MAX_STEPS, NONFINITE or LINE_SEARCH_FAILED.

The result always carries ``converged``, the final ``residual_norm``, the number of
``iterations`` and a ``status`` code (see ``STATUS_MESSAGES``); a failure is never silent.
Everything is jit-, vmap- and scan-compatible: the function is pure, and the loop bounds
are static.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp

CONVERGED, MAX_STEPS, NONFINITE, LINE_SEARCH_FAILED = 0, 1, 2, 3
STATUS_MESSAGES = {
    CONVERGED: "converged",
    MAX_STEPS: "maximum number of Newton steps reached without convergence; the initial guess "
    "may be far from a solution, or the solution may sit at a fold (singular Jacobian)",
    NONFINITE: "the residual or the Newton step became NaN/inf; the Jacobian is probably "
    "singular (a fold or bifurcation point) or the parameters are out of range",
    LINE_SEARCH_FAILED: "no step length reduced the residual; the iterate is stuck at a local "
    "minimum of |F| or the Jacobian is inaccurate",
}


class NewtonResult(NamedTuple):
    """Outcome of ``newton``: the iterate and how it was obtained."""

    x: jax.Array
    converged: jax.Array
    residual_norm: jax.Array
    iterations: jax.Array
    status: jax.Array

    def message(self) -> str:
        """Human-readable status (host side)."""
        return STATUS_MESSAGES[int(self.status)]


class _State(NamedTuple):
    x: jax.Array
    fnorm: jax.Array
    k: jax.Array
    done: jax.Array
    status: jax.Array


def _norm(v):
    return jnp.max(jnp.abs(v))


def newton(residual: Callable[[jax.Array, Any], jax.Array], x0: jax.Array, args: Any = None, *,
           tol: float = 1e-12, xtol: float = 1e-10, max_steps: int = 50,
           max_halvings: int = 12, stall_xtol: float = 1e-7) -> NewtonResult:
    """Solve ``residual(x, args) = 0`` from ``x0`` (square system, x a 1-D array).

    Args:
      residual: pure function; its Jacobian in x is taken by ``jax.jacfwd``.
      x0: initial guess.
      args: PyTree of parameters passed through unchanged.
      tol: absolute tolerance on the max-norm of the residual.
      xtol: relative tolerance on the max-norm of a full Newton step; the step is applied,
        so near a regular root (quadratic convergence) the result is accurate to ~xtol^2.
      max_steps, max_halvings: static iteration budgets.
      stall_xtol: a step this small (relative) that cannot reduce |F| means |F| is at its
        round-off floor: accepted as converged.
    """
    x0 = jnp.asarray(x0)
    if not jnp.issubdtype(x0.dtype, jnp.floating):
        x0 = x0.astype(jnp.float64)  # float32 input stays float32 (tolerances are the caller's)
    f = lambda x: residual(x, args)
    jac = jax.jacfwd(f)

    def step(state: _State) -> _State:
        fx = f(state.x)
        dx = jnp.linalg.solve(jac(state.x), -fx)

        def try_shorter(carry):
            t, _, _ = carry
            t = 0.5 * t
            return t, state.x + t * dx, _norm(f(state.x + t * dx))

        def too_long(carry):
            t, _, fn = carry
            bad = ~(fn < (1.0 - 0.25 * t) * state.fnorm)
            return bad & (t > 0.5**max_halvings)

        x1 = state.x + dx
        t, x1, fn1 = jax.lax.while_loop(too_long, try_shorter, (1.0, x1, _norm(f(x1))))
        finite = jnp.all(jnp.isfinite(x1)) & jnp.isfinite(fn1)
        accepted = fn1 < (1.0 - 0.25 * t) * state.fnorm
        small_step = (t == 1.0) & (_norm(dx) <= xtol * (1.0 + _norm(state.x)))
        # A full step that is already at round-off level counts as converged even if the
        # residual did not decrease (it is at its floor).
        x_new = jnp.where(accepted | small_step, x1, state.x)
        fn_new = jnp.where(accepted | small_step, fn1, state.fnorm)
        # No step length reduces |F| although the Newton step is tiny: the residual sits at
        # its round-off floor (|F| cannot be evaluated more accurately), so x is as accurate
        # as the arithmetic allows.
        at_floor = ~accepted & (_norm(dx) <= stall_xtol * (1.0 + _norm(state.x)))
        converged = (fn_new <= tol) | small_step | at_floor
        status = jnp.where(~finite, NONFINITE,
                           jnp.where(converged, CONVERGED,
                                     jnp.where(accepted, MAX_STEPS, LINE_SEARCH_FAILED)))
        done = converged | ~finite | ~(accepted | small_step)
        return _State(x_new, fn_new, state.k + 1, done, status)

    def keep_going(state: _State):
        return (~state.done) & (state.k < max_steps)

    fn0 = _norm(f(x0))
    init = _State(x0, fn0, jnp.asarray(0), fn0 <= tol,
                  jnp.where(jnp.isfinite(fn0), jnp.where(fn0 <= tol, CONVERGED, MAX_STEPS),
                            NONFINITE))
    init = init._replace(done=init.done | ~jnp.isfinite(fn0))
    final = jax.lax.while_loop(keep_going, step, init)
    converged = final.status == CONVERGED
    return NewtonResult(final.x, converged, final.fnorm, final.k, final.status)


def implicit_newton(residual: Callable[[jax.Array], jax.Array], x0: jax.Array,
                    tol: float = 1e-13):
    """(x, stats): a root of ``residual`` by ``newton`` from x0, differentiable by the
    implicit function theorem (``lax.custom_root``).

    ``residual`` closes over the parameters p that x(p) depends on. The primal is Newton's
    solve; the tangent is one dense solve with the Jacobian at the root,
    dx = -(dR/dx)^-1 (dR/dp) dp, so Newton's iterations are never differentiated and the
    starting point carries no gradient. ``stats`` = (converged as 0/1, residual norm,
    iterations) as a float array (custom_root's tangent rule cannot carry integer outputs).
    Under ``vmap`` each batch element gets its own solve.
    """

    def solve(f, z_init):
        res = newton(lambda z, _: f(z), z_init, None, tol=tol)
        return res.x, jnp.stack([res.converged.astype(z_init.dtype), res.residual_norm,
                                 res.iterations.astype(z_init.dtype)])

    def tangent_solve(g, y):
        return jnp.linalg.solve(jax.jacfwd(g)(y), y)

    return jax.lax.custom_root(residual, jax.lax.stop_gradient(x0), solve, tangent_solve,
                               has_aux=True)
