"""Fits and designs on any scene or rig: the inputs whose folds sit at measured (or target)
values, with priors, bounds, an offset of the data, batches and profiles.

The folds f_k(p) are those met along one input v (``vary``) over a range, in the order met
(``jaxrod.equilibria.folds``). Datum i measures one of them, with a sign (a mirrored sweep
of a symmetric rig sees -f_k), and every datum may share an unknown offset delta of the
scale v is read on (a misaligned track):

    model_i(p, delta) = s_i f_{k_i}(p) + delta        (``readout`` = ((k_i, s_i), ...)),

or a difference of two folds, f_k - f_j (a hysteresis width: the readout ``(k, j)`` as
``{k: 1, j: -1}``; the offset cancels).

The free inputs p (any inputs of a scene by key, any numbers of a rig by file key) and
delta (``OFFSET``, when ``offset`` is True) minimise half of

    chi^2 = sum_i ((model_i - m_i) / sigma)^2 + sum_j ((p_j - mean_j) / sd_j)^2,

the second sum over the free inputs with a Gaussian ``Prior``, by the least-squares program
of ``jaxrod.solvers.least_squares`` (optax L-BFGS direction, Armijo line search,
Gauss-Newton scaling, so that inputs of any size are stepped alike). Each evaluation solves
each fold's Moore-Spence system from the fold states of the last accepted point (at the
start, from the approximate folds of ``jaxrod.equilibria.folds.fold_guesses``), implicitly
differentiated in p (``differentiable_fold``); a trial point where a solve fails, a fold
leaves the range, the folds change their order, p leaves its bounds or a magnet enters the
rod's reach is rejected. One compiled program per (scene structure, number of inputs, data,
N) serves every choice of keys, data, priors, bounds and which inputs are held
(``profile``) or batched (``fit_batch``).

The record (``SceneFit``, ``jaxrod.inverse.fit_record``) carries the Laplace covariance,
the identifiability of the inputs from the data and warnings. A design is the same fit
with the targets as data (``design_folds``), from the scene and, optionally, a grid of
starts within the bounds.
"""

from __future__ import annotations

import dataclasses
import itertools
import math

import jax
import jax.numpy as jnp
import numpy as np

from jaxrod.equilibria.equilibrium import DEFAULT_N, discretise
from jaxrod.equilibria.folds import fold_guesses, fold_values
from jaxrod.equilibria.trace import check_range
from jaxrod.inverse.fit_record import OFFSET, Prior, SceneFit, record
from jaxrod.params import ParameterError, check_value
from jaxrod.programs import jit
from jaxrod.progress import Interrupted, progress_bar
from jaxrod.scenes.files import FileScene, apply_settings, scene_from
from jaxrod.scenes.path import PROBE, along
from jaxrod.scenes.scene import Scene
from jaxrod.solvers.least_squares import forward_mode, least_squares_run
from jaxrod.status import Status

# --- the program ----------------------------------------------------------------------------

def _program(path, disc, origin, span, z0, p0, free, data, mask, sigma, weights, shifted,
             prior_mean, prior_scale, lower, upper, magnets, max_iter):
    """p = (the path's inputs after ``vary``, the offset): the least-squares answer (in the
    scaled parameters x = p / |p0|, so that inputs of any size start alike; 1 for an entry
    at zero), the folds' values there and the covariance of x. ``magnets``: (term name ->
    (margin at p0, exponents)) for the clearance."""
    p_start = p0
    unit = jnp.where(p0 == 0.0, 1.0, jnp.abs(p0))

    def clear(p, v):
        """Every magnet beyond the rod's reach at the input value v."""
        scene = path.at(jnp.concatenate([jnp.reshape(v, (1,)), p[:-1]]))
        gaps = [jnp.linalg.norm(scene.terms[t].centre()) - 1.0
                - margin * jnp.prod((p[:-1] / p_start[:-1]) ** k)
                for t, (margin, k) in magnets.items()]
        return jnp.all(jnp.stack(gaps) > 0.0) if gaps else jnp.asarray(True)

    def residuals(x, z):
        p = x * unit
        values, z_new, ok = fold_values(path, disc, origin, span, p[:-1], z)
        lam = z_new[:, -1]
        ok = ok & jnp.all((lam >= -1e-9) & (lam <= 1.0 + 1e-9)) \
            & jnp.all(jnp.diff(lam) * jnp.sign(jnp.diff(z0[:, -1])) > 0.0) \
            & jnp.all(~free | ((p >= lower) & (p <= upper))) \
            & jnp.all(jax.vmap(lambda v: clear(p, v))(values))
        model = weights @ values + shifted * p[-1]
        r = jnp.where(mask, (model - data) / sigma, 0.0)
        return jnp.concatenate([r, (p - prior_mean) * prior_scale]), z_new, ok

    res = least_squares_run(forward_mode(residuals), p0 / unit, z0, free,
                            data.shape[0] + p0.shape[0], True, max_iter)
    return res._replace(p=res.p * unit, J=res.J / unit), origin + span * res.aux[:, -1]


