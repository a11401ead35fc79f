"""The fold curve of any scene in two of its inputs (``vary``, ``along``), and its cusps.

A fold in ``vary`` moves as a second input ``along`` changes: pseudo-arclength continuation
of the Moore-Spence system in (x, phi, lam, u) (``jaxrod.solvers.fold_curve``) on the path
of the scene through its inputs, with vary = origin + span lam and the other inputs
``values + u direction`` (``Shift``): u on a scaled coordinate of ``along`` here, the relative
change of one input of a design point in ``jaxrod.bistability.fold_curves``; one compiled
program serves every pair of inputs of a scene. Along the curve the quadratic coefficient
F_qq = D^3E[phi, phi, phi] is recorded; where it changes sign the curve passes a cusp (the
two folds meet and the hysteresis closes), refined by Newton on the Moore-Spence system with
F_qq = 0 added (``refine``: the same Newton finds where a curve reaches a given lam or u),
with the cusp's cubic coefficient F_qqq.
"""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np

from jaxrod.equilibria.equilibrium import DEFAULT_N, MODEL, discretise, mean_functional, tip
from jaxrod.equilibria.folds import Fold, folds
from jaxrod.equilibria.trace import check_range
from jaxrod.params import ParameterError
from jaxrod.programs import jit
from jaxrod.scenes.files import FileScene
from jaxrod.scenes.path import ALONG
from jaxrod.scenes.path import along as along_path
from jaxrod.scenes.scene import Scene
from jaxrod.solvers.fold_curve import (
    FoldCurveOptions,
    cubic_coefficient,
    event_solve,
    fold_curve_run,
    parameter_lam,
    parameter_u,
    quadratic_coefficient,
    split,
)
from jaxrod.solvers.folds import fold_coefficients
from jaxrod.status import Status

CAPACITY = 512


@dataclasses.dataclass(frozen=True)
class Shift:
    """``args_at`` of the fold-curve solver: the path's other parameters at values + u
    direction, with args = (path, disc, origin, span, values, direction) (the fold's own
    parameter on its scaled coordinate, ``jaxrod.scenes.path.ALONG``)."""

    def __call__(self, u, args):
        path, disc, origin, span, values, direction = args
        return path, disc, origin, span, values + u * direction


SHIFT = Shift()


def _mean_row(disc):
    """The reduced coordinate q = c . x as its row c (``mean_functional``, any geometry)."""
    return jax.grad(mean_functional(disc))(jnp.zeros(disc.size, jnp.float64))


def _tip_at(w, m, args):
    x, _, lam, u = split(w, m)
    return tip(ALONG(lam, SHIFT(u, args))[0], x, args[1])[0]


def _trace_program(w0, directions, args, opts, capacity):
    """Fold curves from the states w0 (k, 2m + 2) in the directions (k,), with what each
    point records: (u, lam, q, tip angle, dF/dlam, F_qq, the two smallest eigenvalues of H),
    phi scaled to q(phi) = 1."""
    runs = jax.vmap(lambda w, d: fold_curve_run(MODEL, SHIFT, w, args, opts, capacity, d))(
        w0, directions)
    m = args[1].size
    each = lambda f: jax.vmap(jax.vmap(f))
    mean = mean_functional(args[1])
    phi_q = each(mean)(runs.w[..., m:2 * m])
    observed = (runs.w[..., -1], runs.w[..., 2 * m], each(mean)(runs.w[..., :m]),
                each(lambda w: _tip_at(w, m, args))(runs.w), runs.lam_derivative / phi_q,
                runs.cubic_form / phi_q**3, runs.smallest_eigenvalues)
    return runs, observed


trace_program = jit(_trace_program, static_argnames=("capacity",))

def _at_value(w, model, args_at, args):
    """lam or u at w (the event of a fold curve reaching a given value of either): the
    selector is the target's second entry (0: lam, 1: u)."""
    return jnp.where(args[-1], parameter_u(w, model, args_at, args[:-1]),
                     parameter_lam(w, model, args_at, args[:-1]))


class _Selected:
    """``args_at`` that drops the event's selector from args before ``Shift``."""

    def __call__(self, u, args):
        return SHIFT(u, args[:-1])


SELECTED = _Selected()


