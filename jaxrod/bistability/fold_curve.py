"""The fold curve of any scene in two of its inputs (``vary``, ``along``), and its cusps.

A fold in ``vary`` moves as a second input ``along`` changes: pseudo-arclength continuation
of the Moore-Spence system in (x, phi, v, u) (``jaxrod.solvers.fold_curve``), both inputs on
their scaled coordinates (v = start + span lam, u the same for ``along``), from a fold found
on the branch. Along the curve the quadratic coefficient F_qq = D^3E[phi, phi, phi] is
recorded; where it changes sign the curve passes a cusp (the two folds meet and the
hysteresis closes), refined by Newton on the Moore-Spence system with F_qq = 0 added.
"""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np

from jaxrod.equilibria.equilibrium import DEFAULT_N, MODEL, discretise, tip
from jaxrod.equilibria.folds import Fold, folds
from jaxrod.equilibria.trace import check_range
from jaxrod.params import ParameterError
from jaxrod.programs import jit
from jaxrod.scenes.files import FileScene
from jaxrod.scenes.path import ALONG
from jaxrod.scenes.path import along as along_path
from jaxrod.scenes.scene import Scene
from jaxrod.solvers.fold_curve import FoldCurveOptions, event_solve, fold_curve_run, split
from jaxrod.status import Status

CAPACITY = 400


@dataclasses.dataclass(frozen=True)
class Second:
    """``args_at`` of the fold-curve solver: the path's second parameter on its scaled
    coordinate, with args = (path, disc, origin, span, origin2, span2)."""

    def __call__(self, u, args):
        path, disc, origin, span, origin2, span2 = args
        return path, disc, origin, span, jnp.reshape(origin2 + span2 * u, (1,))


SECOND = Second()


@dataclasses.dataclass(frozen=True)
class Cusp:
    """A cusp of a fold curve, refined: the fold where F_qq = D^3E[phi, phi, phi] = 0
    (``jaxrod.solvers.fold_curve.event_solve``: the Moore-Spence system with that equation
    added, in (x, phi, v, u)). ``along_value``, ``value``: the two inputs there; the state,
    the tip angle (degrees), and Newton's report."""

    along_value: float
    value: float
    tip_angle_deg: float
    state: np.ndarray
    converged: bool
    residual_norm: float
    iterations: int
    status: Status

    def as_dict(self) -> dict:
        return {"along": self.along_value, "value": self.value,
                "tip_angle_deg": self.tip_angle_deg, "converged": self.converged,
                "residual_norm": self.residual_norm, "iterations": self.iterations}


@dataclasses.dataclass(frozen=True)
class FoldCurve:
    """Points of a fold curve (both directions from the starting fold, joined in order of
    ``along``), with the cusp test F_qq / |phi|^3 at each and the cusps passed.

    ``along_values``: the second input; ``values``: ``vary`` at the fold; ``tip_angle_deg``:
    the tip at the fold; ``status``: why each direction ended.
    """

    vary: str
    along: str
    along_values: np.ndarray
    values: np.ndarray
    tip_angle_deg: np.ndarray
    cusp_test: np.ndarray
    status: tuple[Status, ...]
    start: Fold
    cusps: tuple[Cusp, ...] = ()

    @property
    def cusp_indices(self) -> np.ndarray:
        """i such that a cusp lies between points i and i + 1 (F_qq changes sign)."""
        c = self.cusp_test
        return np.nonzero(np.sign(c[:-1]) * np.sign(c[1:]) < 0)[0]

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


def _tip_at(w, m, args):
    x, _, lam, u = split(w, m)
    return tip(ALONG(lam, SECOND(u, args))[0], x, args[1])[0]


def _curve_program(w0, directions, path, disc, origin, span, origin2, span2, opts, capacity):
    args = (path, disc, origin, span, origin2, span2)
    runs = jax.vmap(lambda d: fold_curve_run(MODEL, SECOND, w0, args, opts, capacity, d))(
        directions)
    return runs, jax.vmap(jax.vmap(lambda w: _tip_at(w, disc.size, args)))(runs.w)


_program = jit(_curve_program, static_argnames=("capacity",))


def _cusp_program(w0, path, disc, origin, span, origin2, span2):
    args = (path, disc, origin, span, origin2, span2)
    res = event_solve(MODEL, SECOND, w0, args)
    return res, _tip_at(res.x, disc.size, args)