_fit_program = jit(_program, static_argnames=("max_iter",))


@jit(static_argnames=("max_iter",))
def _batch_program(path, disc, origin, span, z0, p0, free, data, mask, sigma, weights,
                   shifted,
                   prior_mean, prior_scale, lower, upper, magnets, max_iter):
    """``_program`` of each row of ``data`` and ``mask`` (vmapped)."""
    return jax.vmap(lambda d, mk: _program(
        path, disc, origin, span, z0, p0, free, d, mk, sigma, weights, shifted, prior_mean,
        prior_scale, lower, upper, magnets, max_iter))(data, mask)


# --- a problem, prepared on the host -------------------------------------------------------

@dataclasses.dataclass(frozen=True)
class _Problem:
    keys: tuple            # the path's inputs after vary (free and held)
    free: tuple            # the free names (keys and the offset)
    arrays: dict           # the program's arguments but data and mask
    data: np.ndarray
    mask: np.ndarray
    n_data: int
    n_priors: int
    priors: dict
    span_abs: float


def with_values(scene, values: dict):
    """``scene`` (a ``Scene`` or a rig read from a file) with inputs set by key (a rig's
    numbers by file key, or its scene's inputs)."""
    if isinstance(scene, FileScene):
        inner = scene.scene.inputs() + ["load_scale"]
        rig = scene_from(apply_settings(scene.data, [f"{k}={float(v)!r}" for k, v in
                                                     values.items() if k not in inner]))
        values = {k: v for k, v in values.items() if k in inner}
        return dataclasses.replace(rig, scene=with_values(rig.scene, values)) \
            if values else rig
    for k, v in values.items():
        scene = scene.replace(k, float(v))
    return scene


def magnet_margins(scene, keys, start) -> dict:
    """term name -> (the magnet's radius in rod lengths at ``start``, its exponents in the
    keys): a rig's magnet radius d / (2 L) moves with the rig's numbers; a scene's magnets
    are points."""
    margins = getattr(scene, "margins", {}) or {}
    names = [t for t, term in (scene.scene if isinstance(scene, FileScene) else scene)
             .terms.items() if hasattr(term, "centre")]
    out = {}
    for t in names:
        margin = float(margins.get(t, 0.0))
        k = np.zeros(len(keys))
        if margin > 0.0:
            for j, key in enumerate(keys):
                if key in scene.scene.inputs() + ["load_scale"]:
                    continue
                up = with_values(scene, {key: start[j] * PROBE}).margins.get(t, margin)
                k[j] = round(math.log(up / margin) / math.log(PROBE))
        out[t] = (margin, k)
    return out


#: The host work of a start (its path, its folds, its magnets), kept for the fits that
#: follow from the same scene: a calibration of many data sets at one point prepares once.
_STARTS: dict = {}


def _remembered(key, make):
    """``make()``, kept under ``key`` (the last 16)."""
    if key not in _STARTS:
        if len(_STARTS) >= 16:
            _STARTS.pop(next(iter(_STARTS)))
        _STARTS[key] = make()
    return _STARTS[key]


def _identity(scene) -> tuple:
    """What a scene (or rig) is, as a hashable key: its file, or its structure and values."""
    if isinstance(scene, FileScene):
        import json

        return ("file", json.dumps(scene.data, sort_keys=True, default=str),
                _identity(scene.scene))
    leaves, treedef = jax.tree_util.tree_flatten(scene)
    return (str(treedef), tuple(np.asarray(v, np.float64).tobytes() for v in leaves))


