"""Fold curves of the permanent-magnet scene in a second parameter, and the cusp where the
hysteresis ends (the paper's design rule: the hysteresis width "is set by M and D ... a
tunable design parameter for a remotely switched bistable element").

A design point is either the groups (G, M, D) or the physical inputs

    (E, rho, g, wire diameter, L, M_rod, M_magnet, magnet diameter, track radius),

and runs as a path through the shipped rig (or the paper's scene of the groups) in the
magnet angle and all of its inputs (``jaxrod.scenes.dipole.rig_of``), so any one of them
can be the second parameter. It varies as v = v0 (1 + u): the continuation variable u is the
relative change, which puts every input on the same scale. The curves are those of the
generic engine (``jaxrod.bistability.fold_curve``: one program for every input).

``fold_curves`` starts at the two folds of the given point (the batched fold-pair path, the
generic folds of its branch in the magnet angle where that does not converge), follows each
by pseudo-arclength on the Moore-Spence system in (theta, phi, alpha, u)
(``jaxrod.solvers.fold_curve``) towards the requested value, and refines the cusp where
d2F/dq2 changes sign along a curve (beyond it the curve continues as the other fold).
``find_cusp`` follows the lower fold both ways and returns the nearest cusp. Along a curve
it records alpha*, q*, tip*, dF/dalpha, d2F/dq2 (with phi scaled to int phi = 1) and the two
smallest Hessian eigenvalues (one is zero at the fold; the other's sign tells the fold's
stability data: a fold between a stable and an index-1 branch has it positive).
"""

from __future__ import annotations

import dataclasses
import math

import jax
import jax.numpy as jnp
import numpy as np

from jaxrod.bistability.fold_curve import (
    CAPACITY,
    SHIFT,
    FoldCurve,
    FoldCurvePoint,
    refine_program,
    run_columns,
    special_point,
    trace_program,
    with_point,
)
from jaxrod.design_point import DesignPoint, check_target, valid_range
from jaxrod.discretise.planar import planar_discretisation
from jaxrod.equilibria.equilibrium import DEFAULT_N, MODEL, discretise
from jaxrod.equilibria.folds import folds
from jaxrod.magnet.batch import fold_pair_states
from jaxrod.params import ParameterError
from jaxrod.scenes.dipole import rig_of
from jaxrod.scenes.path import along
from jaxrod.solvers.fold_curve import FoldCurveOptions, differentiable_cusp
from jaxrod.status import Status
from jaxrod.stored import StoredProgram


@dataclasses.dataclass(frozen=True)
class _Rig:
    """The design point as a path through its rig: p = (magnet angle, the point's inputs in
    the rig's units); ``args(i)`` varies input i as v0 (1 + u) with lam the angle in
    radians (``jaxrod.bistability.fold_curve.Shift``)."""

    path: object
    disc: object
    span: float
    values: np.ndarray

    @classmethod
    def of(cls, point: DesignPoint, n: int) -> _Rig:
        scene, angle, _, degrees, keys = rig_of(point)
        path = along(scene, (angle,) + tuple(keys[name][0] for name in point.names))
        values = np.array([v / keys[name][1] for name, v in zip(point.names, point.values)])
        return cls(path, discretise(scene, n), 180.0 / math.pi / degrees, values)

    def args(self, i: int, values=None):
        values = jnp.asarray(self.values if values is None else values, jnp.float64)
        return (self.path, self.disc, 0.0, self.span, values,
                values * (jnp.arange(values.size) == i))


#: The fold curves' ``vary``: the magnet angle at the fold, in degrees.
ALPHA = "alpha_deg"


def _scales(point: DesignPoint, vary: str) -> tuple[float, float, float, float]:
    """``special_point``'s scales of a design point's runs: alpha in degrees from lam (the
    angle in radians) and the input as v0 (1 + u)."""
    v0 = point.values[point.index(vary)]
    return 0.0, 180.0 / math.pi, v0, v0


