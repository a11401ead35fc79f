"""Fits of a twisted rod's inputs to measured folds, by the folds' exact sensitivities.

A fold of the branch along an input v (the turns, say) moves with any other input p (the
shortening, the tension, the twist ratio, a load's), with the exact derivative dv_fold / dp
from the fold's null vector (``jaxrod.twisted.folds.fold_sensitivity``).

The fit (``fit_twist_folds``) minimises chi^2 = sum_i ((v_i(p) - m_i) / sigma)^2 over the
free inputs p by Levenberg-Marquardt steps (Gauss-Newton first, damped when a step does
not lower chi^2), the folds v_i at each p those met along v over the range, in order; each
evaluation continues the branch again from the start of the range, from the last accepted
start. The record is ``jaxrod.inverse.fit_record.SceneFit``: the Laplace covariance, the
identifiability and the warnings of the planar rigs' fits.
"""

from __future__ import annotations

import dataclasses
import math
import types

import numpy as np

from jaxrod.inverse.fit_record import SceneFit, record
from jaxrod.params import ParameterError
from jaxrod.status import Status
from jaxrod.twisted.branch import folds_along
from jaxrod.twisted.folds import fold_sensitivity
from jaxrod.twisted.rod import TwistedRod

__all__ = ["fit_twist_folds"]


@dataclasses.dataclass
class _Evaluation:
    folds: list
    start: object


def _folds_at(rod: TwistedRod, vary: str, vary_range, turns: float, free, p, count: int,
              start, options: dict) -> _Evaluation:
    """The folds along ``vary`` over ``vary_range`` with the free inputs at p
    (``folds_along``), continued from ``start``."""
    for key, v in zip(free, p):
        if key == "turns":
            turns = float(v)
        else:
            rod = rod.replace(key, float(v))
    folds, first, _ = folds_along(rod, vary, vary_range, turns, count, start, **options)
    return _Evaluation(folds, first if first is not None and first.converged else None)


