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
brackets and Moore-Spence where they succeed, else from a continuation from the straight rod
(``jaxrod.inverse.calibration.start_states``, the calibration's start), and every later
evaluation solves each fold's Moore-Spence system from the folds of the last accepted point
(``tracked_angles``; the folds move smoothly with E). Residuals, their
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

import jax
import jax.numpy as jnp
import numpy as np

from jaxrod.discretise.planar import PlanarDiscretisation, planar_discretisation
from jaxrod.inverse.calibration import (
    ANGLE_NAMES,
    angles_from_folds,
    sign_hint,
    start_states,
)
from jaxrod.magnet.folds import fold_angles
from jaxrod.params import (
    NDFEB_MAGNET,
    RANGES,
    ParameterError,
    check,
    check_track_clearance,
    preset,
)
from jaxrod.programs import jit
from jaxrod.progress import Interrupted, progress_bar
from jaxrod.scenes.dipole import ALPHA_MODEL, DipoleMagnet
from jaxrod.solvers.folds import differentiable_fold
from jaxrod.solvers.least_squares import forward_mode, least_squares_run
from jaxrod.stored import StoredProgram

LOG_E_RANGE = (math.log(1e9), math.log(1e13))


@jax.tree_util.register_dataclass
@dataclasses.dataclass(frozen=True)
class FitSetup:
    """The experiment that ``fit_youngs_modulus`` models: G and M at the reference modulus
    E_ref (both scale as 1/E) and the track ratio D (default: the paper's permanent-magnet
    rig, ``setup_from_preset``). Paper: Corollary ``cor:permanent_physical_parameters``."""

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
    return angles_from_folds(alphas, params[1]), converged


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
    return angles_from_folds(alphas, params[1]), (z_new, ok)


def _fit_core(measured, mask, sigma, fit_offset, setup: FitSetup, log_e0, max_iter: int = 40,
              gtol: float = 1e-9):
    """Minimise 0.5 |r(p)|^2 over p = (log E, delta) (``least_squares_run``); the fold model
    is evaluated from the fold states of the last accepted point (module docstring)."""
    offset_free = jnp.asarray(fit_offset, jnp.float64)
    free = jnp.stack([jnp.ones(()), offset_free])
    disc = planar_discretisation(FIT_N, "clamped")
    start = _scene(jnp.asarray(log_e0, jnp.float64), setup)
    z0, found = start_states(start, disc)
    target = jnp.where(mask, measured, 0.0)

    def residuals(p, z):
        model, (z_new, ok) = tracked_angles(p, z, setup, disc)
        in_range = (p[0] > LOG_E_RANGE[0]) & (p[0] < LOG_E_RANGE[1])
        return jnp.where(mask, (model - target) / sigma, 0.0), z_new, ok & in_range

    res = least_squares_run(forward_mode(residuals), jnp.array([log_e0, 0.0]), z0, free, 4,
                            found, max_iter, gtol)
    cov = res.covariance(free)
    return res.p, res.r * sigma, jnp.sqrt(cov[0, 0]), jnp.sqrt(cov[1, 1]) * offset_free, \
        res.ok & found, res.iterations, res.grad_norm, res.converged


_fit_jit = StoredProgram("fit", _fit_core, static_argnames=("max_iter",))
_fit_batch_jit = jit(jax.vmap(_fit_core, in_axes=(0, 0, None, None, None, None)))


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

    Model: the four angles (capture and release, both directions) from the folds of
    Proposition ``thm:planar_fold`` plus the offset. Paper: Corollary
    ``cor:permanent_physical_parameters``.
    """
    measured, mask = _parse(measured, sigma_deg)
    if fit_offset and mask.sum() < 2:
        raise ParameterError("angles: fitting the offset needs at least two angles")
    check("E", E0)
    setup = setup or setup_from_preset()
    out = _fit_jit(
        jnp.asarray(np.nan_to_num(measured)), jnp.asarray(mask), float(sigma_deg),
        bool(fit_offset), setup, math.log(E0))
    return _result(*out, mask, sigma_deg, fit_offset, measured)


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

    Paper: Corollary ``cor:permanent_physical_parameters`` (one fit per row).
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
    return [_result(*(v[i] for v in out), np.asarray(mask[i]), sigma_deg, fit_offset,
                    rows[i][0]) for i in range(m.shape[0])]


def _result(p, res, std_log_e, std_off, ok, k, gnorm, settled, mask, sigma_deg,
            fit_offset, measured=None) -> FitResult:
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
    hint = sign_hint(np.nan_to_num(measured), mask) if measured is not None else None
    if hint is not None:
        warning = hint if warning is None else f"{warning}; {hint}"
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
    return np.asarray(_loss_profile_program(
        np.log(np.asarray(E_values, np.float64)), np.nan_to_num(measured), mask,
        float(sigma_deg), bool(fit_offset), setup))


@jit
def _loss_profile_program(log_e, measured, mask, sigma_deg, fit_offset, setup):
    """``loss_profile`` at each log E (one program for every grid of the same length)."""

    def at(log_e):
        model, ok = model_angles(jnp.array([log_e, 0.0]), setup)
        d = jnp.where(mask, measured - model, 0.0)
        delta = jnp.where(fit_offset, jnp.sum(d) / jnp.sum(mask), 0.0)
        r = jnp.where(mask, (d - delta) / sigma_deg, 0.0)
        return jnp.where(ok, 0.5 * jnp.sum(r**2), jnp.nan)

    return jax.vmap(at)(log_e)