def _event_program(w0, args, target, at_u, cusp):
    """Newton on the fold system with the event ``kind`` at ``target``, and at the point:
    (u, lam, q, tip, dF/dlam, F_qq, two smallest eigenvalues) and F_qqq (a cusp only: the
    coefficient of the cusp's normal form; NaN at any other point)."""
    if cusp:
        res = event_solve(MODEL, SHIFT, w0, args, quadratic_coefficient, target, tol=1e-13)
    else:
        res = event_solve(MODEL, SELECTED, w0, args + (at_u,), _at_value, target, tol=1e-13)
    disc = args[1]
    m = disc.size
    x, phi, lam, u = split(res.x, m)
    a = SHIFT(u, args)
    mean = mean_functional(disc)
    d_lam, d_qq, _ = fold_coefficients(MODEL, x, lam, phi, a, mean)
    eigs = jnp.linalg.eigvalsh(MODEL.hessian(x, lam, a))[:2]
    report = (u, lam, mean(x), _tip_at(res.x, m, args), d_lam, d_qq, eigs)
    cubic = (cubic_coefficient(res.x, _mean_row(disc), MODEL, SHIFT, args) if cusp
             else jnp.nan)
    return res, report, cubic


#: One program for the cusp, one for a given lam or u (which of them a traced flag).
refine_program = jit(_event_program, static_argnames=("cusp",))


def refine(kind: str, w, args, target: float = 0.0):
    """(Newton's report, the point's observations, F_qqq) of the fold-curve point near w
    where ``kind`` ("cusp", "lam" or "u") reaches ``target`` (host arrays)."""
    return jax.device_get(refine_program(jnp.asarray(w), args, target, kind == "u",
                                         kind == "cusp"))


@dataclasses.dataclass(frozen=True)
class FoldCurvePoint:
    """A special point of a fold curve, refined by Newton on the Moore-Spence system with
    one equation added (``jaxrod.solvers.fold_curve.event_solve``, in (x, phi, v, u)):
    ``kind`` "cusp" where F_qq = D^3E[phi, phi, phi] = 0, "end" where the curve leaves the
    range of ``vary`` or of ``along``, or an event of the curve (the paper's "alpha = 90
    deg"). ``along_value``, ``value``: the two inputs there; ``curve``: the name of the
    curve it lies on; the state x, the solver's unknowns ``w`` = (x, phi, lam, u), the tip
    angle (degrees), q = mean(x), the fold's coefficients F_v = dF/d``value`` and F_qq
    (phi scaled to mean(phi) = 1), the Hessian's two smallest eigenvalues (one is zero at
    the fold), the cubic coefficient F_qqq of a cusp's normal form
    F = F_v (v - v_c) + F_qu (u - u_c) q + F_qqq q^3 / 6 (NaN elsewhere), and Newton's
    report."""

    kind: str
    along_value: float
    value: float
    tip_angle_deg: float
    cubic_coefficient: float
    state: np.ndarray
    converged: bool
    residual_norm: float
    iterations: int
    status: Status
    q: float = np.nan
    dF_dvalue: float = np.nan
    d2F_dq2: float = np.nan
    hessian_smallest: tuple[float, float] = (np.nan, np.nan)
    w: np.ndarray | None = None
    curve: str = ""

    def as_dict(self) -> dict:
        finite = lambda v: float(v) if np.isfinite(v) else None
        return {"kind": self.kind, "curve": self.curve, "along": self.along_value,
                "value": self.value, "tip_angle_deg": self.tip_angle_deg, "q": finite(self.q),
                "dF_dvalue": finite(self.dF_dvalue), "d2F_dq2": finite(self.d2F_dq2),
                "hessian_smallest_eigenvalues": [finite(e) for e in self.hessian_smallest],
                "cubic_coefficient": finite(self.cubic_coefficient),
                "converged": self.converged, "residual_norm": self.residual_norm,
                "iterations": self.iterations}


#: A fold curve's columns beside ``along_values`` and ``values`` (``FoldCurve.columns``).
COLUMNS = ("tip_angle_deg", "q", "dF_dvalue", "d2F_dq2", "newton_iterations",
           "residual_norm")


