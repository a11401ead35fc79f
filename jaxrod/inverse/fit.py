"""Calibration on measured switching angles: any subset of the physical inputs and the
track's angular offset, with Gaussian priors and bounds (``fit``); the Laplace covariance,
correlations and chi^2 of the estimates, the identifiability of the free inputs from the
Fisher information of the angles (``Calibration``), and profile likelihoods (``profile``).

The model is the calibration program of ``jaxrod.inverse.calibration`` (the folds of the
planar branch as functions of the physical inputs, tracked by Moore-Spence and
differentiated implicitly); the one-parameter fit of Young's modulus alone is
``jaxrod.inverse.youngs``.
"""

from __future__ import annotations

import dataclasses
import math

import jax
import jax.numpy as jnp
import numpy as np

from jaxrod.design_point import DesignPoint, range_of
from jaxrod.inverse.calibration import (
    MODEL_N,
    OFFSET,
    Problem,
    angles_from_folds,
    parameter_names,
    parse_angles,
    physical_parameters,
    sign_hint,
    solve_batch,
    solve_program,
)
from jaxrod.magnet.folds import fold_angles
from jaxrod.params import (
    NDFEB_MAGNET,
    PHYSICAL_NAMES,
    UNITS,
    ParameterError,
    check_value,
    preset,
)
from jaxrod.progress import Interrupted, progress_bar

# --- several parameters: calibration of the experiment on physical inputs -------------------

#: The inputs a calibration may free: every physical input, and the track's angular offset.
FREE_NAMES = PHYSICAL_NAMES + (OFFSET,)
#: Default bounds of the offset, degrees.
OFFSET_BOUNDS = (-45.0, 45.0)
#: A parameter whose standard deviation (relative, or degrees for the offset) exceeds this
#: is reported without one: the data and priors do not fix it.
MEANINGLESS_STD = {"relative": 1.0, "offset": 45.0}
#: A Fisher eigenvalue below this fraction of the largest marks a combination of the free
#: parameters that the angles cannot tell apart.
FISHER_RANK_TOL = 1e-9


@dataclasses.dataclass(frozen=True)
class Prior:
    """A Gaussian prior, in the parameter's own units (the offset in degrees)."""

    mean: float
    sd: float

    def __post_init__(self):
        object.__setattr__(self, "mean", check_value("prior mean", self.mean,
                                                     lambda x: True, "a finite number"))
        object.__setattr__(self, "sd", check_value("prior sd", self.sd, lambda x: x > 0.0,
                                                   "a finite number > 0"))


def _problem(point: DesignPoint, measured, mask, sigma_deg, free, priors, bounds, p_start=None):
    """The arrays of a calibration or design (``jaxrod.inverse.calibration.Problem``)."""
    names = parameter_names(point.kind)
    k = len(names)
    free_mask = np.zeros(k, bool)
    for name in free:
        free_mask[names.index(name)] = True
    mean, sd, has = np.zeros(k), np.ones(k), np.zeros(k, bool)
    for name, prior in priors.items():
        i = names.index(name)
        mean[i], sd[i], has[i] = prior.mean, prior.sd, True
    lower, upper = np.empty(k), np.empty(k)
    for i, name in enumerate(names):
        lo, hi = bounds.get(name, OFFSET_BOUNDS if name == OFFSET else
                            (range_of(name).low, range_of(name).high))
        lower[i], upper[i] = lo, hi
    return Problem(
        v0=jnp.asarray(point.values, jnp.float64), radius=jnp.asarray(point.radius()),
        measured=jnp.asarray(np.nan_to_num(measured)), mask=jnp.asarray(mask),
        sigma=jnp.asarray(float(sigma_deg)), free=jnp.asarray(free_mask),
        prior_mean=jnp.asarray(mean), prior_sd=jnp.asarray(sd), has_prior=jnp.asarray(has),
        lower=jnp.asarray(lower), upper=jnp.asarray(upper),
        p_start=jnp.zeros(k) if p_start is None else jnp.asarray(p_start, jnp.float64))