def fit_twist_folds(rod: TwistedRod, vary: str, vary_range: tuple[float, float], measured,
                    free, sigma: float = 1.0, bounds: dict | None = None, *,
                    turns: float = 0.0, start=None, max_iter: int = 30, **options
                    ) -> SceneFit:
    """Fit the inputs ``free`` (keys of the rod: "tension" or "shortening" (its control),
    "twist_ratio", "bending_ratio", "load_scale", a load's "term.field[.i]", or "turns"
    where ``vary`` is another input) so that the folds met along ``vary`` from
    ``vary_range[0]`` to ``vary_range[1]`` sit at ``measured`` (in order; NaN: not
    measured), each with standard deviation ``sigma`` (module docstring). ``turns``: the
    far end's rotation where ``vary`` is not the turns; ``start``: a state at the range's
    start of a nearby rod (the first evaluation's start is solved from it by Newton; None:
    by the rod's own path); ``bounds``: key -> (lo, hi);
    ``options`` go to each ``twist_branch`` (``ds_max``, ...). The rod's values are the
    start."""
    measured = np.atleast_1d(np.asarray(measured, float))
    mask = ~np.isnan(measured)
    free = tuple(free)
    if not mask.any() or np.any(np.isinf(measured)):
        raise ParameterError("measured: finite fold values (NaN: not measured), at least one")
    if not free or len(set(free)) != len(free) or vary in free:
        raise ParameterError(f"free: distinct inputs other than {vary!r}, got {list(free)}")
    if not (math.isfinite(sigma) and sigma > 0):
        raise ParameterError(f"sigma: a finite number > 0, got {sigma!r}")
    p = np.array([float(turns) if k == "turns" else rod.value(k) for k in free])
    bounds = dict(bounds or {})
    lo = np.array([bounds.get(k, (-np.inf, np.inf))[0] for k in free])
    hi = np.array([bounds.get(k, (-np.inf, np.inf))[1] for k in free])
    if np.any(p < lo) or np.any(p > hi):
        raise ParameterError("bounds: the rod's values (the start) lie outside them")
    count = len(measured)

    def evaluate(p, start):
        try:
            ev = _folds_at(rod, vary, vary_range, turns, free, p, count, start, options)
        except (ParameterError, ArithmeticError):
            return None
        if len(ev.folds) < count or not all(f.converged for f in ev.folds[:count]):
            return None  # a fold missing or not refined: the data would be misread
        values = np.array([f.value for f in ev.folds[:count]])
        r = np.where(mask, (values - np.nan_to_num(measured)) / sigma, 0.0)
        return ev, values, r

    at = evaluate(p, start)
    if at is None:
        raise ParameterError(f"measured: the branch along {vary} over {list(vary_range)} "
                             f"meets fewer than {count} folds at the start")
    ev, values, r = at
    J = _jacobian(ev, vary, free, mask, sigma)
    damping, iterations, converged, reason = 0.0, 0, False, None
    while iterations < max_iter and not converged:
        iterations += 1
        A, g = J.T @ J, J.T @ r
        scale = np.maximum(np.diag(A), 1e-300)
        try:
            newton = np.clip(p - np.linalg.solve(A, g), lo, hi)
            step = -np.linalg.solve(A + damping * np.diag(scale), g)
        except np.linalg.LinAlgError:
            reason = "the data do not fix the free inputs (a singular Gauss-Newton matrix)"
            break
        if np.all(np.abs(newton - p) <= 1e-9 * np.maximum(np.abs(p), 1e-12)):
            converged = True  # at the minimum: the Gauss-Newton step below the folds'
            break             # own accuracy
        trial = np.clip(p + step, lo, hi)
        new = evaluate(trial, ev.start)
        if new is None or np.dot(new[2], new[2]) > np.dot(r, r):
            damping = max(4.0 * damping, 1e-3)
            if damping > 1e8:
                reason = "no step lowers chi^2 (the folds fail or leave the range nearby)"
                break
            continue
        p, (ev, values, r) = trial, new
        J = _jacobian(ev, vary, free, mask, sigma)
        damping /= 3.0
        converged = float(np.dot(r, r)) <= 1e-24
    if not converged and reason is None:
        reason = f"not converged within {max_iter} iterations"
    resolved = all(f.state.status == Status.SUCCESS for f in ev.folds[:count])
    return _record(free, p, J, r, values, measured, mask, sigma, vary_range,
                   converged and resolved, iterations, reason, resolved)


def _jacobian(ev: _Evaluation, vary, free, mask, sigma) -> np.ndarray:
    """d(residual_i)/dp_j: the folds' sensitivities over sigma, zero where not measured."""
    rows = [fold_sensitivity(f, vary, free) / sigma for f in ev.folds[:len(mask)]]
    return np.where(mask[:, None], np.array(rows), 0.0)


def _record(free, p, J, r, values, measured, mask, sigma, vary_range, converged,
            iterations, reason, resolved) -> SceneFit:
    """The fit's ``SceneFit`` (``jaxrod.inverse.fit_record.record``: its covariance,
    identifiability and warnings); its status UNDER_RESOLVED where a fold is."""
    count = len(measured)
    problem = types.SimpleNamespace(
        keys=free, free=free, data=measured, mask=mask, n_data=int(mask.sum()), n_priors=0,
        span_abs=abs(vary_range[1] - vary_range[0]), priors={},
        arrays={"sigma": sigma, "weights": np.eye(count), "shifted": np.zeros(count)})
    res = types.SimpleNamespace(
        p=np.append(p, 0.0), J=np.column_stack([J, np.zeros(count)]), r=r, ok=True,
        converged=converged, grad_norm=float(np.linalg.norm(J.T @ r)),
        iterations=iterations)
    fit = record(problem, res, values, design=False)
    reasons = [x for x in (reason, None if resolved else
                           "a fold is under-resolved (its Chebyshev tail above 1e-8: raise "
                           "n, or gather the grid with layer_width)") if x]
    status = Status.of(converged) if resolved else Status.UNDER_RESOLVED
    return dataclasses.replace(fit, converged=converged, status=status,
                               reason="; ".join(reasons) or None)