@dataclasses.dataclass(frozen=True)
class FoldCurve:
    """Points of a fold curve in order of the run, with what each records and its special
    points (the cusps passed, each end refined onto the range it leaves, events).

    ``along_values``: the second input; ``values``: ``vary`` at the fold; ``tip_angle_deg``:
    the tip at the fold; q = mean(x), ``dF_dvalue`` and ``d2F_dq2`` the fold's coefficients
    (phi scaled to mean(phi) = 1: F_qq changes sign at a cusp), ``hessian_smallest`` (k, 2)
    the Hessian's two smallest eigenvalues, Newton's iterations and residual at each point;
    ``cusp_test``: F_qq / |phi|^3; ``status``: why each direction ended; ``start``: the fold
    it starts from; ``name``: which curve it is (the paper's "lower", "upper").
    """

    vary: str
    along: str
    along_values: np.ndarray
    values: np.ndarray
    tip_angle_deg: np.ndarray
    cusp_test: np.ndarray
    status: tuple[Status, ...]
    start: Fold | None
    special_points: tuple[FoldCurvePoint, ...] = ()
    q: np.ndarray | None = None
    dF_dvalue: np.ndarray | None = None
    d2F_dq2: np.ndarray | None = None
    hessian_smallest: np.ndarray | None = None
    newton_iterations: np.ndarray | None = None
    residual_norm: np.ndarray | None = None
    name: str = ""

    @property
    def cusps(self) -> tuple[FoldCurvePoint, ...]:
        return tuple(p for p in self.special_points if p.kind == "cusp")

    @property
    def cusp_indices(self) -> np.ndarray:
        """i such that a cusp lies between points i and i + 1 (F_qq changes sign)."""
        c = self.cusp_test
        return np.nonzero(np.sign(c[:-1]) * np.sign(c[1:]) < 0)[0]

    @property
    def reaches_cusp(self) -> bool:
        return bool(self.cusps)

    @property
    def overall(self) -> Status:
        """The first direction that failed, else NOT_CONVERGED where a special point did
        not converge, else SUCCESS."""
        failed = [s for s in self.status if not s.ok]
        return failed[0] if failed else (Status.SUCCESS if all(
            p.converged for p in self.special_points) else Status.NOT_CONVERGED)

    @property
    def converged(self) -> bool:
        return self.overall == Status.SUCCESS

    def columns(self) -> dict[str, np.ndarray]:
        """The curve's points as named columns (along, value, ``COLUMNS``, eig0, eig1)."""
        cols = {self.along: self.along_values, self.vary: self.values}
        cols |= {k: getattr(self, k) for k in COLUMNS if getattr(self, k) is not None}
        if self.hessian_smallest is not None:
            cols |= {"eig0": self.hessian_smallest[:, 0], "eig1": self.hessian_smallest[:, 1]}
        return cols

    def as_dict(self) -> dict:
        return {"vary": self.vary, "along": self.along, "name": self.name,
                **{k: np.asarray(v).tolist() for k, v in self.columns().items()},
                "special_points": [p.as_dict() for p in self.special_points],
                "status": [s.name.lower() for s in self.status],
                "overall": self.overall.name.lower(), "converged": self.converged}

    def plot(self, ax=None):
        """``vary`` at the fold against ``along``; cusps marked."""
        import matplotlib.pyplot as plt

        ax = ax or plt.gca()
        ax.plot(self.along_values, self.values, "-", color="C0", label=f"fold in {self.vary}")
        if self.cusps:
            ax.plot([c.along_value for c in self.cusps], [c.value for c in self.cusps], "k^",
                    label="cusp (refined)")
        ax.set_xlabel(self.along)
        ax.set_ylabel(self.vary)
        return ax


def special_point(kind, w, args, target, scales, label=None, curve="") -> FoldCurvePoint:
    """The point near w where ``kind`` ("cusp", "lam", "u") reaches ``target``, in the
    inputs' units: scales = (origin, span, origin2, span2) with value = origin + span lam and
    along = origin2 + span2 u; ``label`` its kind (default "cusp" or "end")."""
    res, (u, lam, q, angle, d_lam, d_qq, eigs), cubic = refine(kind, w, args, target)
    origin, span, origin2, span2 = scales
    conv = bool(res.converged)
    return FoldCurvePoint(
        label or ("cusp" if kind == "cusp" else "end"), origin2 + span2 * float(u),
        origin + span * float(lam), float(np.degrees(angle)), float(cubic),
        np.asarray(res.x)[:args[1].size], conv, float(res.residual_norm), int(res.iterations),
        Status.of(conv), q=float(q), dF_dvalue=float(d_lam) / span, d2F_dq2=float(d_qq),
        hessian_smallest=(float(eigs[0]), float(eigs[1])), w=np.asarray(res.x), curve=curve)