def _check_names(names, allowed, what: str) -> tuple[str, ...]:
    names = tuple(names)
    unknown = [n for n in names if n not in allowed]
    if unknown:
        raise ParameterError(f"{what}: unknown parameter {', '.join(map(repr, unknown))}; "
                             f"choose from {', '.join(allowed)}")
    if len(set(names)) != len(names):
        raise ParameterError(f"{what}: a parameter is named twice in {', '.join(names)}")
    return names


def _check_bounds(bounds: dict, point: DesignPoint) -> dict:
    names = parameter_names(point.kind)
    _check_names(bounds, names, "bounds")
    out = {}
    for name, (lo, hi) in bounds.items():
        lo = check_value(f"bounds {name} (lower)", lo, lambda x: True, "a finite number")
        hi = check_value(f"bounds {name} (upper)", hi, lambda x: x > lo,
                         f"a finite number above the lower bound {lo:g}")
        out[name] = (lo, hi)
    return out


@dataclasses.dataclass(frozen=True)
class Calibration:
    """The result of ``fit``: estimates and what the data say about them.

    ``estimates``, ``std`` (one standard deviation from the Laplace (Gauss-Newton)
    covariance; None where the data and priors do not fix the parameter) and ``units`` by
    parameter name; ``correlation`` between the free parameters (in ``free`` order);
    ``residuals_deg`` (model - measured; None where not measured); ``chi2`` (angles and
    priors), ``dof`` (measured angles + priors on free parameters - free parameters) and
    ``reduced_chi2``; ``identifiability``: the Fisher information of the angles alone in
    the relative coordinates d(log value) (offset: degrees), one entry per eigenvector with
    its standard deviation and whether the angles fix it; ``warnings``.
    """

    free: tuple[str, ...]
    estimates: dict
    std: dict
    units: dict
    correlation: np.ndarray
    covariance_relative: np.ndarray
    residuals_deg: list
    model_deg: list
    chi2: float
    dof: int
    reduced_chi2: float | None
    identifiability: list
    converged: bool
    iterations: int
    reason: str | None
    warnings: list
    sigma_deg: float
    priors: dict

    def as_dict(self) -> dict:
        return {"free": list(self.free), "estimates": self.estimates, "std": self.std,
                "units": self.units, "correlation": self.correlation.tolist(),
                "residuals_deg": self.residuals_deg, "model_deg": self.model_deg,
                "chi2": self.chi2, "dof": self.dof, "reduced_chi2": self.reduced_chi2,
                "identifiability": self.identifiability, "converged": self.converged,
                "iterations": self.iterations, "reason": self.reason,
                "warnings": self.warnings, "sigma_deg": self.sigma_deg,
                "priors": {k: {"mean": v.mean, "sd": v.sd} for k, v in self.priors.items()}}


def default_point() -> DesignPoint:
    """The paper's permanent-magnet experiment (nickel wire, NdFeB magnet), physical."""
    rod, _ = preset("permanent-magnet")
    return DesignPoint.from_physical(rod, NDFEB_MAGNET)


def fit(measured, free=("E", OFFSET), point: DesignPoint | None = None,
        priors: dict | None = None, sigma_deg: float = 1.0, bounds: dict | None = None,
        start: dict | None = None) -> Calibration:
    """Fit any subset of the physical inputs and the offset to measured switching angles.

    ``measured``: the four angles in ``ANGLE_NAMES`` order (degrees; nan where not
    measured). ``free``: the names that vary (``FREE_NAMES``); the others stay at
    ``point``'s values (default: the paper's experiment, ``default_point``). ``priors``:
    name -> ``Prior`` (a Gaussian in the parameter's units). ``bounds``: name -> (lo, hi)
    (default: the valid ranges, offset within +-45 degrees). ``start``: name -> starting
    value of a free parameter (default: the point's value, offset 0). One compiled program
    serves every choice of these (``jaxrod.inverse.calibration``).
    """
    prepared = _prepare(measured, free, point, priors, sigma_deg, bounds, start)
    return _calibration(*prepared, solve_program(prepared[0].kind, prepared[1]))