_cusps = jit(jax.vmap(_cusp_program, in_axes=(0, None, None, None, None, None, None)))


def fold_curve(scene: Scene | FileScene, vary: str, vary_range: tuple[float, float], along: str,
               along_range: tuple[float, float], which: int = 0, n: int = DEFAULT_N,
               ds_max: float = 0.02) -> FoldCurve:
    """The fold curve through the ``which``-th fold met along ``vary`` (over ``vary_range``,
    at the scene's value of ``along``), followed in ``along`` over ``along_range``.

    Solves R(x, phi, v; u) = [grad E; H phi; l . phi - 1] = 0 along the curve (paper: the
    fold curves of section "Fold curves and the cusp", for any scene).
    """
    start, stop = check_range(scene, vary, *vary_range)
    a0, a1 = check_range(scene, along, *along_range)
    if along == vary:
        raise ParameterError(f"along must differ from vary ({vary})")
    path = along_path(scene, (vary, along))
    u_now = float(path.value(along))
    if not min(a0, a1) <= u_now <= max(a0, a1):
        raise ParameterError(f"the scene's {along} = {u_now:g} is outside along_range "
                             f"[{min(a0, a1):g}, {max(a0, a1):g}]")
    found = folds(scene, vary, start, stop, n)
    if len(found) <= which:
        raise ParameterError(f"the branch in {vary} from {start:g} to {stop:g} has "
                             f"{len(found)} fold(s); which = {which} asks for fold "
                             f"{which + 1}")
    f = found[which]
    disc = discretise(path.template, n)
    lo, hi = min(start, stop), max(start, stop)
    origin, span = lo, hi - lo
    origin2, span2 = min(a0, a1), abs(a1 - a0)
    w0 = jnp.concatenate([jnp.asarray(f.state), jnp.asarray(f.null_vector),
                          jnp.array([(f.value - origin) / span, (u_now - origin2) / span2])])
    opts = FoldCurveOptions(ds=0.01, ds_max=ds_max, u_min=0.0, u_max=1.0, lam_min=0.0,
                            lam_max=1.0)
    runs, angle = jax.device_get(_program(w0, jnp.array([-1.0, 1.0]), path, disc, origin,
                                          span, origin2, span2, opts, CAPACITY))
    m = disc.size
    parts, status = [], []
    for i, rev in ((0, True), (1, False)):
        k = int(runs.num_points[i])
        w = runs.w[i, :k]
        cols = [origin2 + span2 * w[:, 2 * m + 1], origin + span * w[:, 2 * m],
                np.degrees(angle[i, :k]), runs.cusp_test[i, :k], w]
        cols = [c[::-1] if rev else c for c in cols]
        parts.append([c[:-1] if rev else c for c in cols])  # the start point once
        status.append(Status(int(runs.status[i])))
    cat = [np.concatenate([p[j] for p in parts]) for j in range(5)]
    curve = FoldCurve(vary=vary, along=along, along_values=cat[0], values=cat[1],
                      tip_angle_deg=cat[2], cusp_test=cat[3], status=tuple(status), start=f)
    idx = curve.cusp_indices
    if len(idx) == 0:
        return curve
    # each cusp refined from the bracket's point with the smaller |F_qq|
    test = curve.cusp_test
    pick = np.where(np.abs(test[idx]) <= np.abs(test[idx + 1]), idx, idx + 1)
    res, angles = jax.device_get(_cusps(jnp.asarray(cat[4][pick]), path, disc, origin, span,
                                        origin2, span2))
    cusps = []
    for i, j in enumerate(idx):
        x, _, lam, u = split(res.x[i], m)
        a_value, value = origin2 + span2 * float(u), origin + span * float(lam)
        # converged, and in its bracket (widened by the bracket's width on each side)
        a_lo, a_hi = sorted((float(curve.along_values[j]), float(curve.along_values[j + 1])))
        width = max(a_hi - a_lo, 1e-12 * span2)
        conv = bool(res.converged[i]) and a_lo - width <= a_value <= a_hi + width
        cusps.append(Cusp(a_value, value, float(np.degrees(angles[i])), np.asarray(x), conv,
                          float(res.residual_norm[i]), int(res.iterations[i]),
                          Status.of(conv)))
    return dataclasses.replace(curve, cusps=tuple(cusps))


__all__ = ["Cusp", "FoldCurve", "fold_curve"]