def _prepare(scene, vary, vary_range, measured, free, sigma, bounds, n, readout, offset,
             priors, hold=(), z0=None, ahead: int | None = None) -> tuple[_Problem, object]:
    start, stop = check_range(scene, vary, *vary_range)
    free, hold = tuple(free), tuple(hold)
    if not free and not offset:
        raise ParameterError("free: name at least one input to fit")
    for key in free + hold:
        if key == vary:
            raise ParameterError(f"free: {key} is the input the folds are met along")
        if key == OFFSET:
            raise ParameterError(f"free: {OFFSET!r} is the data's offset (offset=True)")
    keys = free + tuple(k for k in hold if k not in free)
    if len(set(keys)) != len(keys):
        raise ParameterError(f"free: an input is named twice in {', '.join(keys)}")
    data = np.asarray(measured, float).reshape(-1)
    if np.any(np.isinf(data)):
        raise ParameterError(f"measured: must be finite (nan: not measured), got {data}")
    mask = ~np.isnan(data)
    if not mask.any():
        raise ParameterError("measured: at least one value is needed")
    weights, shifted = _readout_weights(readout, data.size)
    if not (math.isfinite(sigma) and sigma > 0):
        raise ParameterError(f"sigma must be a finite number > 0, got {sigma!r}")
    here = _identity(scene)
    path = _remembered(("path", here, vary, keys), lambda: along(scene, (vary, *keys)))
    names = keys + (OFFSET,)
    bounds = dict(bounds or {})
    for key, pair in bounds.items():
        if key not in names:
            raise ParameterError(f"bounds: {key!r} is not a free input ({', '.join(names)})")
        lo = check_value(f"bounds {key} (lower)", pair[0], lambda x: True, "a finite number")
        check_value(f"bounds {key} (upper)", pair[1], lambda x: x > lo,
                    f"a finite number above the lower bound {lo:g}")
    lower = np.array([bounds.get(k, (-np.inf, np.inf))[0] for k in names], float)
    upper = np.array([bounds.get(k, (-np.inf, np.inf))[1] for k in names], float)
    priors = dict(priors or {})
    for key, prior in priors.items():
        if not isinstance(prior, Prior):
            raise ParameterError(f"prior {key}: must be a Prior(mean, sd), got {prior!r:.60}")
        if key not in free and not (key == OFFSET and offset):
            raise ParameterError(f"prior {key}: {key} is not free (free: "
                                 f"{', '.join(free + ((OFFSET,) if offset else ()))}); a "
                                 "prior acts on a fitted input only")
    mean = np.array([priors[k].mean if k in priors else 0.0 for k in names])
    scale = np.array([1.0 / priors[k].sd if k in priors else 0.0 for k in names])
    p0 = np.array([*path.start[1:], 0.0])
    free_mask = np.array([k in free for k in keys] + [bool(offset)])
    if np.any(free_mask & ((p0 < lower) | (p0 > upper))):
        raise ParameterError("bounds: the scene's values of the free inputs (the start) lie "
                             "outside the bounds")
    n_folds = weights.shape[1]
    disc = discretise(path.template, n)
    arrays = dict(path=path, disc=disc, origin=start,
                  span=stop - start, z0=z0, p0=jnp.asarray(p0),
                  free=jnp.asarray(free_mask), sigma=float(sigma),
                  weights=jnp.asarray(weights), shifted=jnp.asarray(shifted),
                  prior_mean=jnp.asarray(mean),
                  prior_scale=jnp.asarray(scale * free_mask), lower=jnp.asarray(lower),
                  upper=jnp.asarray(upper), magnets=_remembered(
                      ("magnets", here, keys), lambda: magnet_margins(scene, keys, p0)))
    if z0 is None:
        if ahead is not None:  # the fit's program compiles while the folds are found
            states = jax.ShapeDtypeStruct((n_folds, 2 * disc.size + 1), jnp.float64)
            _fit_program.compile_ahead(*_fit_arguments(arrays | {"z0": states}, data, mask),
                                       ahead)
        z0, status = _remembered(("folds", here, vary, start, stop, n, n_folds),
                                 lambda: fold_guesses(scene, vary, start, stop, n_folds, n))
        if len(z0) < n_folds:
            why = "" if status.ok else f" (the branch stopped: {status})"
            raise ParameterError(f"the start has {len(z0)} fold(s) along {vary} from "
                                 f"{start:g} to {stop:g}{why}; the data need {n_folds}: "
                                 "start nearer the answer, or widen the range")
    arrays["z0"] = jnp.asarray(z0)
    names_free = free + ((OFFSET,) if offset else ())
    return _Problem(keys, names_free, arrays, data, mask, int(mask.sum()),
                    sum(1 for k in priors if k in names_free), priors,
                    abs(stop - start)), path