def run_columns(runs, observed, i: int, k: int, scales) -> dict:
    """The first k points of run i of ``trace_program`` as ``FoldCurve``'s fields (the
    inputs' units, ``special_point``'s scales) and the states ``w``."""
    origin, span, origin2, span2 = scales
    u, lam, q, angle, d_lam, d_qq, eigs = (np.asarray(o[i][:k]) for o in observed)
    return {"along_values": origin2 + span2 * u, "values": origin + span * lam,
            "tip_angle_deg": np.degrees(angle), "cusp_test": np.asarray(runs.cusp_test[i][:k]),
            "q": q, "dF_dvalue": d_lam / span, "d2F_dq2": d_qq, "hessian_smallest": eigs,
            "newton_iterations": np.asarray(runs.newton_iterations[i][:k]),
            "residual_norm": np.asarray(runs.residual_norm[i][:k]),
            "w": np.asarray(runs.w[i][:k])}


def fold_curve(scene: Scene | FileScene, vary: str, vary_range: tuple[float, float], along: str,
               along_range: tuple[float, float], which: int = 0, n: int = DEFAULT_N,
               ds_max: float = 0.02, start: Fold | None = None) -> FoldCurve:
    """The fold curve through the ``which``-th fold met along ``vary`` (over ``vary_range``,
    at the scene's value of ``along``), followed in ``along`` over ``along_range``; or from
    ``start``, a fold of the scene's branch in ``vary`` at degree ``n`` (a special point of
    ``jaxrod.branch``, or one of ``jaxrod.folds``: the branch is not traced again).

    Solves R(x, phi, v; u) = [grad E; H phi; l . phi - 1] = 0 along the curve (paper: the
    fold curves of section "Fold curves and the cusp", for any scene).
    """
    lo_hi = check_range(scene, vary, *vary_range)
    a0, a1 = check_range(scene, along, *along_range)
    if along == vary:
        raise ParameterError(f"along must differ from vary ({vary})")
    path = along_path(scene, (vary, along))
    u_now = float(path.value(along))
    if not min(a0, a1) <= u_now <= max(a0, a1):
        raise ParameterError(f"the scene's {along} = {u_now:g} is outside along_range "
                             f"[{min(a0, a1):g}, {max(a0, a1):g}]")
    disc = discretise(path.template, n)
    if start is None:
        found = folds(scene, vary, lo_hi[0], lo_hi[1], n)
        if len(found) <= which:
            raise ParameterError(f"the branch in {vary} from {lo_hi[0]:g} to {lo_hi[1]:g} has "
                                 f"{len(found)} fold(s); which = {which} asks for fold "
                                 f"{which + 1}")
        f = found[which]
    else:
        f = _checked_start(start, vary, disc.size, lo_hi)
    origin, span = min(lo_hi), abs(lo_hi[1] - lo_hi[0])
    origin2, span2 = min(a0, a1), abs(a1 - a0)
    args = (path, disc, origin, span, jnp.array([origin2]), jnp.array([span2]))
    w0 = jnp.concatenate([jnp.asarray(f.state), jnp.asarray(f.null_vector),
                          jnp.array([(f.value - origin) / span, (u_now - origin2) / span2])])
    opts = FoldCurveOptions(ds=0.01, ds_max=ds_max, u_min=0.0, u_max=1.0, lam_min=0.0,
                            lam_max=1.0)
    runs, observed = jax.device_get(trace_program(jnp.stack([w0, w0]), jnp.array([-1.0, 1.0]),
                                                  args, opts, CAPACITY))
    scales, m = (origin, span, origin2, span2), disc.size
    parts, status, ends = [], [], []
    for i, rev in ((0, True), (1, False)):
        k = int(runs.num_points[i])
        cols = run_columns(runs, observed, i, k, scales)
        lam, u = runs.w[i, k - 1, 2 * m], runs.w[i, k - 1, 2 * m + 1]
        if int(runs.status[i]) == Status.REACHED_BOUND:  # its last point is just outside
            kind = "lam" if not 0.0 <= lam <= 1.0 else "u"
            target = float(np.clip(lam if kind == "lam" else u, 0.0, 1.0))
            end = special_point(kind, runs.w[i, k - 1], args, target, scales)
            other = (end.along_value - origin2) / span2 if kind == "lam" else \
                (end.value - origin) / span  # the other input, scaled: inside [0, 1]
            if not -1e-9 <= other <= 1.0 + 1e-9:
                end = dataclasses.replace(end, converged=False, status=Status.NOT_CONVERGED)
            ends.append(end)
            if end.converged:  # the curve ends on the range exactly
                cols = with_point(cols, end, replace_last=True)
        # the start point once
        parts.append({c: v[::-1][:-1] if rev else v for c, v in cols.items()})
        status.append(Status(int(runs.status[i])))
    cat = {c: np.concatenate([p[c] for p in parts]) for c in parts[0]}
    w = cat.pop("w")
    curve = FoldCurve(vary=vary, along=along, status=tuple(status), start=f, **cat)
    cusps = []
    for j in curve.cusp_indices:  # each from the bracket's point with the smaller |F_qq|
        pick = j if abs(curve.cusp_test[j]) <= abs(curve.cusp_test[j + 1]) else j + 1
        c = special_point("cusp", w[pick], args, 0.0, scales)
        # converged, and within its bracket's step of the nearer of its two points, in the
        # solver's unknowns (both inputs are stationary at a cusp: the curve turns back in
        # each, so the cusp may lie beyond the bracket's range of either)
        step = np.linalg.norm(w[j + 1] - w[j])
        if not min(np.linalg.norm(c.w - w[j]), np.linalg.norm(c.w - w[j + 1])) <= step:
            c = dataclasses.replace(c, converged=False, status=Status.NOT_CONVERGED)
        cusps.append(c)
    return dataclasses.replace(curve, special_points=tuple(cusps + ends))