#: Fold-curve step control: u is the relative change of the varied input; alpha is bounded
#: to [-90, 180] degrees (a fold leaving (0, 90] is reported, and followed a little further).
CURVE_OPTIONS = FoldCurveOptions(ds=0.01, ds_min=1e-9, ds_max=0.02, lam_min=-math.pi / 2,
                                 lam_max=math.pi, tol=1e-12)


#: Bracketing cells per end the start's fold-pair solve uses (one point: the robust setting).
START_CELLS = 4


def _pair_start_program(G, M, D, disc):
    z, converged, _ = fold_pair_states(G, M, D, disc, START_CELLS)
    return z, converged


_pair_start = StoredProgram("fold-pair-start", _pair_start_program)


def _start(point: DesignPoint, n: int) -> np.ndarray:
    """The lower and upper folds of ``point`` as fold-curve states w = (theta, phi, alpha,
    u = 0), (2, 2m + 2): from the batched fold-pair path (one-mode brackets refined by
    Moore-Spence, ``jaxrod.magnet.batch``: 3 ms warm), or, where that path does not
    converge, the generic folds of the rig's branch in the magnet angle from the straight
    rod (``jaxrod.equilibria.folds``)."""
    G, M, D = point.groups()
    z, converged = jax.device_get(_pair_start(*(jnp.asarray(v, jnp.float64) for v in (G, M, D)),
                                              planar_discretisation(n, "clamped")))
    if converged:
        return np.concatenate([np.asarray(z), np.zeros((2, 1))], axis=1)
    scene, angle, (a0, a1), degrees, _ = rig_of(point)
    found = sorted(folds(scene, angle, a0, a1, n, throw=False), key=lambda f: f.value)
    if len(found) != 2 or not all(f.converged for f in found):
        raise ParameterError(
            f"no fold to start from: the rod at G = {G:.6g}, M = {M:.6g}, D = {D:.6g} has "
            f"{sum(f.converged for f in found)} converged fold(s) with alpha in (0, 90] "
            "degrees, not the lower and upper pair (it is not bistable there; start from a "
            "bistable point)")
    return np.stack([np.concatenate([f.state, f.null_vector,
                                     [math.radians(f.value * degrees), 0.0]]) for f in found])


def _compile_ahead(point: DesignPoint, vary: str, n: int, runs: int, cusp: bool) -> None:
    """Start compiling the trace of ``runs`` fold curves (and the cusp's refinement:
    ``cusp``) on a background thread while ``_start`` finds the fold pair
    (``Program.compile_ahead``). Only programs sure to run: a compilation that overlaps
    another slows it (XLA's compiler uses both cores)."""
    args = _Rig.of(point, n).args(point.index(vary))
    w = jax.ShapeDtypeStruct((2 * args[1].size + 2,), jnp.float64)
    trace_program.compile_ahead(jax.ShapeDtypeStruct((runs, *w.shape), jnp.float64),
                                jax.ShapeDtypeStruct((runs,), jnp.float64), args,
                                CURVE_OPTIONS, CAPACITY)
    if cusp:
        refine_program.compile_ahead(w, args, 0.0, False, True)


def _run(point, name, u_lo, u_hi, w0, directions, n, max_cusps):
    """The fold curves from the states w0 in the directions, and the engine's args."""
    args = _Rig.of(point, n).args(point.index(name))
    opts = CURVE_OPTIONS._replace(u_min=u_lo, u_max=u_hi, max_cusps=max_cusps)
    runs, observed = jax.device_get(trace_program(jnp.asarray(w0), jnp.asarray(directions),
                                                  args, opts, CAPACITY))
    return runs, observed, args


def _sign_changes(values):
    s = np.sign(values)
    return np.nonzero(s[:-1] * s[1:] < 0)[0]


def _nearest_change(test) -> int | None:
    """The point of the first sign change of ``test`` with the smaller |test| (None)."""
    change = _sign_changes(test)
    if not change.size:
        return None
    j = int(change[0])
    return j if abs(test[j]) < abs(test[j + 1]) else j + 1