def _readout_weights(readout, n_data: int) -> tuple[np.ndarray, np.ndarray]:
    """(W, o): datum i reads W[i] @ folds + o[i] delta. A readout entry (k, s) is s f_k
    (o = 1), a dict {k: 1, j: -1} the difference f_k - f_j (o = 0); by default the folds
    in the order met."""
    entries = list(readout) if readout is not None else [(i, 1) for i in range(n_data)]
    rows = []
    for entry in entries:
        if isinstance(entry, dict):
            pairs = [(k, float(v)) for k, v in entry.items()]
            ok = sorted(v for _, v in pairs) == [-1.0, 1.0]
        else:
            try:
                k, v = entry
                pairs, ok = [(k, float(v))], abs(float(v)) == 1.0
            except (TypeError, ValueError):
                pairs, ok = [], False
        ok = ok and all(isinstance(k, (int, np.integer)) or float(k).is_integer()
                        for k, _ in pairs) and all(float(k) >= 0 for k, _ in pairs)
        if not ok:
            raise ParameterError("readout: one (fold index, sign +-1) per datum, or a "
                                 "difference {k: 1, j: -1} of two folds")
        rows.append(pairs)
    if len(rows) != n_data:
        raise ParameterError("readout: one (fold index, sign +-1) per datum")
    W = np.zeros((n_data, int(max(k for pairs in rows for k, _ in pairs)) + 1))
    for i, pairs in enumerate(rows):
        for k, v in pairs:
            W[i, int(k)] = v
    return W, np.array([float(len(pairs) == 1) for pairs in rows])


def _fit_arguments(a: dict, data, mask) -> tuple:
    """``_fit_program``'s arguments but ``max_iter``, from a problem's arrays."""
    return (a["path"], a["disc"], a["origin"], a["span"], a["z0"], a["p0"], a["free"],
            jnp.asarray(np.nan_to_num(data)), jnp.asarray(mask), a["sigma"], a["weights"],
            a["shifted"], a["prior_mean"], a["prior_scale"], a["lower"], a["upper"],
            a["magnets"])


def _solve(problem: _Problem, max_iter: int, design: bool = False):
    """(the record, the fold states at the answer)."""
    res, folds = _fit_program(*_fit_arguments(problem.arrays, problem.data, problem.mask),
                              max_iter)
    return record(problem, res, folds, design), res.aux


# --- the public analyses -------------------------------------------------------------------

def fit_folds(scene: Scene | FileScene, vary: str, vary_range: tuple[float, float], measured,
              free, sigma: float = 1.0, bounds: dict | None = None, n: int = DEFAULT_N,
              max_iter: int = 60, design: bool = False, *, readout=None,
              offset: bool = False, priors: dict | None = None, hold=()) -> SceneFit:
    """Fit the inputs ``free`` (keys) so that the folds met along ``vary`` over
    ``vary_range`` sit at ``measured`` (module docstring: NaN where not measured; datum i
    reads fold ``readout[i][0]`` with sign ``readout[i][1]``, by default the folds in the
    order met), each with standard deviation ``sigma`` (``vary``'s units). ``offset``: fit
    a shared offset of the data too (``OFFSET``); ``priors``: key -> ``Prior``;
    ``bounds``: key -> (lo, hi) (default unbounded); ``hold``: inputs carried but held (one
    compiled program then serves every subset of ``free + hold``). The scene's values are
    the start.
    """
    problem, _ = _prepare(scene, vary, vary_range, measured, free, sigma, bounds, n,
                          readout, offset, priors, hold, ahead=max_iter)
    return _solve(problem, max_iter, design)[0]