def fit_batch(measured, free=("E", OFFSET), point: DesignPoint | None = None,
              priors: dict | None = None, sigma_deg: float = 1.0, bounds: dict | None = None,
              start: dict | None = None, method: str = "auto",
              progress: bool = False) -> list[Calibration]:
    """``fit`` of each row of ``measured`` (K, 4), the other inputs shared.

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
            rows.append(_prepare(m, free, point, priors, sigma_deg, bounds, start))
        except ParameterError as err:
            raise ParameterError(f"row {i}: {err}") from None
    if method == "auto":
        method = "vmap" if jax.default_backend() == "gpu" else "loop"
    if method not in ("vmap", "loop"):
        raise ParameterError(f"method must be 'auto', 'vmap' or 'loop', got {method!r}")
    if method == "loop":
        out = []
        bar = progress_bar(len(rows), "fits", "fit", progress)
        try:
            for prepared in rows:
                out.append(_calibration(*prepared, solve_program(prepared[0].kind,
                                                                 prepared[1])))
                bar.update(1)
        except KeyboardInterrupt:
            raise Interrupted(out, f"after {len(out)} of {len(rows)} fits") from None
        finally:
            bar.close()
        return out
    kind = rows[0][0].kind
    problems = jax.tree.map(lambda *a: jnp.stack(a), *(r[1] for r in rows))
    solutions = solve_batch(kind, problems)
    return [_calibration(*r, jax.tree.map(lambda a, i=i: a[i], solutions))
            for i, r in enumerate(rows)]


def _prepare(measured, free, point, priors, sigma_deg, bounds, start):
    """Validate a fit's inputs: (point, problem, free, priors, mask, rows of r)."""
    measured, mask = parse_angles(measured, sigma_deg)
    point = point or default_point()
    if point.kind != "physical":
        raise ParameterError("point: a calibration needs a physical design point (the "
                             "groups carry no physical inputs to fit)")
    free = _check_names(free, FREE_NAMES, "free")
    if not free:
        raise ParameterError("free: name at least one parameter to fit")
    priors = dict(priors or {})
    _check_names(priors, FREE_NAMES, "prior")
    for name, prior in priors.items():
        if not isinstance(prior, Prior):
            raise ParameterError(f"prior {name}: must be a Prior(mean, sd), got {prior!r:.60}")
        if name != OFFSET:
            range_of(name).check(prior.mean)
    fixed = [name for name in priors if name not in free]
    if fixed:
        raise ParameterError(f"prior {fixed[0]}: {fixed[0]} is not free (free: "
                             f"{', '.join(free)}); a prior acts on a fitted input only: add "
                             "it to the free inputs, or drop the prior")
    bounds = _check_bounds(dict(bounds or {}), point)
    p_start = _start_vector(point, start or {}, free)
    n_data = int(mask.sum())
    n_priors = sum(1 for name in priors if name in free)
    problem = _problem(point, measured, mask, sigma_deg, free, priors, bounds, p_start)
    return point, problem, free, priors, mask, n_data + n_priors




def _start_vector(point: DesignPoint, start: dict, free) -> np.ndarray:
    names = parameter_names(point.kind)
    p = np.zeros(len(names))
    for name, value in start.items():
        if name not in free:
            raise ParameterError(f"start: {name!r} is not a free parameter")
        i = names.index(name)
        if name == OFFSET:
            p[i] = check_value("start offset", value, lambda x: True, "a finite number")
        else:
            p[i] = math.log(range_of(name).check(value) / point.values[i])
    return p


