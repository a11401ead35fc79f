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
(``jaxrod.analysis.calibration.start_states``, the calibration's start), and every later
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

from jaxrod.analysis.calibration import (
    ANGLE_NAMES,
    OFFSET,
    Problem,
    angles_from_folds,
    parameter_names,
    physical_parameters,
    sign_hint,
    solve_program,
    start_states,
)
from jaxrod.analysis.fold_curves import DesignPoint, range_of
from jaxrod.analysis.magnet import fold_angles
from jaxrod.discretise.planar import PlanarDiscretisation, planar_discretisation
from jaxrod.params import (
    NDFEB_MAGNET,
    PHYSICAL_NAMES,
    RANGES,
    UNITS,
    ParameterError,
    check,
    check_track_clearance,
    check_value,
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
    """The arrays of a calibration or design (``jaxrod.analysis.calibration.Problem``)."""
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
    serves every choice of these (``jaxrod.analysis.calibration``).
    """
    measured, mask = _parse(measured, sigma_deg)
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
    solution = solve_program(point.kind, problem)
    return _calibration(point, problem, solution, free, priors, mask, n_data + n_priors)


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


def _calibration(point, problem, solution, free, priors, mask, n_rows) -> Calibration:
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
    alphas, ok = fold_angles(G, M, D, n=FIT_N)
    model = np.asarray(angles_from_folds(alphas, 0.0))
    m, mask = _parse(measured, sigma_deg)
    return float(np.sum(((model - m)[mask] / sigma_deg) ** 2)) if bool(ok) else math.nan
