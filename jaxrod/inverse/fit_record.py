"""The record of a fit of folds (``jaxrod.inverse.scene_fit``) and what the data say about
its inputs.

The Laplace (Gauss-Newton) covariance (J^T J)^-1 of the free inputs is taken over the
directions the data and priors fix (the eigenvectors of J^T J above ``FISHER_RANK_TOL`` of
the largest eigenvalue); an input that loads on a direction they leave free, or whose
standard deviation exceeds its own size (relative coordinates) or half the range of the
folds' input (the offset), gets none (None) and a warning. ``identifiability`` lists the
eigenvectors of the data's Fisher information, in relative coordinates d log p for a
positive input and dp for the offset and the others, each with its standard deviation and
whether the data fix it.
"""

from __future__ import annotations

import dataclasses
import math

import jax
import numpy as np

from jaxrod.params import check_value
from jaxrod.status import Status

#: The name of the data's shared offset among the estimates.
OFFSET = "offset"
#: A Fisher eigenvalue below this fraction of the largest marks a combination of the free
#: inputs that the data cannot tell apart.
FISHER_RANK_TOL = 1e-9


@dataclasses.dataclass(frozen=True)
class Prior:
    """A Gaussian prior on a free input, in its own units."""

    mean: float
    sd: float

    def __post_init__(self):
        object.__setattr__(self, "mean", check_value("prior mean", self.mean,
                                                     lambda x: True, "a finite number"))
        object.__setattr__(self, "sd", check_value("prior sd", self.sd, lambda x: x > 0.0,
                                                   "a finite number > 0"))


@dataclasses.dataclass(frozen=True)
class SceneFit:
    """The answer of ``fit_folds`` / ``design_folds``.

    ``estimates`` and ``std`` by key (one standard deviation from the Laplace covariance,
    None where the data and priors do not fix the input; ``std`` None for a design);
    ``correlation`` between the free inputs (``free`` order); ``folds``: the fold values at
    the answer in the order met; ``model`` and ``residuals`` (model - datum, None where
    none) per datum; ``chi2`` (data and priors), ``dof`` (data + priors - free) and
    ``reduced_chi2``; ``identifiability`` (module docstring), ``warnings``;
    ``converged``, ``iterations``, ``status`` (a ``jaxrod.Status``) and ``reason``.
    """

    free: tuple[str, ...]
    estimates: dict
    std: dict | None
    correlation: np.ndarray
    folds: list
    model: list
    residuals: list
    chi2: float
    dof: int
    reduced_chi2: float | None
    identifiability: list
    warnings: list
    sigma: float
    priors: dict
    converged: bool
    iterations: int
    status: Status
    reason: str | None

    def as_dict(self) -> dict:
        return {"free": list(self.free), "estimates": self.estimates, "std": self.std,
                "correlation": np.asarray(self.correlation).tolist(), "folds": self.folds,
                "model": self.model, "residuals": self.residuals, "chi2": self.chi2,
                "dof": self.dof, "reduced_chi2": self.reduced_chi2,
                "identifiability": self.identifiability, "warnings": self.warnings,
                "sigma": self.sigma,
                "priors": {k: {"mean": v.mean, "sd": v.sd} for k, v in self.priors.items()},
                "converged": self.converged, "iterations": self.iterations,
                "status": self.status.name.lower(), "reason": self.reason}