def _calibration(point, problem, free, priors, mask, n_rows, solution) -> Calibration:
    names = parameter_names(point.kind)
    idx = [names.index(n) for n in free]
    res = jax.device_get(solution.result)
    q = np.asarray(physical_parameters(problem, jnp.asarray(res.p)))
    J = np.asarray(res.J)[:, idx]
    r = np.asarray(res.r)
    # the Laplace covariance over the directions that the angles and priors fix; a
    # parameter that loads on a direction they leave free gets no standard deviation
    lam, V = np.linalg.eigh(J.T @ J)
    fixed = lam > FISHER_RANK_TOL * max(float(lam[-1]), 1e-300)
    cov = (V[:, fixed] / lam[fixed]) @ V[:, fixed].T
    loose = np.sum(V[:, ~fixed] ** 2, axis=1) > 1e-4
    sd_rel = np.where(loose, np.inf, np.sqrt(np.abs(np.diag(cov))))
    estimates, std, units = {}, {}, {}
    warnings = []
    for j, (name, i) in enumerate(zip(free, idx)):
        estimates[name] = float(q[i])
        units[name] = "deg" if name == OFFSET else UNITS[name]
        limit = MEANINGLESS_STD["offset" if name == OFFSET else "relative"]
        if not np.isfinite(sd_rel[j]) or sd_rel[j] > limit:
            std[name] = None
            warnings.append(f"{name} is not fixed by these angles and priors (its "
                            "standard deviation would exceed "
                            f"{'45 degrees' if name == OFFSET else 'its own value'}): "
                            "give it a prior, fix it, or measure more")
        else:
            std[name] = float(sd_rel[j] if name == OFFSET else sd_rel[j] * q[i])
    with np.errstate(all="ignore"):
        corr = cov / np.outer(sd_rel, sd_rel)
    identifiability = _identifiability(J[:4], free)
    for entry in identifiability:
        if not entry["fixed_by_angles"]:
            warnings.append("the angles cannot tell apart the combination "
                            f"{entry['combination_text']}")
    sigma = float(problem.sigma)
    residuals = [float(v * sigma) if m else None for v, m in zip(r[:4], mask)]
    chi2 = float(np.dot(r, r)) if bool(solution.found) else math.nan
    dof = n_rows - len(free)
    reduced = chi2 / dof if dof > 0 else None
    if reduced is not None and reduced > 9.0:
        warnings.append(f"the residuals exceed sigma = {sigma:g} deg (reduced chi^2 = "
                        f"{reduced:.3g}): the model does not explain the angles within the "
                        "assumed error")
    hint = sign_hint(np.asarray(problem.measured), mask)
    if hint is not None:
        warnings.append(hint)
    reasons = []
    if not bool(solution.found):
        reasons.append("the start has no two folds (no hysteresis there) or lies outside "
                       "the valid ranges")
    elif not bool(res.ok):
        reasons.append("the fold model failed at the final point")
    if bool(solution.found) and not bool(res.converged):
        reasons.append(f"the gradient did not vanish (|grad| = {float(res.grad_norm):.2e}) "
                       f"within {int(res.iterations)} iterations")
    model = np.asarray(solution.angles)
    return Calibration(
        free=tuple(free), estimates=estimates, std=std, units=units, correlation=corr,
        covariance_relative=cov, residuals_deg=residuals,
        model_deg=[float(v) for v in model], chi2=chi2, dof=dof, reduced_chi2=reduced,
        identifiability=identifiability, converged=not reasons,
        iterations=int(res.iterations), reason="; ".join(reasons) or None,
        warnings=warnings, sigma_deg=sigma, priors=priors)