def _columns(runs, observed, i, scales) -> tuple[dict, int | None]:
    """Run i's columns (``run_columns``), cut at its first cusp, and the point nearest it."""
    k = int(runs.num_points[i])
    cols = run_columns(runs, observed, i, k, scales)
    change = _sign_changes(cols["cusp_test"])
    cut = int(change[0]) + 1 if change.size else k
    return {c: v[:cut] for c, v in cols.items()}, _nearest_change(cols["cusp_test"])


def fold_curves(point: DesignPoint, vary: str, to: float,
                n: int = DEFAULT_N) -> tuple[FoldCurve, FoldCurve]:
    """Both fold curves of ``point`` (``name`` "lower", "upper") as the input ``vary`` goes
    to ``to``: the magnet angle at the fold (``ALPHA``, degrees) against ``vary``, each with
    its special points: the cusp where they meet (if it lies in the range: each curve ends
    there), where a fold leaves alpha in (0, 90] degrees ("alpha = 90 deg", "alpha = 0
    deg"), and the end at ``to``.

    Along a curve: grad E = 0, H phi = 0, l . phi = 1 in (theta, phi, alpha, u) with
    pseudo-arclength in (alpha, u). Paper: the folds of Proposition ``thm:planar_fold``
    followed in a second parameter; the design rule of section ``s.discussion``.
    """
    to = check_target(point, vary, to)
    v0 = point.values[point.index(vary)]
    _compile_ahead(point, vary, n, 2, cusp=False)
    w0 = _start(point, n)
    u_to = to / v0 - 1.0
    lo, hi = sorted((0.0, u_to))
    direction = math.copysign(1.0, u_to)
    # a curve that passes the cusp comes back as the other fold: stop it just past the start
    margin = 1e-3 * abs(u_to)
    runs, observed, args = _run(point, vary, lo - margin, hi + margin, w0,
                                [direction, direction], n, 1.0)
    scales, cusp, out = _scales(point, vary), None, []
    for i_run, name in enumerate(("lower", "upper")):
        cols, near = _columns(runs, observed, i_run, scales)
        if near is not None and cusp is None:
            cusp = special_point("cusp", runs.w[i_run][near], args, 0.0, scales)
        special = _alpha_events(runs, observed, i_run, args, scales, len(cols["values"]),
                                name)
        if near is not None:
            cols = with_point(cols, cusp, replace_last=False)
            special.insert(0, cusp)
        elif abs(cols["along_values"][-1] - v0) > abs(to - v0):  # passed `to`: end there
            end = special_point("u", cols["w"][-1], args, u_to, scales, curve=name)
            cols = with_point(cols, end, replace_last=True)
            special.append(end)
        del cols["w"]
        out.append(FoldCurve(vary=ALPHA, along=vary, start=None, name=name,
                             status=(Status(int(runs.status[i_run])),),
                             special_points=tuple(special), **cols))
    return tuple(out)


def _alpha_events(runs, observed, i, args, scales, k, name) -> list[FoldCurvePoint]:
    alpha = np.asarray(observed[1][i][:k])
    events = []
    for target, label in ((math.pi / 2, "alpha = 90 deg"), (0.0, "alpha = 0 deg")):
        for j in _sign_changes(alpha - target):
            near = j if abs(alpha[j] - target) < abs(alpha[j + 1] - target) else j + 1
            events.append(special_point("lam", runs.w[i][near], args, target, scales, label,
                                        name))
    return events


def trace_fold_curve(point: DesignPoint, vary: str, between: tuple[float, float],
                     direction: float = 1.0, start: str = "lower", max_cusps: int = 2,
                     n: int = DEFAULT_N) -> FoldCurve:
    """One fold curve followed round its cusps: from the ``start`` fold of ``point``, with
    ``vary`` first moving in ``direction`` (+1 or -1), through up to ``max_cusps`` cusps (at
    each the curve turns back in ``vary`` and continues as the other fold), while ``vary``
    stays ``between`` the two values given; the refined cusps are its special points, in
    the order passed."""
    v0 = point.values[point.index(vary)]
    lo, hi = sorted(check_target(point, vary, b) for b in between)
    if not lo < v0 < hi:
        raise ParameterError(f"between: {vary} = {v0!r} must lie inside ({lo!r}, {hi!r})")
    w0 = _start(point, n)
    runs, observed, args = _run(
        point, vary, lo / v0 - 1.0, hi / v0 - 1.0, w0[[0 if start == "lower" else 1]],
        [math.copysign(1.0, direction)], n, float(max_cusps))
    scales = _scales(point, vary)
    cols = run_columns(runs, observed, 0, int(runs.num_points[0]), scales)
    test, w = cols["cusp_test"], cols.pop("w")
    cusps = tuple(special_point("cusp", w[j if abs(test[j]) < abs(test[j + 1]) else j + 1],
                                args, 0.0, scales) for j in _sign_changes(test))
    return FoldCurve(vary=ALPHA, along=vary, start=None, name=start,
                     status=(Status(int(runs.status[0])),), special_points=cusps, **cols)


