"""The one pseudo-arclength driver (Keller): a curve of solutions of R(w) = 0, R: R^n -> R^(n-1),
followed through its turning points.

With the weighted inner product <a, b> of the system and the unit tangent t_k at w_k, a step is

    predictor   w_p = w_k + ds t_k
    corrector   R(w) = 0,  <t_k, w - w_p> = 0                 (Newton, exact Jacobian)
    tangent     [R_w(w_{k+1}); (W t_k)^T] t = e_n,   t_{k+1} = t / <t, t>^(1/2)

accepted when the corrector converges and the tangent turns by less than ~25 degrees
(<t_{k+1}, t_k> > 0.9); the step grows by ``growth`` after an easy corrector (<= 3 Newton
steps) and is halved after a rejection. A run stops when an accepted point leaves the
system's bounds (REACHED_BOUND), after ``max_events`` events of the system (its fold or cusp
count: ``event_status``), when the fixed-capacity record is full, or when the step falls
below ``ds_min`` (STEP_TOO_SMALL).

What differs between curves is the *system* (a static, hashable object): the equilibria
F(x, lam) = 0 (``jaxrod.solvers.continuation``) or the folds in two parameters
(``jaxrod.solvers.fold_curve``). It provides

    linearise(w, aux, data) -> (R, R_w)      the system and its Jacobian (n - 1 rows)
    inner(a, b), weights                     <a, b> = sum W_i a_i b_i
    accepted(w, aux, J) -> (aux, J)          the system's state after an accepted point
                                             (the fold curve's normalisation vector) and the
                                             Jacobian there for the tangent
    record(out, k, w, t, J, newton) -> out   the recorded columns of point k
    event(w, t, t_old, J, out, k_old) -> bool   a fold (sign change of dlam) or a cusp
    outside(w, options) -> bool              beyond the bounds

The whole run is one ``lax.while_loop`` (jit-, vmap-compatible).
"""

from __future__ import annotations

from typing import Any, NamedTuple

import jax
import jax.numpy as jnp

from jaxrod.solvers.newton import newton
from jaxrod.status import Status

RUNNING, REACHED_BOUND, CAPACITY_FULL, STEP_TOO_SMALL, NOT_CONVERGED = (
    Status.RUNNING, Status.REACHED_BOUND, Status.CAPACITY_FULL, Status.STEP_TOO_SMALL,
    Status.NOT_CONVERGED)


class StepControl(NamedTuple):
    """The step control every curve shares (traced)."""

    ds: Any
    ds_min: Any
    ds_max: Any
    growth: Any
    tol: Any
    max_events: Any


class _State(NamedTuple):
    w: jax.Array
    t: jax.Array
    aux: Any
    ds: jax.Array
    k: jax.Array
    rejected: jax.Array
    events: jax.Array
    status: jax.Array
    out: Any


def _corrector(z, data):
    """[R(z); <t, z - w_p>] and its Jacobian [R_w; (W t)^T]."""
    system, w_pred, t, aux, sys_data = data
    R, J = system.linearise(z, aux, sys_data)
    return (jnp.append(R, system.inner(t, z - w_pred)),
            jnp.vstack([J, (system.weights * t)[None, :]]))


def unit_tangent(system, J, t_prev):
    """The solution t of [J; (W t_prev)^T] t = e_n, scaled to <t, t> = 1."""
    B = jnp.vstack([J, (system.weights * t_prev)[None, :]])
    t = jnp.linalg.solve(B, jnp.zeros(B.shape[0], B.dtype).at[-1].set(1.0))
    return t / jnp.sqrt(system.inner(t, t))


def arclength_run(system, data, w0, orient, aux0, out0, control: StepControl, options,
                  capacity: int, event_status: int):
    """Follow the curve of ``system`` from the point w0 (module docstring); ``out0`` is the
    empty record. The first pass of the loop is the start itself: the corrector at w0 (a
    converged point needs no step) gives the Jacobian there and the unit tangent t0 with
    <t0, orient> > 0, recorded as point 0; so the program holds one copy of the system's
    linearisation. A start the corrector does not converge at is recorded as it ends and
    stops the run with ``NOT_CONVERGED``. Returns (out, num_points, status,
    rejected_steps)."""

    def step(s: _State) -> _State:
        first = s.k < 0
        w_pred = jnp.where(first, s.w, s.w + s.ds * s.t)
        res = newton(None, w_pred, (system, w_pred, s.t, s.aux, data), tol=control.tol,
                     linearise=_corrector, keep_jacobian=True)
        aux, J = system.accepted(res.x, s.aux, res.jacobian[:-1])
        t_new = unit_tangent(system, J, s.t)
        accept = first | (res.converged & (system.inner(t_new, s.t) > 0.9)
                          & jnp.all(jnp.isfinite(t_new)))
        k = s.k + jnp.where(accept, 1, 0)
        event = ~first & system.event(res.x, t_new, s.t, J, s.out, s.k)
        out = jax.lax.cond(accept, lambda o: system.record(o, k, res.x, t_new, J, res),
                           lambda o: o, s.out)
        events = s.events + jnp.where(accept & event, 1, 0)
        ds = jnp.where(first, s.ds,
                       jnp.where(accept, jnp.where(res.iterations <= 3,
                                                   jnp.minimum(s.ds * control.growth,
                                                               control.ds_max), s.ds),
                                 0.5 * s.ds))
        w = jnp.where(accept, res.x, s.w)
        status = jnp.where(accept & ~first & system.outside(w, options), int(REACHED_BOUND),
                           jnp.where(events >= control.max_events, int(event_status),
                                     jnp.where(k >= capacity - 1, int(CAPACITY_FULL),
                                               jnp.where(ds < control.ds_min,
                                                         int(STEP_TOO_SMALL), int(RUNNING)))))
        status = jnp.where(first & ~res.converged, int(NOT_CONVERGED), status)
        aux = jax.tree_util.tree_map(lambda a, b: jnp.where(accept, a, b), aux, s.aux)
        return _State(w, jnp.where(accept, t_new, s.t), aux, ds, k,
                      s.rejected + jnp.where(accept, 0, 1), events, status, out)

    init = _State(w0, orient, aux0, jnp.asarray(control.ds, w0.dtype), jnp.asarray(-1),
                  jnp.asarray(0), jnp.asarray(0), jnp.asarray(int(RUNNING)), out0)
    final = jax.lax.while_loop(lambda s: s.status == int(RUNNING), step, init)
    return final.out, final.k + 1, final.status, final.rejected
