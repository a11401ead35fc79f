"""Fits and designs on any scene: the inputs whose folds sit at measured (or target) values.

The data are the folds met along one input v (``vary``) over a range, in the order met
(``jaxrod.equilibria.folds``): measured switching values (the field angle where a robot
snaps, the rail position where a wire is captured), NaN where one was not measured. The free
inputs p (any scalar inputs of the scene, by key) minimise

    0.5 sum_i ((f_i(p) - m_i) / sigma)^2,

f_i(p) the i-th fold's value, by the least-squares program of ``jaxrod.solvers.least_squares``
(optax L-BFGS direction, Armijo line search, Gauss-Newton scaling). Each evaluation solves
each fold's Moore-Spence system from the fold states of the last accepted point, implicitly
differentiated in p (``differentiable_fold``); a trial point where a solve fails, a fold
leaves the range or the folds change their order, or p leaves its bounds, is rejected. The
start's folds come from ``jaxrod.equilibria.folds`` (the branch from the ramped equilibrium).
The standard deviations follow from the Gauss-Newton covariance sigma^2 (J^T J)^-1 at the
answer. A design is the same fit with the targets as data (``design_folds``).
"""

from __future__ import annotations

import dataclasses
import math

import jax
import jax.numpy as jnp
import numpy as np

from jaxrod.equilibria.equilibrium import DEFAULT_N, discretise
from jaxrod.equilibria.folds import folds as scene_folds
from jaxrod.equilibria.trace import MODEL, check_range
from jaxrod.params import ParameterError
from jaxrod.programs import jit
from jaxrod.scenes.files import FileScene
from jaxrod.scenes.path import along
from jaxrod.scenes.scene import Scene
from jaxrod.solvers.folds import differentiable_fold
from jaxrod.solvers.least_squares import forward_mode, least_squares_run
from jaxrod.status import Status


@dataclasses.dataclass(frozen=True)
class SceneFit:
    """The answer of ``fit_folds`` / ``design_folds``.

    ``estimates`` and ``std`` (one standard deviation from the Gauss-Newton covariance, in
    the inputs' units; None for a design) by key; ``folds``: the model's fold values at the
    answer, in the order met; ``residuals``: folds - data (None where no datum);
    ``converged``, ``iterations``, ``status`` (a ``jaxrod.Status``) and ``reason``.
    """

    free: tuple[str, ...]
    estimates: dict
    std: dict | None
    folds: list
    residuals: list
    chi2: float
    converged: bool
    iterations: int
    status: Status
    reason: str | None

    def as_dict(self) -> dict:
        return {"free": list(self.free), "estimates": self.estimates, "std": self.std,
                "folds": self.folds, "residuals": self.residuals, "chi2": self.chi2,
                "converged": self.converged, "iterations": self.iterations,
                "status": self.status.name.lower(), "reason": self.reason}


def _program(path, disc, origin, span, z0, p0, data, mask, sigma, lower, upper, max_iter):
    model = MODEL
    m = disc.size

    def residuals(p, z):
        args = (path, disc, origin, span, p)
        z_new, stats = jax.vmap(lambda zi: differentiable_fold(
            model, zi[:m], zi[-1], zi[m:2 * m], args))(z)
        lam = z_new[:, -1]
        ok = jnp.all(stats[:, 0] == 1.0) & jnp.all((lam >= -1e-9) & (lam <= 1.0 + 1e-9)) \
            & jnp.all(jnp.diff(lam) * jnp.sign(jnp.diff(z[:, -1])) > 0.0) \
            & jnp.all((p >= lower) & (p <= upper))
        values = origin + span * lam
        r = jnp.where(mask, (values - data) / sigma, 0.0)
        return r, z_new, ok

    free_mask = jnp.ones(p0.shape[0], bool)
    res = least_squares_run(forward_mode(residuals), p0, z0, free_mask, data.shape[0], True,
                            max_iter)
    return res, origin + span * res.aux[:, -1], res.covariance(free_mask)


_fit_program = jit(_program, static_argnames=("max_iter",))