def record(problem, res, folds, design: bool) -> SceneFit:
    """The host record of one solved problem (``jaxrod.inverse.scene_fit``'s): its
    least-squares result ``res`` and the folds' values there."""
    res, folds = jax.device_get((res, folds))
    names = problem.keys + (OFFSET,)
    idx = [names.index(k) for k in problem.free]
    p = np.asarray(res.p)
    estimates = {k: float(p[i]) for k, i in zip(problem.free, idx)}
    # relative coordinates (d log p) for positive inputs, absolute for the offset and others
    rel = np.array([p[i] if (k != OFFSET and p[i] > 0) else 1.0
                    for k, i in zip(problem.free, idx)])
    J = np.asarray(res.J)[:, idx] * rel
    lam, V = np.linalg.eigh(J.T @ J)
    fixed = lam > FISHER_RANK_TOL * max(float(lam[-1]), 1e-300)
    cov = (V[:, fixed] / lam[fixed]) @ V[:, fixed].T
    loose = np.sum(V[:, ~fixed] ** 2, axis=1) > 1e-4
    sd_rel = np.where(loose, np.inf, np.sqrt(np.abs(np.diag(cov))))
    limits = np.array([1.0 if r != 1.0 or (k != OFFSET and p[i] > 0)
                       else 0.5 * problem.span_abs
                       for k, i, r in zip(problem.free, idx, rel)])
    std, warnings = {}, []
    for j, k in enumerate(problem.free):
        if not np.isfinite(sd_rel[j]) or sd_rel[j] > limits[j]:
            std[k] = None
            warnings.append(f"{k} is not fixed by these data and priors: give it a prior, "
                            "fix it, or measure more")
        else:
            std[k] = float(sd_rel[j] * rel[j])
    with np.errstate(all="ignore"):
        corr = cov / np.outer(sd_rel, sd_rel)
    identifiability = _identifiability(J[:problem.data.size], problem.free, rel, limits)
    for entry in identifiability:
        if not entry["fixed_by_data"]:
            warnings.append("the data cannot tell apart the combination "
                            f"{entry['combination_text']}")
    sigma = problem.arrays["sigma"]
    r = np.asarray(res.r)
    weights, shifted = (np.asarray(problem.arrays[k]) for k in ("weights", "shifted"))
    model = weights @ np.asarray(folds) + shifted * p[-1]
    residuals = [float(v - d) if mk else None
                 for v, d, mk in zip(model, problem.data, problem.mask)]
    chi2 = float(np.dot(r, r))
    dof = problem.n_data + problem.n_priors - len(problem.free)
    reduced = chi2 / dof if dof > 0 else None
    if reduced is not None and reduced > 9.0 and not design:
        warnings.append(f"the residuals exceed sigma = {sigma:g} (reduced chi^2 = "
                        f"{reduced:.3g}): the model does not explain the data within the "
                        "assumed error")
    reasons = []
    if not bool(res.ok):
        reasons.append("the fold model failed at the last point (a solve did not converge, "
                       "a fold left the range, or the start lies outside the bounds)")
    if not bool(res.converged):
        reasons.append(f"the gradient did not vanish (|grad| = {float(res.grad_norm):.2e}) "
                       f"within {int(res.iterations)} iterations")
    return SceneFit(free=problem.free, estimates=estimates, std=None if design else std,
                    correlation=corr, folds=[float(v) for v in folds],
                    model=[float(v) for v in model], residuals=residuals, chi2=chi2, dof=dof,
                    reduced_chi2=reduced, identifiability=identifiability,
                    warnings=warnings, sigma=float(sigma), priors=problem.priors,
                    converged=not reasons, iterations=int(res.iterations),
                    status=Status.of(not reasons), reason="; ".join(reasons) or None)


def _identifiability(J: np.ndarray, free, rel, limits) -> list:
    """Eigenvectors of the data's Fisher information J^T J (relative coordinates)."""
    lam, V = np.linalg.eigh(J.T @ J)
    top = max(float(lam[-1]), 1e-300)
    out = []
    for k in range(len(lam) - 1, -1, -1):
        v = V[:, k] / np.max(np.abs(V[:, k])) * np.sign(V[np.argmax(np.abs(V[:, k])), k])
        terms = {name: float(c) for name, c in zip(free, v) if abs(c) > 0.05}
        text = " ".join(f"{c:+.3g} {('log ' if r != 1.0 else '') + n}"
                        for (n, c), r in zip(terms.items(),
                                             [rel[list(free).index(n)] for n in terms]))
        limit = max(limits[list(free).index(n)] for n in terms)
        fixed = bool(lam[k] > FISHER_RANK_TOL * top and 1.0 / math.sqrt(lam[k]) <= limit)
        out.append({"eigenvalue": float(lam[k]), "fixed_by_data": fixed,
                    "std": float(1.0 / math.sqrt(lam[k])) if lam[k] > 0 else None,
                    "combination": terms, "combination_text": text})
    return out
