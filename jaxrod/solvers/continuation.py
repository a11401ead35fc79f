"""Pseudo-arclength continuation of equilibria of a parametrised energy E(x, lam).

Equilibria solve F(x, lam) = grad_x E(x, lam) = 0. With y = (x, lam) and the weighted inner
product <a, b> = a_x . b_x / m + a_lam b_lam (m = len(x), so a change of the state is
measured by its RMS), one step from the point y_k with unit tangent t_k is (Keller):

    predictor   y_p = y_k + ds t_k
    corrector   F(y) = 0,  <t_k, y - y_p> = 0          (Newton, ``jaxrod.solvers.newton``)
    tangent     [F_x  F_lam; t_k^T W] t = [0; 1],  t_{k+1} = t / |t|

The bordered Jacobian is regular at simple folds, so the branch is followed round them.
The step adapts: it grows by ``growth`` after an easy corrector (<= 3 Newton steps), and is
halved after a failed corrector or a tangent turning by more than ~25 degrees; below
``ds_min`` the run stops with ``STEP_TOO_SMALL``. Along the branch the Hessian F_x is
symmetric; its smallest eigenvalue and number of negative eigenvalues (the Morse index) give
the stability, and a sign change of the parameter component of the tangent marks a fold.

The whole run is one ``lax.while_loop`` over fixed-capacity arrays (NaN padded beyond
``num_points``): jit-compiled once per (energy function, problem size, capacity). A run stops
at the parameter bounds, after ``max_folds`` folds, when full, or when the step collapses.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp

from jaxrod.derivatives import EnergyModel, as_model
from jaxrod.programs import jit
from jaxrod.solvers.arclength import (
    CAPACITY_FULL,
    NOT_CONVERGED,
    REACHED_BOUND,
    RUNNING,
    STEP_TOO_SMALL,
    StepControl,
    arclength_run,
)
from jaxrod.status import Status

FOLDS_FOUND = Status.FOLDS_FOUND
#: The messages of a run's codes (``jaxrod.status.Status``).
STATUS_MESSAGES = {int(c): c.message for c in (RUNNING, REACHED_BOUND, FOLDS_FOUND,
                                                CAPACITY_FULL, STEP_TOO_SMALL, NOT_CONVERGED)}

#: An ``EnergyModel`` (assembled derivatives) or a plain energy function E(x, lam, args).
Energy = EnergyModel | Callable[[jax.Array, jax.Array, Any], jax.Array]


class ContinuationOptions(NamedTuple):
    """Step control. ``max_points`` is static (array capacity); the others are traced."""

    ds: float = 0.02
    ds_min: float = 1e-7
    ds_max: float = 0.1
    growth: float = 1.5
    lam_min: float = -jnp.inf
    lam_max: float = jnp.inf
    tol: float = 1e-12
    max_folds: float = jnp.inf
    max_points: int = 400


class RawBranch(NamedTuple):
    """Device arrays of a continuation run (first ``num_points`` rows valid)."""

    x: jax.Array  # (capacity, m)
    lam: jax.Array  # (capacity,)
    tangent_lam: jax.Array  # (capacity,)
    tangent_x: jax.Array  # (capacity, m): the state part of the unit tangent (near a fold,
    #                       the null vector of the Hessian)
    min_eig: jax.Array  # (capacity,)
    morse_index: jax.Array  # (capacity,)
    newton_iterations: jax.Array  # (capacity,)
    residual_norm: jax.Array  # (capacity,)
    num_points: jax.Array
    status: jax.Array
    rejected_steps: jax.Array


def empty_branch(capacity: int, m: int) -> RawBranch:
    """The record of a run before its first point: ``capacity`` rows of m unknowns, NaN."""
    nan = jnp.full(capacity, jnp.nan)
    return RawBranch(
        x=jnp.full((capacity, m), jnp.nan), lam=nan, tangent_lam=nan,
        tangent_x=jnp.full((capacity, m), jnp.nan), min_eig=nan,
        morse_index=jnp.full(capacity, -1), newton_iterations=jnp.full(capacity, -1),
        residual_norm=nan, num_points=jnp.asarray(0), status=jnp.asarray(int(RUNNING)),
        rejected_steps=jnp.asarray(0))


def _wdot(a, b, m):
    return jnp.dot(a[:-1], b[:-1]) / m + a[-1] * b[-1]


def _spectrum(H):
    ev = jnp.linalg.eigvalsh(0.5 * (H + H.T))
    return ev[0], jnp.sum(ev < 0)


@dataclasses.dataclass(frozen=True)
class _Equilibria:
    """The equilibria F(x, lam) = grad_x E = 0 as a system of ``jaxrod.solvers.arclength``:
    w = (x, lam), <a, b> = a_x . b_x / m + a_lam b_lam; a fold is a sign change of dlam/ds."""

    model: EnergyModel
    m: int
    spectrum: bool
    dtype: Any

    @property
    def weights(self):
        return jnp.append(jnp.full(self.m, 1.0 / self.m, self.dtype), jnp.ones(1, self.dtype))

    def inner(self, a, b):
        return _wdot(a, b, self.m)

    def linearise(self, z, aux, args):
        F, H, g_lam = self.model.linearisation(z[:-1], z[-1], args)
        return F, jnp.hstack([H, g_lam[:, None]])

    def accepted(self, w, aux, J):
        return aux, J

    def record(self, out: RawBranch, k, w, t, J, res):
        return _record(out, k, w, t, J[:, :self.m], res.iterations, res.residual_norm,
                       self.spectrum)

    def event(self, w, t, t_old, J, out, k_old):
        return t[-1] * t_old[-1] < 0

    def outside(self, w, opts):
        return (w[-1] > opts.lam_max) | (w[-1] < opts.lam_min)


def _record(out: RawBranch, k, y, t, H, iters, res, spectrum: bool) -> RawBranch:
    lo, index = _spectrum(H) if spectrum else (jnp.nan, -1)
    return out._replace(
        x=out.x.at[k].set(y[:-1]), lam=out.lam.at[k].set(y[-1]),
        tangent_lam=out.tangent_lam.at[k].set(t[-1]),
        tangent_x=out.tangent_x.at[k].set(t[:-1]), min_eig=out.min_eig.at[k].set(lo),
        morse_index=out.morse_index.at[k].set(index),
        newton_iterations=out.newton_iterations.at[k].set(iters),
        residual_norm=out.residual_norm.at[k].set(res))


def pseudo_arclength(energy: Energy, x0: jax.Array, lam0, args: Any,
                     options: ContinuationOptions = ContinuationOptions(),
                     direction: float = 1.0) -> RawBranch:
    """Trace the equilibrium branch of ``energy`` through the converged point (x0, lam0).

    ``energy(x, lam, args)`` must be a pure function; pass the same function object each
    time (not a new closure) so that the compiled program is reused.
    """
    return _pseudo_arclength(energy, jnp.asarray(x0, jnp.float64), jnp.asarray(lam0, jnp.float64),
                             args, options._replace(max_points=0), options.max_points, direction)


def continuation_run(energy: Energy, x0, lam0, args, opts: ContinuationOptions, capacity: int,
                     direction, spectrum: bool = True) -> RawBranch:
    """Traceable core of ``pseudo_arclength`` (``capacity`` static; vmappable over direction).

    ``spectrum`` (static): record the Hessian's smallest eigenvalue and Morse index at every
    point (an eigendecomposition per step); without it ``min_eig`` stays NaN and
    ``morse_index`` -1, for runs that only need the branch and its folds. The steps are those
    of ``jaxrod.solvers.arclength`` with the system of the equilibria."""
    model = as_model(energy)
    m = x0.shape[0]
    y0 = jnp.append(x0, lam0)
    system = _Equilibria(model, m, spectrum, y0.dtype)
    # the first tangent is oriented so that d lam has the sign of direction
    orient = jnp.zeros(m + 1, y0.dtype).at[-1].set(jnp.sign(direction))
    out = empty_branch(capacity, m)
    control = StepControl(opts.ds, opts.ds_min, opts.ds_max, opts.growth, opts.tol,
                          opts.max_folds)
    out, num, status, rejected = arclength_run(
        system, args, y0, orient, None, out, control, opts, capacity,
        FOLDS_FOUND)
    return out._replace(num_points=num, status=status, rejected_steps=rejected)


_pseudo_arclength = jit(continuation_run, static_argnums=(0, 5))