def fit_folds(scene: Scene | FileScene, vary: str, vary_range: tuple[float, float], measured,
              free, sigma: float = 1.0, bounds: dict | None = None, n: int = DEFAULT_N,
              max_iter: int = 60, design: bool = False) -> SceneFit:
    """Fit the inputs ``free`` (scene keys) so that the folds met along ``vary`` over
    ``vary_range`` sit at ``measured`` (in the order met; NaN where not measured), each with
    standard deviation ``sigma`` (module docstring). ``bounds``: key -> (lo, hi) (default
    unbounded); the scene's values of the free inputs are the start.
    """
    start, stop = check_range(scene, vary, *vary_range)
    free = tuple(free)
    if not free:
        raise ParameterError("free: name at least one input to fit")
    for key in free:
        if key == vary:
            raise ParameterError(f"free: {key} is the input the folds are met along")
    if len(set(free)) != len(free):
        raise ParameterError(f"free: an input is named twice in {', '.join(free)}")
    data = np.asarray(measured, float).reshape(-1)
    mask = ~np.isnan(data)
    if not mask.any():
        raise ParameterError("measured: at least one fold value is needed")
    if not (math.isfinite(sigma) and sigma > 0):
        raise ParameterError(f"sigma must be a finite number > 0, got {sigma!r}")
    bounds = dict(bounds or {})
    for key in bounds:
        if key not in free:
            raise ParameterError(f"bounds: {key!r} is not a free input ({', '.join(free)})")
    lower = np.array([bounds.get(k, (-np.inf, np.inf))[0] for k in free], float)
    upper = np.array([bounds.get(k, (-np.inf, np.inf))[1] for k in free], float)
    path = along(scene, (vary, *free))
    p0 = np.array(path.start[1:])
    if np.any((p0 < lower) | (p0 > upper)):
        raise ParameterError("bounds: the scene's values of the free inputs (the start) lie "
                             "outside the bounds")
    found = scene_folds(scene, vary, start, stop, n, throw=False)
    if len(found) < data.size or not all(f.converged for f in found[:data.size]):
        raise ParameterError(f"the start has {len(found)} fold(s) along {vary} from "
                             f"{start:g} to {stop:g}; {data.size} value(s) were given: start "
                             "nearer the answer, or widen the range")
    span = stop - start
    z0 = np.stack([np.concatenate([f.state, f.null_vector, [(f.value - start) / span]])
                   for f in found[:data.size]])
    disc = discretise(path.template, n)
    res, values, cov = jax.device_get(_fit_program(
        path, disc, start, span, jnp.asarray(z0), jnp.asarray(p0),
        jnp.asarray(np.nan_to_num(data)), jnp.asarray(mask), float(sigma),
        jnp.asarray(lower), jnp.asarray(upper), max_iter))
    ok, settled = bool(res.ok), bool(res.converged)
    reasons = []
    if not ok:
        reasons.append("the fold model failed at the last point (a solve did not converge, "
                       "or a fold left the range)")
    if not settled:
        reasons.append(f"the gradient did not vanish (|grad| = {float(res.grad_norm):.2e}) "
                       f"within {int(res.iterations)} iterations")
    std = None if design else {k: float(math.sqrt(max(cov[j, j], 0.0)))
                               for j, k in enumerate(free)}
    values = [float(v) for v in values]
    residuals = [float(v - d) if mk else None for v, d, mk in zip(values, data, mask)]
    return SceneFit(free=free, estimates={k: float(v) for k, v in zip(free, res.p)}, std=std,
                    folds=values, residuals=residuals,
                    chi2=float(np.dot(res.r, res.r)), converged=not reasons,
                    iterations=int(res.iterations),
                    status=Status.of(not reasons),
                    reason="; ".join(reasons) or None)


def design_folds(scene: Scene | FileScene, vary: str, vary_range: tuple[float, float],
                 targets, free, bounds: dict | None = None, n: int = DEFAULT_N) -> SceneFit:
    """The inputs ``free`` whose folds along ``vary`` sit at ``targets`` (in the order met):
    ``fit_folds`` with the targets as data; converged means the targets are hit to 1e-9 of
    the range."""
    out = fit_folds(scene, vary, vary_range, targets, free, 1.0, bounds, n, design=True)
    start, stop = check_range(scene, vary, *vary_range)
    miss = max(abs(r) for r in out.residuals if r is not None)
    if out.converged and miss > 1e-9 * abs(stop - start):
        return dataclasses.replace(out, converged=False, status=Status.NOT_CONVERGED,
                                   reason=f"the folds miss the targets by {miss:.3g}: no "
                                   "design of these inputs hits them (within the bounds)")
    return out
