"""The paper's permanent-magnet experiment calibrated on its switching angles: a thin adapter
of the generic fit (``jaxrod.inverse.scene_fit``) on the shipped rig ``permanent-magnet``.

The experiment's four switching angles, in the order of its protocol,

    cw_capture = -alpha_lower + delta,   cw_release = alpha_upper + delta,
    ccw_capture = alpha_lower + delta,   ccw_release = -alpha_upper + delta,

are the folds alpha_lower < alpha_upper of the planar branch along the magnet's angle
(the branch from alpha = 0 meets the upper fold first, then turns back to the lower one:
``READOUT``) and an angular offset delta of the track (degrees). Any subset of the nine
physical inputs (``PHYSICAL_NAMES``, the rig's numbers by ``KEYS``) and the offset is
fitted (``fit``), with Gaussian priors and bounds (default: the inputs' valid ranges and
+-45 degrees); ``profile`` gives profile likelihoods and ``calibrate_rows`` a batch. The
fold model is computed at N = ``MODEL_N``.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from jaxrod.design_point import DesignPoint, range_of
from jaxrod.inverse import scene_fit
from jaxrod.inverse.scene_fit import OFFSET, Prior, SceneFit
from jaxrod.params import (
    NDFEB_MAGNET,
    PHYSICAL_NAMES,
    RANGES,
    ParameterError,
    check,
    check_value,
    preset,
)
from jaxrod.scenes.dipole import rig_of

__all__ = ["ANGLE_NAMES", "FREE_NAMES", "OFFSET", "Prior", "calibrate_rows", "default_point",
           "fit", "profile"]

ANGLE_NAMES = ("cw_capture", "cw_release", "ccw_capture", "ccw_release")
#: (fold in the order met, sign) of each angle: the upper fold is met first.
READOUT = ((1, -1.0), (0, 1.0), (1, 1.0), (0, -1.0))
#: The fold model's Chebyshev degree (the fold angles reach round-off by N = 12).
MODEL_N = 12
#: The inputs a calibration may free: every physical input, and the track's angular offset.
FREE_NAMES = PHYSICAL_NAMES + (OFFSET,)
#: Default bounds of the offset, degrees.
OFFSET_BOUNDS = (-45.0, 45.0)


def sign_hint(measured, mask) -> str | None:
    """A hint when the measured angles' signs are the opposite of the convention (every
    measured angle beyond 2 degrees with the other sign)."""
    m = np.asarray(measured, float)[np.asarray(mask, bool)]
    expected = np.array([s for _, s in READOUT])[np.asarray(mask, bool)]
    big = np.abs(m) > 2.0
    if big.sum() >= 2 and np.all(np.sign(m[big]) == -expected[big]):
        return ("the angles' signs are the opposite of the convention: in the order "
                f"{', '.join(ANGLE_NAMES)} they are -, +, +, - (capture at -alpha_lower in "
                "the clockwise sweep, magnet angles positive towards e1): change the signs")
    return None


def parse_angles(measured, sigma_deg):
    """The four measured angles (nan where not measured) and which were measured;
    ParameterError naming what is wrong (count, infinities, none measured, an angle outside
    (-90, 90) degrees, sigma)."""
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


def default_point() -> DesignPoint:
    """The paper's permanent-magnet experiment (nickel wire, NdFeB magnet), physical."""
    rod, _ = preset("permanent-magnet")
    return DesignPoint.from_physical(rod, NDFEB_MAGNET)


def _check_names(names, allowed, what: str) -> tuple[str, ...]:
    names = tuple(names)
    unknown = [n for n in names if n not in allowed]
    if unknown:
        raise ParameterError(f"{what}: unknown parameter {', '.join(map(repr, unknown))}; "
                             f"choose from {', '.join(allowed)}")
    if len(set(names)) != len(names):
        raise ParameterError(f"{what}: a parameter is named twice in {', '.join(names)}")
    return names


