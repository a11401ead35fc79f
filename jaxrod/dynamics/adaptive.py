"""BDF2 with adaptive steps: the rod's motion at a stated accuracy, in as few steps as it
allows (slow approaches to a fold in long steps, the snap itself in short ones).

Each step is variable-step BDF2 on Lagrange's equations (``jaxrod.dynamics.integrate``,
coefficients from the step ratio omega = h_n / h_{n-1}), solved by Newton. Its local error
is estimated by the difference from the quadratic extrapolation of the last three states,

    err = C |q_{n+1} - q_pred|,   C = 2/11,

(BDF2's error constant 2/9 against the extrapolation's 1 at equal steps), measured in the
norm rms(err_i / (tol (1 + |q_i|))). A step with err <= 1 is kept and the next is
h * min(2, max(0.2, 0.9 err^(-1/3))); a larger error, or a Newton solve that does not
converge, repeats the step shorter. The first two steps (backward Euler, then BDF2) take the
initial step ``dt``. Everything runs in one ``lax.while_loop`` writing into buffers of
``max_steps`` rows (forward-mode differentiable; the accepted steps are counted, the rest of
the buffers unused).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from jaxrod.dynamics.integrate import bdf_step, observe
from jaxrod.dynamics.lagrangian import scene_at
from jaxrod.programs import jit

ERROR_CONSTANT = 2.0 / 11.0


def _extrapolate(q, qm, qmm, h, h1, h2):
    """The quadratic through (0, q), (-h1, qm), (-h1 - h2, qmm) at h."""
    t1, t2 = -h1, -h1 - h2
    l0 = (h - t1) * (h - t2) / (t1 * t2)
    l1 = h * (h - t2) / (t1 * (t1 - t2))
    l2 = h * (h - t1) / (t2 * (t2 - t1))
    return l0 * q + l1 * qm + l2 * qmm


def _run(path, disc, q0, p0, t_end, dt, h_max, tol, max_steps, c, start, rate):
    size = q0.shape[0]
    z = jnp.zeros(max_steps)
    buffers = (z, jnp.zeros((max_steps, size)), z, z, z, z, jnp.zeros((max_steps, 3)),
               jnp.zeros(max_steps, bool), z)

    def go(carry):
        t, k, tries = carry[0], carry[2], carry[3]
        return (t < t_end * (1.0 - 1e-12)) & (k < max_steps) & (tries < 4 * max_steps)

    def attempt(carry):
        t, h, k, tries, hist, bufs = carry
        q, qm, qmm, p, pm, h1, h2 = hist
        h = jnp.minimum(jnp.minimum(h, h_max), t_end - t)
        at = scene_at(path, start, rate, t + h)
        ratio = jnp.where(k == 0, 0.0, h / h1)
        guess = jnp.where(k == 0, q, q + ratio * (q - qm))
        res, v1, p1 = bdf_step(at, disc, q, qm, p, pm, h, ratio, c, guess)
        pred = _extrapolate(q, qm, qmm, h, h1, h2)
        err = ERROR_CONSTANT * jnp.sqrt(jnp.mean(
            ((res.x - pred) / (tol * (1.0 + jnp.abs(res.x)))) ** 2))
        err = jnp.where(k < 2, 0.0, err)
        keep = res.converged & (err <= 1.0)
        grow = jnp.clip(0.9 * jnp.maximum(err, 1e-10) ** (-1.0 / 3.0), 0.2, 2.0)
        h_next = jnp.where(res.converged, jnp.where(k < 2, dt, h * grow), 0.25 * h)
        row = (t + h, res.x, *observe(at, disc, res.x, v1), res.converged, res.residual_norm)

        def write(b):
            return tuple(buf.at[k].set(jnp.where(keep, r, buf[k])) for buf, r in zip(b, row))

        new_hist = (res.x, q, qm, p1, p, h, h1)
        hist = jax.tree.map(lambda a, b: jnp.where(keep, a, b), new_hist, hist)
        return (jnp.where(keep, t + h, t), h_next, k + keep.astype(k.dtype), tries + 1, hist,
                write(bufs))

    hist = (q0, q0, q0, p0, p0, dt, dt)
    init = (jnp.asarray(0.0), jnp.asarray(dt), jnp.asarray(0), jnp.asarray(0), hist, buffers)
    t, _, k, _, _, bufs = jax.lax.while_loop(go, attempt, init)
    return t, k, bufs


run_adaptive = jit(_run, static_argnames=("max_steps",))