def fit_batch(scene: Scene | FileScene, vary: str, vary_range: tuple[float, float], measured,
              free, sigma: float = 1.0, bounds: dict | None = None, n: int = DEFAULT_N,
              max_iter: int = 60, *, readout=None, offset: bool = False,
              priors: dict | None = None, hold=(), method: str = "auto",
              progress: bool = False) -> list[SceneFit]:
    """``fit_folds`` of each row of ``measured`` (K, data), the rest shared (one start).

    ``method="vmap"`` runs them in one vmapped, compiled call (the form that scales on a
    GPU); ``"loop"`` runs the compiled single fit row by row, faster on a CPU, where every
    nested while loop of a vmapped batch runs until its slowest element is done; ``"auto"``
    picks vmap on a GPU. ``progress`` shows a progress bar (loop); Ctrl-C raises
    ``jaxrod.progress.Interrupted`` with the fits done so far as ``partial``.
    """
    rows = np.atleast_2d(np.asarray(measured, float))
    problem, _ = _prepare(scene, vary, vary_range, rows[0], free, sigma, bounds, n, readout,
                          offset, priors, hold)
    problems = []
    for i, row in enumerate(rows):
        mask = ~np.isnan(row)
        if np.any(np.isinf(row)) or not mask.any() or row.size != problem.data.size:
            raise ParameterError(f"measured row {i}: {problem.data.size} finite values "
                                 "(nan: not measured), at least one")
        problems.append(dataclasses.replace(problem, data=row, mask=mask,
                                            n_data=int(mask.sum())))
    if method == "auto":
        method = "vmap" if jax.default_backend() == "gpu" else "loop"
    if method not in ("vmap", "loop"):
        raise ParameterError(f"method must be 'auto', 'vmap' or 'loop', got {method!r}")
    if method == "vmap":
        a = problem.arrays
        res, folds = _batch_program(
            a["path"], a["disc"], a["origin"], a["span"], a["z0"], a["p0"], a["free"],
            jnp.asarray(np.nan_to_num(rows)), jnp.asarray(~np.isnan(rows)), a["sigma"],
            a["weights"], a["shifted"], a["prior_mean"], a["prior_scale"], a["lower"], a["upper"],
            a["magnets"], max_iter)
        return [record(pr, jax.tree.map(lambda x, i=i: x[i], res), folds[i], False)
                for i, pr in enumerate(problems)]
    out = []
    bar = progress_bar(len(problems), "fits", "fit", progress)
    try:
        for pr in problems:
            out.append(_solve(pr, max_iter)[0])
            bar.update(1)
    except KeyboardInterrupt:
        raise Interrupted(out, f"after {len(out)} of {len(problems)} fits") from None
    finally:
        bar.close()
    return out


def profile(scene: Scene | FileScene, vary: str, vary_range: tuple[float, float], measured,
            name: str, free, sigma: float = 1.0, values=None, count: int = 15,
            span: float = 3.0, fitted: SceneFit | None = None, n: int = DEFAULT_N,
            max_iter: int = 60, *, readout=None, offset: bool = False,
            priors: dict | None = None, bounds: dict | None = None, hold=()) -> dict:
    """The profile likelihood of the free input ``name`` (or ``OFFSET``): chi^2 minimised
    over the other free inputs with ``name`` held at each of ``values`` (default ``count``
    values within ``span`` standard deviations of the estimate), beside the Laplace
    (quadratic) approximation chi2_min + ((v - estimate) / std)^2. The held input's prior
    term counts at each value. One compiled program for every value (the held input is a
    masked entry of the same fit), each warm-started from the last."""
    kw = dict(readout=readout, offset=offset, priors=priors, hold=hold)
    names = tuple(free) + ((OFFSET,) if offset else ())
    if name not in names:
        raise ParameterError(f"profile: {name!r} is not a free input ({', '.join(names)})")
    best = fitted or fit_folds(scene, vary, vary_range, measured, free, sigma, bounds, n,
                               max_iter, **kw)
    centre, sd = best.estimates[name], best.std[name] if best.std else None
    if values is None:
        half = span * sd if sd is not None else 0.3 * abs(centre) + (5.0 if name == OFFSET
                                                                     else 0.0)
        values = np.linspace(centre - half, centre + half, count)
    values = np.asarray(values, float)
    others = tuple(k for k in free if k != name)
    held = {k: v for k, v in (priors or {}).items() if k != name}
    problem, _ = _prepare(with_values(scene, {k: best.estimates[k] for k in free}), vary,
                          vary_range, measured, others, sigma,
                          {k: b for k, b in (bounds or {}).items() if k != name}, n,
                          readout, offset and name != OFFSET, held,
                          hold=tuple(hold) + ((name,) if name != OFFSET else ()))
    keys = problem.keys + (OFFSET,)
    j = keys.index(name)
    p0 = np.asarray(problem.arrays["p0"]).copy()
    if offset and name != OFFSET:
        p0[-1] = best.estimates[OFFSET]
    prior = (priors or {}).get(name)
    chi2, converged = [], []
    # from the centre outwards on each side, each start the last answer's folds
    order = np.argsort(np.abs(values - centre), kind="stable")
    results = {}
    for side in (values >= centre, values < centre):
        z0 = problem.arrays["z0"]
        for i in [i for i in order if side[i]]:
            p = p0.copy()
            p[j] = values[i]
            arrays = problem.arrays | {"p0": jnp.asarray(p), "z0": z0}
            fit, z = _solve(dataclasses.replace(problem, arrays=arrays), max_iter)
            if fit.converged:
                z0 = z
            extra = ((values[i] - prior.mean) / prior.sd) ** 2 if prior is not None else 0.0
            results[i] = (fit.chi2 + extra if fit.converged else math.nan, fit.converged)
    chi2 = [results[i][0] for i in range(len(values))]
    converged = [results[i][1] for i in range(len(values))]
    laplace = None if sd is None else (best.chi2 + ((values - centre) / sd) ** 2).tolist()
    return {"name": name, "values": [float(v) for v in values], "chi2": chi2,
            "converged": converged, "laplace_chi2": laplace, "estimate": centre, "std": sd,
            "chi2_min": best.chi2}