def _identifiability(J_angles: np.ndarray, free) -> list:
    """Eigenvectors of the angles' Fisher information J^T J in relative coordinates."""
    lam, V = np.linalg.eigh(J_angles.T @ J_angles)
    top = max(float(lam[-1]), 1e-300)
    out = []
    for k in range(len(lam) - 1, -1, -1):
        v = V[:, k] / np.max(np.abs(V[:, k])) * np.sign(V[np.argmax(np.abs(V[:, k])), k])
        terms = {name: float(c) for name, c in zip(free, v) if abs(c) > 0.05}
        text = " ".join(f"{c:+.3g} {'offset' if n == OFFSET else 'log ' + n}"
                        for n, c in terms.items())
        offset_only = set(terms) == {OFFSET}
        limit = MEANINGLESS_STD["offset" if offset_only else "relative"]
        fixed = bool(lam[k] > FISHER_RANK_TOL * top) and 1.0 / math.sqrt(lam[k]) <= limit
        out.append({"eigenvalue": float(lam[k]), "fixed_by_angles": fixed,
                    "std": float(1.0 / math.sqrt(lam[k])) if lam[k] > 0 else None,
                    "combination": terms, "combination_text": text})
    return out


def profile(measured, name: str, free=("E", OFFSET), point: DesignPoint | None = None,
            priors: dict | None = None, sigma_deg: float = 1.0, values=None,
            count: int = 15, span: float = 3.0, fitted: Calibration | None = None) -> dict:
    """The profile likelihood of one free parameter: chi^2 minimised over the others at each
    of ``values`` (default: ``count`` values within ``span`` standard deviations of the
    estimate), with the Laplace (quadratic) approximation beside it.

    Paper: the fit of Corollary ``cor:permanent_physical_parameters`` (Young's modulus from
    the switching angles).
    """
    free = _check_names(free, FREE_NAMES, "free")
    if name not in free:
        raise ParameterError(f"profile: {name!r} is not a free parameter ({', '.join(free)})")
    point = point or default_point()
    best = fitted or fit(measured, free, point, priors, sigma_deg)
    centre, sd = best.estimates[name], best.std[name]
    if values is None:
        half = span * sd if sd is not None else 0.3 * abs(centre) + (5.0 if name == OFFSET
                                                                     else 0.0)
        values = np.linspace(centre - half, centre + half, count)
    others = tuple(n for n in free if n != name)
    chi2, converged = [], []
    for v in np.asarray(values, float):
        fixed_point = point.replace(name, v) if name != OFFSET else point
        start = {n: best.estimates[n] for n in others}
        if name == OFFSET:
            # the offset fixed at v: a calibration with the offset as a start, not free
            cal = _fit_fixed_offset(measured, others, fixed_point, priors, sigma_deg, v, start)
        elif others:
            cal = fit(measured, others, fixed_point, {k: p for k, p in (priors or {}).items()
                                                      if k in others}, sigma_deg, start=start)
        else:
            cal = None
        if cal is None:
            chi2.append(_chi2_at(measured, fixed_point, sigma_deg))
            converged.append(True)
        else:
            prior = (priors or {}).get(name)
            extra = ((v - prior.mean) / prior.sd) ** 2 if prior is not None else 0.0
            chi2.append(cal.chi2 + extra if cal.converged else math.nan)
            converged.append(cal.converged)
    laplace = (None if sd is None else
               (best.chi2 + ((np.asarray(values) - centre) / sd) ** 2).tolist())
    return {"name": name, "values": [float(v) for v in values], "chi2": chi2,
            "converged": converged, "laplace_chi2": laplace, "estimate": centre, "std": sd,
            "chi2_min": best.chi2}


def _fit_fixed_offset(measured, others, point, priors, sigma_deg, offset, start):
    shifted = np.asarray(measured, float) - offset
    if not others:
        return None
    return fit(shifted, others, point, {k: p for k, p in (priors or {}).items()
                                        if k in others}, sigma_deg, start=start)


def _chi2_at(measured, point: DesignPoint, sigma_deg) -> float:
    G, M, D = point.groups()
    alphas, ok = fold_angles(G, M, D, n=MODEL_N)
    model = np.asarray(angles_from_folds(alphas, 0.0))
    m, mask = parse_angles(measured, sigma_deg)
    return float(np.sum(((model - m)[mask] / sigma_deg) ** 2)) if bool(ok) else math.nan