def _checked_start(fold, vary: str, size: int, vary_range) -> Fold:
    """A given starting fold: a converged fold in ``vary``, inside its range, whose state
    has the discretisation's size (the same N)."""
    if not isinstance(fold, Fold):
        raise ParameterError(f"start: a fold (jaxrod.folds, or a branch's special point of "
                             f"kind 'fold'), got {type(fold).__name__}")
    if fold.vary != vary:
        raise ParameterError(f"start: a fold in {fold.vary}, not in vary = {vary}")
    if not fold.converged:
        raise ParameterError("start: the fold's refinement did not converge")
    if np.size(fold.state) != size:
        raise ParameterError(f"start: the fold's state has {np.size(fold.state)} unknowns, "
                             f"the curve's N gives {size} (compute both at the same n)")
    if not min(vary_range) <= fold.value <= max(vary_range):
        raise ParameterError(f"start: the fold's {vary} = {fold.value:g} lies outside "
                             f"vary_range")
    return fold


def with_point(cols: dict, point: FoldCurvePoint, replace_last: bool) -> dict:
    """``run_columns``' columns with the refined ``point`` as their last row (replacing the
    last, or appended); the cusp test is zero at a cusp, kept at an end."""
    row = {"along_values": point.along_value, "values": point.value,
           "tip_angle_deg": point.tip_angle_deg, "q": point.q, "dF_dvalue": point.dF_dvalue,
           "d2F_dq2": point.d2F_dq2, "hessian_smallest": point.hessian_smallest,
           "newton_iterations": point.iterations, "residual_norm": point.residual_norm,
           "w": point.w, "cusp_test": 0.0 if point.kind == "cusp" else cols["cusp_test"][-1]}
    keep = slice(None, -1) if replace_last else slice(None)
    return {c: np.concatenate([v[keep], np.asarray([row[c]], v.dtype)]) for c, v in cols.items()}


__all__ = ["FoldCurve", "FoldCurvePoint", "Shift", "fold_curve", "refine", "run_columns",
           "special_point", "trace_program", "with_point"]
