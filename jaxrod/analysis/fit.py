"""Young's modulus from measured switching angles (paper, permanent-magnet experiment).

The measured angles, in the order of the experiment's protocol and with the sign of the
magnet angle alpha (positive towards e1):

    0 cw_capture    clockwise sweep (alpha increasing), the rod snaps onto the magnet
    1 cw_release    clockwise sweep, the rod lets go
    2 ccw_capture   counter-clockwise sweep (alpha decreasing), snaps on
    3 ccw_release   counter-clockwise sweep, lets go

are modelled by the folds of the planar branch (``fold_angles``) and an optional constant
offset delta of the angular scale (a misaligned track):

    cw_capture = -alpha_lower + delta,    cw_release = alpha_upper + delta,
    ccw_capture = alpha_lower + delta,    ccw_release = -alpha_upper + delta.

With E the only material unknown, G and M scale as 1/E (``gravity_group``,
``magnet_group``) and D does not depend on E. The fit minimises
0.5 sum_i ((model_i - measured_i) / sigma)^2 over p = (log E, delta) (log E keeps E
positive) with optax's L-BFGS direction (``optax.scale_by_lbfgs``) and a backtracking line
search on the sufficient decrease (Armijo) condition, in scaled coordinates
p = p0 + P u with P = (J0^T J0)^(-1/2) from the first Jacobian, so that the first direction
is the Gauss-Newton step.

The fold model tracks the folds: the folds at the starting modulus come from the one-mode
brackets and Moore-Spence (``jaxrod.analysis.batch.fold_pair_states``, no continuation), and
every later evaluation solves each fold's Moore-Spence system from the folds of the last
accepted point (``tracked_angles``; the folds move smoothly with E). Residuals, their
Jacobian and the gradient J^T r come from one forward-mode pass at one place in the loop
(implicit differentiation of the Moore-Spence systems), and a trial point where a solve
fails is rejected by the line search. The standard deviation of E follows from the
Gauss-Newton covariance (J^T J)^-1 of the residuals r_i / sigma at the optimum:
std(E) = E std(log E). ``model_angles`` (a continuation from the straight rod per call) is
the independent reference the tests build synthetic data with.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
import optax

from jaxrod.analysis.batch import fold_pair_states
from jaxrod.analysis.magnet import fold_angles
from jaxrod.discretise.planar import PlanarDiscretisation, planar_discretisation
from jaxrod.params import (
    NDFEB_MAGNET,
    RANGES,
    ParameterError,
    check,
    check_track_clearance,
    preset,
)
from jaxrod.progress import Interrupted, progress_bar
from jaxrod.scenes.dipole import ALPHA_MODEL, DipoleMagnet
from jaxrod.solvers.folds import differentiable_fold
from jaxrod.stored import StoredProgram

ANGLE_NAMES = ("cw_capture", "cw_release", "ccw_capture", "ccw_release")
_SIGNS = jnp.array([-1.0, 1.0, 1.0, -1.0])  # fold angle sign per measured angle
_FOLD = jnp.array([0, 1, 0, 1])  # lower / upper fold per measured angle
LOG_E_RANGE = (math.log(1e9), math.log(1e13))


@jax.tree_util.register_dataclass
@dataclasses.dataclass(frozen=True)
class FitSetup:
    """G and M at the reference modulus E_ref (both scale as 1/E) and the track ratio D."""

    G_ref: float
    M_ref: float
    D: float
    E_ref: float

    def __post_init__(self):
        # concrete values are checked; traced or placeholder leaves (jax rebuilds the
        # dataclass inside programs) are not
        values = (self.G_ref, self.M_ref, self.D, self.E_ref)
        if all(isinstance(v, (int, float, np.integer, np.floating)) for v in values):
            check("G-magnet", self.G_ref)
            check("M", self.M_ref)
            check_track_clearance(self.D)
            check("E", self.E_ref)


def setup_from_preset(name: str = "permanent-magnet") -> FitSetup:
    rod, _ = preset(name)
    return FitSetup(rod.G, rod.M(NDFEB_MAGNET), rod.D(NDFEB_MAGNET),
                    rod.material.youngs_modulus)


def model_angles(params, setup: FitSetup, n: int = 12):
    """The four switching angles (degrees) at p = (log E, delta_deg), and a converged flag."""
    scale = setup.E_ref / jnp.exp(params[0])
    alphas, converged = fold_angles(setup.G_ref * scale, setup.M_ref * scale, setup.D, n=n)
    return _SIGNS * jnp.degrees(alphas[_FOLD]) + params[1], converged


class FitResult(dict):
    """E_Pa, E_std_Pa, offset_deg, offset_std_deg, residuals_deg (None where not measured),
    converged, iterations, reduced_chi2, reason (why not converged), warning (poor fit)."""


#: Moore-Spence discretisation of the fit's fold model (N = 12 reaches the round-off floor
#: of the fold angles at the experiment's parameters).
FIT_N = 12


def _scene(log_e, setup: FitSetup):
    scale = setup.E_ref / jnp.exp(log_e)
    return DipoleMagnet(setup.G_ref * scale, setup.M_ref * scale, setup.D, 0.0)


def tracked_angles(params, z, setup: FitSetup, disc: PlanarDiscretisation):
    """The four switching angles (degrees) at p = (log E, delta_deg) from fold states z
    (2, 2m + 1) at nearby parameters: each fold is its Moore-Spence solution from z
    (``differentiable_fold``, implicitly differentiated). Returns (angles, (z_new, ok));
    ok is False when a solve fails or the folds leave 0 < lower < upper <= 90 degrees."""
    args = (_scene(params[0], setup), disc)
    m = disc.size
    z_new, stats = jax.vmap(lambda zi: differentiable_fold(
        ALPHA_MODEL, zi[:m], zi[-1], zi[m:2 * m], args))(z)
    alphas = z_new[:, -1]
    ok = jnp.all(stats[:, 0] == 1.0) & (alphas[0] > 0.0) & (alphas[1] - alphas[0] > 1e-9) \
        & (alphas[1] <= 0.5 * jnp.pi)
    return _SIGNS * jnp.degrees(alphas[_FOLD]) + params[1], (z_new, ok)


class _Search(NamedTuple):
    """The fit's loop state: u the accepted point in scaled coordinates p = p0 + P u, the
    fold states z there, the loss, its u-gradient, the residuals and their p-Jacobian, the
    L-BFGS state and direction, the step length t being tried, and counters."""

    u: jax.Array
    z: jax.Array
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


def _fit_core(measured, mask, sigma, fit_offset, setup: FitSetup, log_e0, max_iter: int = 40,
              gtol: float = 1e-9):
    """Minimise 0.5 |r(p)|^2 with optax's L-BFGS direction and a backtracking (Armijo) line
    search; the fold model is evaluated at one place per pass, from the fold states of the
    last accepted point (module docstring)."""
    offset_free = jnp.asarray(fit_offset, jnp.float64)
    columns = jnp.array([1.0, 0.0]) + jnp.array([0.0, 1.0]) * offset_free
    fixed = jnp.diag(jnp.array([0.0, 1.0]) * (1.0 - offset_free))
    disc = planar_discretisation(FIT_N, "clamped")
    start = _scene(jnp.asarray(log_e0, jnp.float64), setup)
    z0, found, _ = fold_pair_states(start.G, start.M, start.D, disc)
    p0 = jnp.array([log_e0, 0.0])
    target = jnp.where(mask, measured, 0.0)

    def evaluate(p, z):
        def residuals(q):
            model, (z_new, ok) = tracked_angles(q, z, setup, disc)
            r = jnp.where(mask, (model - target) / sigma, 0.0)
            return r, (r, z_new, ok)

        J, (r, z_new, ok) = jax.jacfwd(residuals, has_aux=True)(p)
        return r, J * columns, z_new, ok

    opt = optax.scale_by_lbfgs(scale_init_precond=False)  # in u: unit initial preconditioner

    def step(s: _Search) -> _Search:
        first = s.evals == 0
        u = s.u + s.t * s.direction
        p = p0 + s.P @ u
        r, J, z, ok = evaluate(p, s.z)
        in_range = (p[0] > LOG_E_RANGE[0]) & (p[0] < LOG_E_RANGE[1])
        good = ok & in_range & jnp.all(jnp.isfinite(r)) & jnp.all(jnp.isfinite(J))
        value = jnp.where(good, 0.5 * jnp.dot(r, r), jnp.inf)
        # scaled coordinates from the first Gauss-Newton metric: J^T J ~ identity in u
        P = jnp.where(first, _inverse_sqrt(J.T @ J + fixed), s.P)
        grad_u = P.T @ (J.T @ r)
        armijo = value <= s.value + 1e-4 * s.t * jnp.dot(s.grad_u, s.direction)
        # at the loss's round-off floor a decrease cannot be seen: a smaller gradient decides
        at_floor = (jnp.abs(value - s.value) <= 64.0 * jnp.finfo(r.dtype).eps * s.value) \
            & (jnp.max(jnp.abs(grad_u)) < jnp.max(jnp.abs(s.grad_u)))
        accept = good & (first | armijo | at_floor)
        update, opt_state = opt.update(grad_u, s.opt_state, u)
        direction = jnp.where(jnp.dot(update, grad_u) > 0.0, -update, -grad_u)
        pick = lambda new, old: jax.tree_util.tree_map(
            lambda a, b: jnp.where(accept, a, b), new, old)
        u, z, value, grad_u, r, J, ok, opt_state, direction = pick(
            (u, z, value, grad_u, r, J, ok, opt_state, direction),
            (s.u, s.z, s.value, s.grad_u, s.r, s.J, s.ok, s.opt_state, s.direction))
        k = s.k + (accept & ~first)
        # converged: the gradient vanishes, or no decrease can be seen along a step below
        # 1e-7 standard deviations (u is in units of the Gauss-Newton standard deviation):
        # the loss is at its round-off floor there
        at_round_off = ~accept & ~first & good & (s.t * jnp.max(jnp.abs(s.direction)) <= 1e-7)
        converged = (accept & (jnp.max(jnp.abs(J.T @ r)) <= gtol)) | at_round_off
        stalled = ~accept & (s.t < 1e-10)
        done = converged | stalled | (first & ~good) | (k >= max_iter) \
            | (s.evals + 1 >= 4 * max_iter)
        t = jnp.where(accept, 1.0, 0.5 * s.t)
        return _Search(u, z, value, grad_u, r, J, ok, opt_state, direction, t, P, k,
                       s.evals + 1, converged, done)

    zero = jnp.zeros(2)
    init = _Search(zero, z0, jnp.inf, zero, jnp.zeros(4), jnp.zeros((4, 2)), found,
                   opt.init(zero), zero, jnp.zeros(()), jnp.eye(2), jnp.asarray(0),
                   jnp.asarray(0), jnp.asarray(False), ~found)
    s = jax.lax.while_loop(lambda s: ~s.done, step, init)
    p = p0 + s.P @ s.u
    # residuals, Jacobian and gradient (J^T r) at the optimum from its accepted evaluation
    cov = jnp.linalg.inv(s.J.T @ s.J + fixed)
    return p, s.r * sigma, jnp.sqrt(cov[0, 0]), jnp.sqrt(cov[1, 1]) * offset_free, \
        s.ok & found, s.k, jnp.max(jnp.abs(s.J.T @ s.r)), s.converged


_fit_jit = StoredProgram("fit", _fit_core, static_argnames=("max_iter",))
_fit_batch_jit = jax.jit(jax.vmap(_fit_core, in_axes=(0, 0, None, None, None, None)))


def _parse(measured, sigma_deg):
    try:
        measured = np.asarray(measured, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        raise ParameterError(f"angles: give 4 numbers ({', '.join(ANGLE_NAMES)}), got "
                             f"{measured!r:.60}") from None
    if measured.size != 4:
        raise ParameterError(f"angles: give 4 values ({', '.join(ANGLE_NAMES)}), with nan for "
                             f"a missing one; got {measured.size}")
    if np.any(np.isinf(measured)):
        raise ParameterError(f"angles: must be finite, or nan for one not measured; got "
                             f"{measured.tolist()}")
    mask = ~np.isnan(measured)
    if mask.sum() == 0:
        raise ParameterError("angles: at least one measured angle is needed")
    check("sigma-deg", sigma_deg)
    angle = RANGES["angle"]
    bad = [name for name, v, m in zip(ANGLE_NAMES, measured, mask) if m and not angle.contains(v)]
    if bad:
        raise ParameterError(f"angles: switching angles must lie in {angle.interval()}; "
                             f"{', '.join(bad)} do not")
    return measured, mask


def fit_youngs_modulus(measured, sigma_deg: float = 1.0, fit_offset: bool = False,
                       setup: FitSetup | None = None, E0: float = 150e9) -> FitResult:
    """Fit E (and optionally the offset) to measured switching angles in degrees.

    ``measured`` holds the four angles in ``ANGLE_NAMES`` order; nan marks one that was not
    measured. With the offset free, at least two angles are needed.
    """
    measured, mask = _parse(measured, sigma_deg)
    if fit_offset and mask.sum() < 2:
        raise ParameterError("angles: fitting the offset needs at least two angles")
    check("E", E0)
    setup = setup or setup_from_preset()
    out = _fit_jit(
        jnp.asarray(np.nan_to_num(measured)), jnp.asarray(mask), float(sigma_deg),
        bool(fit_offset), setup, math.log(E0))
    return _result(*out, mask, sigma_deg, fit_offset)


def fit_batch(measured, sigma_deg: float = 1.0, fit_offset: bool = False,
              setup: FitSetup | None = None, E0: float = 150e9,
              method: str = "auto", progress: bool = False) -> list[FitResult]:
    """Many independent fits, one per row of ``measured``.

    ``method="vmap"`` runs them in one vmapped, compiled call (the form that scales on a
    GPU); ``"loop"`` runs the compiled single fit row by row, which is faster on a CPU, where
    every nested while loop of a vmapped batch runs until its slowest element is done
    (benchmarks/fit_performance.py). ``"auto"`` picks vmap on a GPU and loop otherwise.
    ``progress`` shows a progress bar on a terminal (loop only); Ctrl-C raises
    ``jaxrod.progress.Interrupted`` with the fits done so far as ``partial``.
    """
    rows = []
    for i, m in enumerate(np.atleast_2d(measured)):
        try:
            rows.append(_parse(m, sigma_deg))
        except ParameterError as err:
            raise ParameterError(f"row {i}: {err}") from None
    setup = setup or setup_from_preset()
    if method == "auto":
        method = "vmap" if jax.default_backend() == "gpu" else "loop"
    if method not in ("vmap", "loop"):
        raise ParameterError(f"method must be 'auto', 'vmap' or 'loop', got {method!r}")
    if method == "loop":
        out = []
        bar = progress_bar(len(rows), "fits", "fit", progress)
        try:
            for m, _ in rows:
                out.append(fit_youngs_modulus(m, sigma_deg, fit_offset, setup, E0))
                bar.update(1)
        except KeyboardInterrupt:
            raise Interrupted(out, f"after {len(out)} of {len(rows)} fits") from None
        finally:
            bar.close()
        return out
    m = jnp.asarray(np.nan_to_num(np.stack([r[0] for r in rows])))
    mask = jnp.asarray(np.stack([r[1] for r in rows]))
    out = _fit_batch_jit(m, mask, float(sigma_deg), bool(fit_offset), setup, math.log(E0))
    return [_result(*(v[i] for v in out), np.asarray(mask[i]), sigma_deg, fit_offset)
            for i in range(m.shape[0])]


def _result(p, res, std_log_e, std_off, ok, k, gnorm, settled, mask, sigma_deg,
            fit_offset) -> FitResult:
    E = float(np.exp(p[0]))
    residuals = [float(r) if mk else None for r, mk in zip(np.asarray(res), mask)]
    used = [r for r in residuals if r is not None]
    dof = max(len(used) - (2 if fit_offset else 1), 1)
    chi2 = float(np.sum(np.square(used)) / sigma_deg**2)
    reasons = []
    if not bool(ok):
        reasons.append("the fold model has no two folds at the final E (no hysteresis there)")
    if not bool(settled):
        reasons.append(f"the gradient did not vanish (|grad| = {float(gnorm):.2e}) within "
                       f"{int(k)} iterations")
    if not (LOG_E_RANGE[0] < float(p[0]) < LOG_E_RANGE[1]):
        reasons.append("E left the range 1 GPa - 10 TPa")
    warning = None
    if len(used) > dof and chi2 / dof > 9.0:
        warning = (f"the residuals exceed sigma = {sigma_deg} deg (reduced chi^2 = "
                   f"{chi2 / dof:.3g}): the measurement error is larger than assumed, or the "
                   "angles' order or signs are wrong")
    return FitResult(
        E_Pa=E, E_std_Pa=E * float(std_log_e), offset_deg=float(p[1]),
        offset_std_deg=float(std_off), residuals_deg=residuals, converged=not reasons,
        iterations=int(k), reduced_chi2=chi2 / dof, reason="; ".join(reasons) or None,
        warning=warning)


def loss_profile(measured, E_values, sigma_deg: float = 1.0, fit_offset: bool = False,
                 setup: FitSetup | None = None):
    """0.5 chi^2 over a grid of E (offset at its best value for each E when fitted)."""
    measured, mask = _parse(measured, sigma_deg)
    setup = setup or setup_from_preset()

    def at(log_e):
        model, ok = model_angles(jnp.array([log_e, 0.0]), setup)
        d = jnp.where(mask, jnp.asarray(np.nan_to_num(measured)) - model, 0.0)
        delta = jnp.where(fit_offset, jnp.sum(d) / jnp.sum(mask), 0.0)
        r = jnp.where(mask, (d - delta) / sigma_deg, 0.0)
        return jnp.where(ok, 0.5 * jnp.sum(r**2), jnp.nan)

    return np.asarray(jax.jit(jax.vmap(at))(jnp.log(jnp.asarray(E_values, jnp.float64))))
