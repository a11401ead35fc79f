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

from jaxrod.bistability.fold_curve import CAPACITY, SHIFT, refine, refine_program, trace_program
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


@dataclasses.dataclass(frozen=True)
class CurvePoint:
    """A refined point of a fold curve: the cusp, or where a fold reaches alpha = 0 or 90."""

    kind: str  # "cusp", "alpha = 90 deg", "alpha = 0 deg"
    vary: str
    value: float
    alpha_deg: float
    q: float
    tip_deg: float
    dF_dalpha: float
    d2F_dq2: float
    cubic_coefficient: float  # F_qqq of the cusp's normal form (NaN at any other point)
    hessian_smallest: tuple[float, float]
    converged: bool
    residual_norm: float
    iterations: int
    state: np.ndarray  # (theta, phi, alpha, u), u relative to the starting point's value
    fold: str = ""  # the fold curve it lies on ("lower" or "upper"; "" for a cusp)

    def as_dict(self) -> dict:
        return {self.vary: self.value, "fold": self.fold, "alpha_deg": self.alpha_deg,
                "q": self.q,
                "tip_deg": self.tip_deg, "dF_dalpha": self.dF_dalpha, "d2F_dq2": self.d2F_dq2,
                "cubic_coefficient": (self.cubic_coefficient
                                      if math.isfinite(self.cubic_coefficient) else None),
                "hessian_smallest_eigenvalues": list(self.hessian_smallest),
                "converged": self.converged, "residual_norm": self.residual_norm,
                "iterations": self.iterations}


@dataclasses.dataclass(frozen=True)
class FoldCurve:
    """One traced fold curve (host arrays, valid points only), cut at its first cusp."""

    start: str  # "lower" or "upper": the fold it starts from
    value: np.ndarray  # the varied input along the curve
    alpha_deg: np.ndarray
    q: np.ndarray
    tip_deg: np.ndarray
    dF_dalpha: np.ndarray
    d2F_dq2: np.ndarray
    hessian_smallest: np.ndarray  # (n, 2)
    newton_iterations: np.ndarray
    residual_norm: np.ndarray
    status: Status
    reaches_cusp: bool

    def columns(self) -> dict[str, np.ndarray]:
        return {"value": self.value, "alpha_deg": self.alpha_deg, "q": self.q,
                "tip_deg": self.tip_deg, "dF_dalpha": self.dF_dalpha, "d2F_dq2": self.d2F_dq2,
                "eig0": self.hessian_smallest[:, 0], "eig1": self.hessian_smallest[:, 1],
                "newton_iterations": self.newton_iterations,
                "residual_norm": self.residual_norm}


@dataclasses.dataclass(frozen=True)
class FoldCurves:
    """Both fold curves from a design point, the cusp (if one lies in the range) and where a
    fold leaves alpha in (0, 90] degrees."""

    point: DesignPoint
    vary: str
    to: float
    n: int
    curves: list[FoldCurve]
    cusp: CurvePoint | None
    events: list[CurvePoint]

    @property
    def converged(self) -> bool:
        good = all(c.status in (Status.REACHED_BOUND, Status.CUSP_PASSED) for c in self.curves)
        return good and (self.cusp is None or self.cusp.converged) and all(
            e.converged for e in self.events)

    def as_dict(self) -> dict:
        return {"vary": self.vary, "to": self.to, "n": self.n, "point": self.point.as_dict(),
                "cusp": None if self.cusp is None else self.cusp.as_dict(),
                "events": [e.kind for e in self.events],
                "event_points": [e.as_dict() for e in self.events],
                "curves": {c.start: {k: v.tolist() for k, v in c.columns().items()}
                           | {"status": str(c.status), "reaches_cusp": c.reaches_cusp}
                           for c in self.curves},
                "converged": self.converged}


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


def _refine(kind, w, target, args, name, v0, label) -> CurvePoint:
    res, rep, cubic = refine(kind, w, args, target)
    u, alpha, q, tip, d_alpha, d_qq, eigs = rep
    return CurvePoint(kind=label, vary=name, value=float(v0 * (1.0 + u)),
                      alpha_deg=math.degrees(float(alpha)), q=float(q),
                      tip_deg=math.degrees(float(tip)), dF_dalpha=float(d_alpha),
                      d2F_dq2=float(d_qq), cubic_coefficient=float(cubic),
                      hessian_smallest=(float(eigs[0]), float(eigs[1])),
                      converged=bool(res.converged), residual_norm=float(res.residual_norm),
                      iterations=int(res.iterations), state=np.asarray(res.x))


def _sign_changes(values):
    s = np.sign(values)
    return np.nonzero(s[:-1] * s[1:] < 0)[0]