#: How far ``find_cusp`` looks: the varied input within a factor 20 of its start.
CUSP_SEARCH = (-0.95, 19.0)


def find_cusp(point: DesignPoint, vary: str, n: int = DEFAULT_N) -> FoldCurvePoint:
    """The cusp reached from ``point`` by varying ``vary``: the lower fold is followed both
    ways (within the valid range and a factor 20 of the start) to the nearest sign change of
    d2F/dq2, refined by Newton on the cusp system (``along_value``: ``vary`` there,
    ``value``: the magnet angle in degrees). Raises ``ParameterError`` if there is no fold to
    start from, and returns ``converged=False`` (with kind "none") if no cusp is found in
    the search range.

    The cusp solves the fold system with d2F/dq2 = 0 (the non-degeneracy condition of
    Proposition ``thm:planar_fold`` in the paper fails there).
    """
    v0 = point.values[point.index(vary)]
    lo, hi = valid_range(point, vary)
    # stop short of the magnet touching the rod (the clearance's last 1 %)
    u_lo = max(CUSP_SEARCH[0], (lo / v0 - 1.0) * 0.99 if lo > 0 else CUSP_SEARCH[0])
    u_hi = min(CUSP_SEARCH[1], (hi / v0 - 1.0) * 0.99 if math.isfinite(hi) else CUSP_SEARCH[1])
    _compile_ahead(point, vary, n, 2, cusp=True)
    w0 = _start(point, n)
    runs, observed, args = _run(point, vary, u_lo, u_hi, w0[[0, 0]], [1.0, -1.0], n, 1.0)
    scales, found = _scales(point, vary), []
    for i_run in (0, 1):
        cols, near = _columns(runs, observed, i_run, scales)
        if near is not None:
            found.append((np.sum(np.abs(np.diff(cols["along_values"]))), i_run, near))
    if not found:
        nan = math.nan
        return FoldCurvePoint("none", nan, nan, nan, nan, np.full(args[1].size, nan), False,
                              nan, 0, Status.NOT_CONVERGED)
    _, i_run, near = min(found)
    return special_point("cusp", runs.w[i_run][near], args, 0.0, scales)


def cusp_location(point: DesignPoint, vary: str, cusp: FoldCurvePoint, n: int = DEFAULT_N):
    """The cusp as a differentiable function of the design point's values:
    ``f(values) -> (value of vary, alpha in radians, Newton stats)``, by implicit
    differentiation of the cusp system about the converged ``cusp`` found from ``point``
    (``jaxrod.solvers.fold_curve.differentiable_cusp``). Compose it with ``jax.jacfwd`` for
    the cusp's sensitivity to the other inputs (the entry of ``vary`` itself has none).

    Paper: the cusp ends the hysteresis of eq. ``intro-hysteresis``; d2F/dq2 = 0 as in
    ``find_cusp``.
    """
    i = point.index(vary)
    rig = _Rig.of(point, n)
    m = rig.disc.size
    w_start = jnp.asarray(cusp.w)
    factors = rig.values / np.asarray(point.values)

    def location(values):
        args = rig.args(i, jnp.asarray(values) * factors)
        w, stats = differentiable_cusp(MODEL, SHIFT, w_start, args)
        return values[i] * (1.0 + w[2 * m + 1]), w[2 * m], stats

    return location