def check_bounds(bounds: dict, names) -> dict:
    """Bounds by name, each a finite (lo, hi) with lo < hi."""
    _check_names(bounds, names, "bounds")
    out = {}
    for name, (lo, hi) in bounds.items():
        lo = check_value(f"bounds {name} (lower)", lo, lambda x: True, "a finite number")
        hi = check_value(f"bounds {name} (upper)", hi, lambda x: x > lo,
                         f"a finite number above the lower bound {lo:g}")
        out[name] = (lo, hi)
    return out


def in_paper_names(fit: SceneFit, keys: dict, degrees: float) -> SceneFit:
    """A generic fit's record with the paper's names and units (angles in degrees)."""
    back = {key: (name, factor) for name, (key, factor) in keys.items()}
    back[OFFSET] = (OFFSET, 1.0)

    def named(d):
        return None if d is None else {
            back[k][0]: None if v is None else v * abs(back[k][1]) for k, v in d.items()}

    ident = [e | {"combination": {back[k][0]: c for k, c in e["combination"].items()},
                  "combination_text": " ".join(
                      w if w not in back else back[w][0]
                      for w in e["combination_text"].split(" "))}
             for e in fit.identifiability]
    deg = lambda xs: [None if x is None else x * degrees for x in xs]
    return dataclasses.replace(
        fit, free=tuple(back[k][0] for k in fit.free), estimates=named(fit.estimates),
        std=named(fit.std), folds=deg(fit.folds), model=deg(fit.model),
        residuals=deg(fit.residuals), identifiability=ident, sigma=fit.sigma * degrees,
        priors={back[k][0]: Prior(p.mean * back[k][1], p.sd * back[k][1])
                for k, p in fit.priors.items()},
        warnings=[" ".join(back[w][0] if w in back else w for w in text.split(" "))
                  for text in fit.warnings])


def _prepare(measured, free, point, priors, sigma_deg, bounds, start):
    """The generic fit's arguments of a calibration (validated)."""
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
        if name not in free:
            raise ParameterError(f"prior {name}: {name} is not free (free: "
                                 f"{', '.join(free)}); a prior acts on a fitted input only: "
                                 "add it to the free inputs, or drop the prior")
    bounds = check_bounds(dict(bounds or {}), FREE_NAMES)
    for name, value in (start or {}).items():
        if name not in free or name == OFFSET:
            raise ParameterError(f"start: {name!r} is not a free input")
        point = point.replace(name, range_of(name).check(value))
    scene, vary, span, degrees, keys = rig_of(point)
    inputs = [n for n in free if n != OFFSET]
    box = {n: bounds.get(n, OFFSET_BOUNDS if n == OFFSET else
                         (range_of(n).low, range_of(n).high)) for n in free}
    key = lambda n: OFFSET if n == OFFSET else keys[n][0]
    scale = lambda n: 1.0 if n == OFFSET else keys[n][1]
    args = dict(scene=scene, vary=vary, vary_range=span, measured=measured / degrees,
                free=[key(n) for n in inputs], sigma=sigma_deg / degrees,
                bounds={key(n): (lo / scale(n), hi / scale(n)) for n, (lo, hi) in box.items()},
                n=MODEL_N, readout=READOUT, offset=OFFSET in free,
                hold=[v[0] for n, v in keys.items() if n not in free],
                priors={key(n): Prior(p.mean / scale(n), p.sd / scale(n))
                        for n, p in priors.items()})
    return args, keys, degrees, mask, measured


def _finish(fit: SceneFit, keys, degrees, mask, measured) -> SceneFit:
    """The record in the paper's names, its warnings in the experiment's words."""
    out = in_paper_names(fit, keys, degrees)
    words = [w.replace(f"sigma = {out.sigma:g} (", f"sigma = {out.sigma:g} deg (")
             .replace("the data", "the angles").replace("these data", "these angles")
             for w in out.warnings]
    hint = sign_hint(measured, mask)
    return dataclasses.replace(out, warnings=words + ([hint] if hint else []))