def design_folds(scene: Scene | FileScene, vary: str, vary_range: tuple[float, float],
                 targets, free, bounds: dict | None = None, n: int = DEFAULT_N, *,
                 readout=None, starts: int = 0,
                 width: float | None = None) -> SceneFit | list[SceneFit]:
    """The inputs ``free`` whose folds along ``vary`` sit at ``targets`` (``readout`` as in
    ``fit_folds``; NaN: a fold not targeted): the fit with the targets as data; converged
    means the targets are hit to 1e-9 of the range. ``width``: a hysteresis width too, the
    first fold met less the second, f_0 - f_1 (positive for a loop met sweeping up).
    ``starts`` > 0: also from a grid of ``starts`` values per input
    within the (finite) bounds (cell centres, in log for positive bounds; a start without
    the folds is skipped), and the list of the distinct answers, those that hit the targets
    first, then by their largest miss."""
    start, stop = check_range(scene, vary, *vary_range)
    tol = 1e-9 * abs(stop - start)
    if width is not None:
        check_value("width", width, lambda v: v != 0.0, "a finite number, not 0 (the first "
                    "fold met less the second)")
        targets = [float(v) for v in np.atleast_1d(np.asarray(
            [] if targets is None else targets, float))]
        readout = [*(readout if readout is not None else
                     [(i, 1) for i in range(len(targets))]), {0: 1, 1: -1}]
        targets = targets + [float(width)]

    def checked(out: SceneFit) -> SceneFit:
        miss = max(abs(r) for r in out.residuals if r is not None)
        if out.converged and miss > tol:
            return dataclasses.replace(out, converged=False, status=Status.NOT_CONVERGED,
                                       reason=f"the folds miss the targets by {miss:.3g}: "
                                       "no design of these inputs hits them (within the "
                                       "bounds)")
        return out

    if not starts:
        return checked(fit_folds(scene, vary, vary_range, targets, free, 1.0, bounds, n,
                                 design=True, readout=readout))
    bounds = dict(bounds or {})
    free = tuple(free)
    missing = [k for k in free if not all(map(math.isfinite, bounds.get(k, (np.inf,) * 2)))]
    if missing:
        raise ParameterError(f"bounds: a grid of starts needs finite bounds of "
                             f"{', '.join(missing)}")
    cells = (np.arange(starts) + 0.5) / starts
    axes = [lo * (hi / lo) ** cells if lo > 0 else lo + (hi - lo) * cells
            for lo, hi in (bounds[k] for k in free)]
    miss = lambda d: max(abs(r) for r in d.residuals if r is not None)
    outcomes = []
    for point in [None, *itertools.product(*axes)]:
        try:  # a start in the rod's reach, or without the folds, is skipped
            at = scene if point is None else with_values(scene, dict(zip(free, point)))
            out = checked(fit_folds(at, vary, vary_range, targets, free, 1.0, bounds, n,
                                    design=True, readout=readout))
        except ParameterError:
            continue
        if not any(all(abs(out.estimates[k] - d.estimates[k]) <= 1e-6 * max(
                abs(d.estimates[k]), 1e-12) for k in free) for d in outcomes):
            outcomes.append(out)
    return sorted(outcomes, key=lambda d: (not d.converged, miss(d)))