def _curve_from(run, observed, i, start, v0) -> tuple[FoldCurve, int | None]:
    k = int(run.num_points[i])
    u, alpha, q, tip, d_alpha, d_qq, eigs = (np.asarray(o[i][:k]) for o in observed)
    change = _sign_changes(run.cusp_test[i][:k])
    cut = int(change[0]) + 1 if change.size else k
    curve = FoldCurve(
        start=start, value=v0 * (1.0 + u[:cut]), alpha_deg=np.degrees(alpha[:cut]),
        q=q[:cut], tip_deg=np.degrees(tip[:cut]), dF_dalpha=d_alpha[:cut],
        d2F_dq2=d_qq[:cut], hessian_smallest=eigs[:cut],
        newton_iterations=np.asarray(run.newton_iterations[i][:cut]),
        residual_norm=np.asarray(run.residual_norm[i][:cut]),
        status=Status(int(run.status[i])), reaches_cusp=bool(change.size))
    near = None
    if change.size:
        j = int(change[0])
        t = run.cusp_test[i]
        near = j if abs(t[j]) < abs(t[j + 1]) else j + 1
    return curve, near


def fold_curves(point: DesignPoint, vary: str, to: float, n: int = DEFAULT_N) -> FoldCurves:
    """Both fold curves of ``point`` as the input ``vary`` goes to ``to``, the cusp where they
    meet (if it lies in the range) and where a fold leaves alpha in (0, 90] degrees.

    Along a curve: grad E = 0, H phi = 0, l . phi = 1 in (theta, phi, alpha, u) with
    pseudo-arclength in (alpha, u). Paper: the folds of Proposition ``thm:planar_fold``
    followed in a second parameter; the design rule of section ``s.discussion``.
    """
    i = point.index(vary)
    to = check_target(point, vary, to)
    v0 = point.values[i]
    _compile_ahead(point, vary, n, 2, cusp=False)
    w0 = _start(point, n)
    u_to = to / v0 - 1.0
    lo, hi = sorted((0.0, u_to))
    direction = math.copysign(1.0, u_to)
    # a curve that passes the cusp comes back as the other fold: stop it just past the start
    margin = 1e-3 * abs(u_to)
    runs, observed, args = _run(point, vary, lo - margin, hi + margin, w0,
                                [direction, direction], n, 1.0)
    curves, cusp, events = [], None, []
    for i_run, start in enumerate(("lower", "upper")):
        curve, near = _curve_from(runs, observed, i_run, start, v0)
        if near is not None and cusp is None:
            cusp = _refine("cusp", runs.w[i_run][near], 0.0, args, vary, v0, "cusp")
        events += [dataclasses.replace(e, fold=start) for e in _alpha_events(
            runs, observed, i_run, args, vary, v0, len(curve.value))]
        if curve.reaches_cusp:
            curve = _with_end(curve, cusp)
        elif abs(curve.value[-1] - v0) > abs(to - v0):  # passed `to`: end exactly there
            k = len(curve.value) - 1
            end = _refine("u", runs.w[i_run][k], u_to, args, vary, v0, "end")
            curve = _with_end(dataclasses.replace(curve, **{
                f.name: getattr(curve, f.name)[:-1] for f in dataclasses.fields(curve)
                if isinstance(getattr(curve, f.name), np.ndarray)}), end)
        curves.append(curve)
    return FoldCurves(point=point, vary=vary, to=to, n=n, curves=curves, cusp=cusp,
                      events=events)


def _with_end(curve: FoldCurve, end: CurvePoint) -> FoldCurve:
    """The curve with the refined point ``end`` (the cusp, or the end value) appended."""
    add = lambda a, v: np.concatenate([a, np.atleast_1d(np.asarray(v, a.dtype))], axis=0)
    return dataclasses.replace(
        curve, value=add(curve.value, end.value), alpha_deg=add(curve.alpha_deg, end.alpha_deg),
        q=add(curve.q, end.q), tip_deg=add(curve.tip_deg, end.tip_deg),
        dF_dalpha=add(curve.dF_dalpha, end.dF_dalpha), d2F_dq2=add(curve.d2F_dq2, end.d2F_dq2),
        hessian_smallest=add(curve.hessian_smallest, [end.hessian_smallest]),
        newton_iterations=add(curve.newton_iterations, end.iterations),
        residual_norm=add(curve.residual_norm, end.residual_norm))