def fit(measured, free=("E", OFFSET), point: DesignPoint | None = None,
        priors: dict | None = None, sigma_deg: float = 1.0, bounds: dict | None = None,
        start: dict | None = None) -> SceneFit:
    """Fit any subset of the physical inputs and the offset to measured switching angles.

    ``measured``: the four angles in ``ANGLE_NAMES`` order (degrees; nan where not
    measured). ``free``: the names that vary (``FREE_NAMES``); the others stay at
    ``point``'s values (default: the paper's experiment, ``default_point``). ``priors``:
    name -> ``Prior``; ``bounds``: name -> (lo, hi) (default: the valid ranges, the offset
    within +-45 degrees); ``start``: name -> a free input's starting value. The record is
    the generic fit's (``jaxrod.inverse.scene_fit.SceneFit``) in the paper's names,
    degrees and SI units; a start without the two folds raises ParameterError.
    """
    args, keys, degrees, mask, measured = _prepare(measured, free, point, priors, sigma_deg,
                                                   bounds, start)
    return _finish(scene_fit.fit_folds(**args), keys, degrees, mask, measured)


def calibrate_rows(measured, free=("E", OFFSET), point: DesignPoint | None = None,
                   priors: dict | None = None, sigma_deg: float = 1.0,
                   bounds: dict | None = None, start: dict | None = None,
                   method: str = "auto", progress: bool = False) -> list[SceneFit]:
    """``fit`` of each row of ``measured`` (K, 4), the rest shared
    (``jaxrod.inverse.scene_fit.fit_batch``: ``method`` "vmap", "loop" or "auto";
    ``progress``; Ctrl-C keeps the fits done)."""
    rows = np.atleast_2d(np.asarray(measured, float))
    for i, row in enumerate(rows):
        try:
            parse_angles(row, sigma_deg)
        except ParameterError as err:
            raise ParameterError(f"row {i}: {err}") from None
    args, keys, degrees, _, _ = _prepare(rows[0], free, point, priors, sigma_deg, bounds,
                                         start)
    args["measured"] = rows / degrees
    fits = scene_fit.fit_batch(**args, method=method, progress=progress)
    return [_finish(f, keys, degrees, ~np.isnan(r), r) for f, r in zip(fits, rows)]


def profile(measured, name: str, free=("E", OFFSET), point: DesignPoint | None = None,
            priors: dict | None = None, sigma_deg: float = 1.0, values=None,
            count: int = 15, span: float = 3.0, fitted: SceneFit | None = None) -> dict:
    """The profile likelihood of one free input: chi^2 minimised over the others at each of
    ``values`` (default ``count`` values within ``span`` standard deviations of the
    estimate), beside the Laplace approximation (``jaxrod.inverse.scene_fit.profile``).

    Paper: the fit of Corollary ``cor:permanent_physical_parameters``.
    """
    free = _check_names(free, FREE_NAMES, "free")
    if name not in free:
        raise ParameterError(f"profile: {name!r} is not a free parameter ({', '.join(free)})")
    best = fitted or fit(measured, free, point, priors, sigma_deg)
    args, keys, degrees, _, _ = _prepare(measured, free, point, priors, sigma_deg, None,
                                         None)
    scale = 1.0 if name == OFFSET else keys[name][1]
    key = OFFSET if name == OFFSET else keys[name][0]
    generic_best = dataclasses.replace(
        best, estimates={(OFFSET if n == OFFSET else keys[n][0]):
                         v / (1.0 if n == OFFSET else keys[n][1])
                         for n, v in best.estimates.items()},
        std={(OFFSET if n == OFFSET else keys[n][0]):
             None if v is None else v / (1.0 if n == OFFSET else keys[n][1])
             for n, v in best.std.items()})
    if values is not None:
        values = np.asarray(values, float) / scale
    out = scene_fit.profile(args.pop("scene"), args.pop("vary"), args.pop("vary_range"),
                            args.pop("measured"), key, args.pop("free"), values=values,
                            count=count, span=span, fitted=generic_best, **args)
    return out | {"name": name, "values": [v * scale for v in out["values"]],
                  "estimate": best.estimates[name], "std": best.std[name]}
