"""Damped Newton's method for F(x, args) = 0, as one ``lax.while_loop``.

Each step solves J(x_k) dx = -F(x_k) with the exact Jacobian J = dF/dx (the caller's
assembled ``jacobian``, or forward-mode autodiff of F) and a dense LU solve, then
backtracks x_{k+1} = x_k + t dx, t = 1, 1/2, 1/4, ..., until
||F(x_{k+1})|| < (1 - t/4) ||F(x_k)|| (Armijo on the residual norm). It stops when

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

import functools
from collections.abc import Callable
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp

from jaxrod.status import Status

CONVERGED, MAX_STEPS, NONFINITE, LINE_SEARCH_FAILED = (
    Status.SUCCESS, Status.MAX_STEPS, Status.NONFINITE, Status.LINE_SEARCH_FAILED)
#: The messages of Newton's codes (``jaxrod.status.Status``).
STATUS_MESSAGES = {int(c): c.message for c in (CONVERGED, MAX_STEPS, NONFINITE,
                                                LINE_SEARCH_FAILED)}


class NewtonResult(NamedTuple):
    """Outcome of ``newton``: the iterate and how it was obtained."""

    x: jax.Array
    converged: jax.Array
    residual_norm: jax.Array
    iterations: jax.Array
    status: jax.Array
    #: dF/dx at ``x`` when asked for (``keep_jacobian``), else None
    jacobian: jax.Array | None = None

    def message(self) -> str:
        """Human-readable status (host side)."""
        return Status(int(self.status)).message


class _State(NamedTuple):
    x: jax.Array  # the last accepted iterate
    fnorm: jax.Array  # |F(x)|_inf
    dx: jax.Array  # the Newton step from x
    t: jax.Array  # the step length being tried
    k: jax.Array  # Newton steps taken
    done: jax.Array
    status: jax.Array
    jac: jax.Array | None  # dF/dx at x (with keep_jacobian)


def _norm(v):
    return jnp.max(jnp.abs(v))


def newton(residual: Callable[[jax.Array, Any], jax.Array], x0: jax.Array, args: Any = None, *,
           tol: float = 1e-12, xtol: float = 1e-10, max_steps: int = 50,
           max_halvings: int = 12, stall_xtol: float = 1e-7, floor_tol: float = 0.0,
           jacobian: Callable[[jax.Array, Any], jax.Array] | None = None,
           linearise: Callable[[jax.Array, Any], tuple[jax.Array, Any]] | None = None,
           solve: Callable[[Any, jax.Array], jax.Array] | None = None,
           keep_jacobian: bool = False) -> NewtonResult:
    """Solve ``residual(x, args) = 0`` from ``x0`` (square system, x a 1-D array).

    Args:
      residual: pure function.
      x0: initial guess.
      args: PyTree of parameters passed through unchanged.
      tol: absolute tolerance on the max-norm of the residual.
      xtol: relative tolerance on the max-norm of a full Newton step; the step is applied,
        so near a regular root (quadratic convergence) the result is accurate to ~xtol^2.
      max_steps, max_halvings: static iteration budgets.
      stall_xtol: a step this small (relative) that cannot reduce |F| means |F| is at its
        round-off floor: accepted as converged.
      floor_tol: where no step length reduces |F| and |F| <= floor_tol, |F| is taken to be
        at its round-off floor whatever the step (a nearly singular direction, where the
        floor's noise makes the step large): accepted as converged. 0 (default): never.
      jacobian: ``jacobian(x, args)`` = dF/dx, exact (assembled from the problem's
        structure); default ``jax.jacfwd`` of the residual.
      linearise: ``linearise(x, args)`` = (F, dF/dx) in one evaluation (where the two share
        their expensive parts); replaces ``residual`` (which may then be None) and
        ``jacobian``. The Jacobian is then also formed at a rejected trial point (rare).
      solve: ``solve(J, b)`` = J^-1 b for what ``linearise`` returns as J (any PyTree: the
        blocks of a structured Jacobian solved by block elimination); default a dense LU
        solve of the matrix J.
      keep_jacobian: return dF/dx at the final x in ``jacobian`` (needs ``linearise``
        returning the matrix, and the default ``solve``), so
        that a caller that needs it there (a continuation's tangent, a stability test) does
        not assemble it again.

    The loop evaluates F at one place and the Jacobian at one other (each pass tries one
    step length), or both at one place with ``linearise``, so the compiled program holds one
    copy of each.
    """
    x0 = jnp.asarray(x0)
    if keep_jacobian and (linearise is None or solve is not None):
        raise ValueError("keep_jacobian needs linearise with a matrix Jacobian (no solve)")
    if not jnp.issubdtype(x0.dtype, jnp.floating):
        x0 = x0.astype(jnp.float64)  # float32 input stays float32 (tolerances are the caller's)
    # evaluate(x) = (F(x), J): J as a thunk, formed only inside the branch that solves with it
    if linearise is None:
        jac = jax.jacfwd(residual) if jacobian is None else jacobian

        def evaluate(x):
            return residual(x, args), lambda: jac(x, args)
    else:
        def evaluate(x):
            F, J = linearise(x, args)
            return F, lambda: J
    if solve is None:
        solve = jnp.linalg.solve
    dtype = x0.dtype
    min_t = 0.5**max_halvings

    def step(s: _State) -> _State:
        first = s.k < 0  # the pass that evaluates F(x0)
        trial = s.x + s.t * s.dx
        ft, jac_at = evaluate(trial)
        fn = _norm(ft)
        finite = jnp.all(jnp.isfinite(trial)) & jnp.isfinite(fn)
        accepted = jnp.where(first, finite, fn < (1.0 - 0.25 * s.t) * s.fnorm)
        dx_small = _norm(s.dx) <= xtol * (1.0 + _norm(s.x))
        # A full step that is already at round-off level counts as converged even if the
        # residual did not decrease (it is at its floor).
        small_step = ~first & (s.t == 1.0) & dx_small
        move = accepted | small_step
        x = jnp.where(move, trial, s.x)
        fnorm = jnp.where(move, fn, s.fnorm)
        k = jnp.where(move, s.k + 1, s.k)
        converged_here = move & ((fn <= tol) | small_step)
        # No step length reduces |F| although the Newton step is tiny: the residual sits at
        # its round-off floor (|F| cannot be evaluated more accurately), so x is as accurate
        # as the arithmetic allows.
        exhausted = ~first & ~move & (s.t <= min_t)
        at_floor = exhausted & (_norm(s.dx) <= stall_xtol * (1.0 + _norm(s.x)))
        if floor_tol > 0.0:  # (a Python branch: without it the program is unchanged)
            at_floor = at_floor | (exhausted & (s.fnorm <= floor_tol))
        new_direction = move & ~converged_here & (k < max_steps)
        # a new direction needs a move, so x is the trial point the Jacobian belongs to
        dx = jax.lax.cond(new_direction, lambda: solve(jac_at(), -ft),
                          lambda: s.dx)
        bad_direction = new_direction & ~jnp.all(jnp.isfinite(dx))
        status = jnp.where(
            converged_here | at_floor, CONVERGED,
            jnp.where((first & ~finite) | bad_direction | (exhausted & ~finite), NONFINITE,
                      jnp.where(exhausted, LINE_SEARCH_FAILED, MAX_STEPS)))
        done = converged_here | at_floor | exhausted | bad_direction | (first & ~finite) \
            | (move & (k >= max_steps))
        t = jnp.where(move, jnp.ones((), dtype), 0.5 * s.t)
        jac = jnp.where(move, jac_at(), s.jac) if keep_jacobian else None
        return _State(x, fnorm, dx, t, k, done, status, jac)

    m = x0.shape[0]
    init = _State(x0, jnp.asarray(jnp.inf, dtype), jnp.zeros_like(x0), jnp.zeros((), dtype),
                  jnp.asarray(-1), jnp.asarray(False), jnp.asarray(MAX_STEPS),
                  jnp.zeros((m, m), dtype) if keep_jacobian else None)
    final = jax.lax.while_loop(lambda s: ~s.done, step, init)
    converged = final.status == CONVERGED
    return NewtonResult(final.x, converged, final.fnorm, jnp.maximum(final.k, 0), final.status,
                        final.jac)


def implicit_newton(residual: Callable[[jax.Array, Any], jax.Array] | None, x0: jax.Array,
                    params: Any, tol: float = 1e-13,
                    jacobian: Callable[[jax.Array, Any], jax.Array] | None = None,
                    linearise: Callable[[jax.Array, Any], tuple[jax.Array, jax.Array]]
                    | None = None):
    """(x, stats): a root of ``residual(x, params) = 0`` by ``newton`` from x0,
    differentiable in ``params`` by the implicit function theorem.

    The primal is Newton's solve; the tangent (a ``jax.custom_jvp`` rule) is one dense solve
    with the Jacobian at the root,

        dx = -(dR/dx)^-1 (dR/dparams . dparams),

    where dR/dparams . dparams is one forward-mode pass through ``residual`` at the root
    (give it with ``linearise`` where it is cheaper than the linearisation) and dR/dx is the
    exact Jacobian Newton uses (``jacobian``, or ``linearise`` giving both, as in
    ``newton``; forward-mode autodiff of ``residual`` when neither is given), taken from
    Newton's last step (at the root). Newton's iterations are never differentiated and the
    starting point carries no gradient.
    ``stats`` = (converged as 0/1, residual norm, iterations) as a float array, with zero
    tangent. Under ``vmap`` each batch element gets its own solve; under ``jacfwd`` the
    tangents share one factorisation of dR/dx.
    """
    if linearise is None:
        jac = (lambda x, p: jax.jacfwd(residual)(x, p)) if jacobian is None else jacobian
        linearise = lambda x, p: (residual(x, p), jac(x, p))
    if residual is None:
        residual = lambda x, p: linearise(x, p)[0]
    return _implicit_root(residual, linearise, tol, jax.lax.stop_gradient(x0), params)[:2]


@functools.partial(jax.custom_jvp, nondiff_argnums=(0, 1, 2))
def _implicit_root(residual, linearise, tol, x0, params):
    """(x, stats, the Jacobian at x): Newton's solve and the Jacobian of its last step (at
    the root), which the tangent rule solves with: no second linearisation in the program.
    The Jacobian output carries no tangent; the rule differentiates it through
    ``_jacobian_at``."""
    res = newton(None, x0, params, tol=tol, linearise=linearise, keep_jacobian=True)
    return res.x, jnp.stack([res.converged.astype(x0.dtype), res.residual_norm,
                             res.iterations.astype(x0.dtype)]), res.jacobian


@functools.partial(jax.custom_jvp, nondiff_argnums=(0,))
def _jacobian_at(linearise, J, x, params):
    """J, the Jacobian of ``linearise`` at (x, params) already computed; its tangent (traced
    only for derivatives of second order) is that of ``linearise``'s Jacobian."""
    return J


@_jacobian_at.defjvp
def _jacobian_at_jvp(linearise, primals, tangents):
    J, x, params = primals
    _, dx, dparams = tangents
    return J, jax.jvp(lambda y, p: linearise(y, p)[1], (x, params), (dx, dparams))[1]


@_implicit_root.defjvp
def _implicit_root_jvp(residual, linearise, tol, primals, tangents):
    x0, params = primals
    _, dparams = tangents
    x, stats, J = _implicit_root(residual, linearise, tol, x0, params)
    dR = jax.jvp(lambda p: residual(x, p), (params,), (dparams,))[1]
    dx = -jnp.linalg.solve(_jacobian_at(linearise, J, x, params), dR)
    return (x, stats, J), (dx, jnp.zeros_like(stats), jnp.zeros_like(J))