def _alpha_events(runs, observed, i, args, vary, v0, k) -> list[CurvePoint]:
    alpha = np.asarray(observed[1][i][:k])
    events = []
    for target, label in ((math.pi / 2, "alpha = 90 deg"), (0.0, "alpha = 0 deg")):
        for j in _sign_changes(alpha - target):
            near = j if abs(alpha[j] - target) < abs(alpha[j + 1] - target) else j + 1
            events.append(_refine("lam", runs.w[i][near], target, args, vary, v0, label))
    return events


def trace_fold_curve(point: DesignPoint, vary: str, between: tuple[float, float],
                     direction: float = 1.0, start: str = "lower", max_cusps: int = 2,
                     n: int = DEFAULT_N):
    """One fold curve followed round its cusps: from the ``start`` fold of ``point``, with
    ``vary`` first moving in ``direction`` (+1 or -1), through up to ``max_cusps`` cusps (at
    each the curve turns back in ``vary`` and continues as the other fold), while ``vary``
    stays ``between`` the two values given. Returns (the values of ``vary`` along the run,
    alpha* in degrees, the refined cusps in the order passed, the run's status message)."""
    i = point.index(vary)
    v0 = point.values[i]
    lo, hi = sorted(check_target(point, vary, b) for b in between)
    if not lo < v0 < hi:
        raise ParameterError(f"between: {vary} = {v0!r} must lie inside ({lo!r}, {hi!r})")
    w0 = _start(point, n)
    runs, observed, args = _run(
        point, vary, lo / v0 - 1.0, hi / v0 - 1.0, w0[[0 if start == "lower" else 1]],
        [math.copysign(1.0, direction)], n, float(max_cusps))
    k = int(runs.num_points[0])
    test = np.asarray(runs.cusp_test[0][:k])
    cusps = []
    for j in _sign_changes(test):
        near = j if abs(test[j]) < abs(test[j + 1]) else j + 1
        cusps.append(_refine("cusp", runs.w[0][near], 0.0, args, vary, v0, "cusp"))
    u, alpha = np.asarray(observed[0][0][:k]), np.asarray(observed[1][0][:k])
    return v0 * (1.0 + u), np.degrees(alpha), cusps, Status(int(runs.status[0]))


#: How far ``find_cusp`` looks: the varied input within a factor 20 of its start.
CUSP_SEARCH = (-0.95, 19.0)


def find_cusp(point: DesignPoint, vary: str, n: int = DEFAULT_N) -> CurvePoint:
    """The cusp reached from ``point`` by varying ``vary``: the lower fold is followed both
    ways (within the valid range and a factor 20 of the start) to the nearest sign change of
    d2F/dq2, refined by Newton on the cusp system. Raises ``ParameterError`` if there is no
    fold to start from, and returns ``converged=False`` (with kind "none") if no cusp is
    found in the search range.

    The cusp solves the fold system with d2F/dq2 = 0 (the non-degeneracy condition of
    Proposition ``thm:planar_fold`` in the paper fails there).
    """
    i = point.index(vary)
    v0 = point.values[i]
    lo, hi = valid_range(point, vary)
    # stop short of the magnet touching the rod (the clearance's last 1 %)
    u_lo = max(CUSP_SEARCH[0], (lo / v0 - 1.0) * 0.99 if lo > 0 else CUSP_SEARCH[0])
    u_hi = min(CUSP_SEARCH[1], (hi / v0 - 1.0) * 0.99 if math.isfinite(hi) else CUSP_SEARCH[1])
    _compile_ahead(point, vary, n, 2, cusp=True)
    w0 = _start(point, n)
    runs, observed, args = _run(point, vary, u_lo, u_hi, w0[[0, 0]], [1.0, -1.0], n, 1.0)
    found = []
    for i_run in (0, 1):
        curve, near = _curve_from(runs, observed, i_run, "lower", v0)
        if near is not None:
            found.append((np.sum(np.abs(np.diff(curve.value))), i_run, near))
    if not found:
        return CurvePoint("none", vary, math.nan, math.nan, math.nan, math.nan, math.nan,
                          math.nan, math.nan, (math.nan, math.nan), False, math.nan, 0,
                          np.full(2 * planar_discretisation(n).size + 2, np.nan))
    _, i_run, near = min(found)
    return _refine("cusp", runs.w[i_run][near], 0.0, args, vary, v0, "cusp")


def cusp_location(point: DesignPoint, vary: str, cusp: CurvePoint, n: int = DEFAULT_N):
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
    w_start = jnp.asarray(cusp.state)
    factors = rig.values / np.asarray(point.values)

    def location(values):
        args = rig.args(i, jnp.asarray(values) * factors)
        w, stats = differentiable_cusp(MODEL, SHIFT, w_start, args)
        return values[i] * (1.0 + w[2 * m + 1]), w[2 * m], stats

    return location
