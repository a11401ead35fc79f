"""Maps of the folds of any scene over two of its inputs.

At every point (x, y) of a grid the branch in ``vary`` is traced from the ramped equilibrium
at the range's start (``jaxrod.equilibria``), its folds are counted (sign changes of dv/ds)
and the first two refined by Moore-Spence: two folds in the range mean a hysteresis loop
(bistability between them). One compiled program runs a chunk of points (vmapped); chunks
run one after another with a progress bar, and Ctrl-C keeps the finished ones.
"""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np

from jaxrod.derivatives import Structured
from jaxrod.equilibria.branch import check_range
from jaxrod.equilibria.equilibrium import DEFAULT_N, discretise, ramp
from jaxrod.params import ParameterError
from jaxrod.programs import jit
from jaxrod.progress import Interrupted, interrupt_requested, progress_bar
from jaxrod.scenes.scene import Input, Scene
from jaxrod.solvers.continuation import REACHED_BOUND, ContinuationOptions, continuation_run
from jaxrod.solvers.folds import moore_spence_solve
from jaxrod.status import Status

CHUNK = 64
CAPACITY = 160
MAX_POINTS = 1_000_000
OPTIONS = ContinuationOptions(ds=0.01, ds_min=1e-9, ds_max=0.05, lam_min=0.0, lam_max=1.0,
                              tol=1e-12, max_points=0)


@dataclasses.dataclass(frozen=True)
class FoldMap:
    """Folds of ``vary`` over a grid of ``x_key`` (columns) and ``y_key`` (rows).

    ``count``: folds met along the range (-1 where not computed); ``first``, ``second``: the
    first two folds' values of ``vary`` (NaN where fewer); ``status``: a ``Status`` code per
    point (NOT_CONVERGED where the branch or a refinement failed).
    """

    vary: str
    vary_range: tuple[float, float]
    x_key: str
    x_values: np.ndarray
    y_key: str
    y_values: np.ndarray
    count: np.ndarray
    first: np.ndarray
    second: np.ndarray
    status: np.ndarray

    @property
    def bistable(self) -> np.ndarray:
        """Two folds or more: a hysteresis loop in the range."""
        return self.count >= 2

    def plot(self, ax=None):
        """The number of folds per point (cells), failures hatched."""
        import matplotlib.pyplot as plt

        ax = ax or plt.gca()
        shown = np.ma.masked_where(self.status != int(Status.SUCCESS), self.count)
        mesh = ax.pcolormesh(self.x_values, self.y_values, shown, shading="nearest",
                             cmap="viridis", vmin=0, vmax=max(2, int(np.max(self.count))))
        bad = self.status != int(Status.SUCCESS)
        if bad.any():
            ax.contourf(self.x_values, self.y_values, bad.astype(float), levels=[0.5, 1.5],
                        hatches=["xx"], colors="none")
        ax.figure.colorbar(mesh, ax=ax, label=f"folds in {self.vary}")
        ax.set_xlabel(self.x_key)
        ax.set_ylabel(self.y_key)
        return ax


def _point(xv, yv, scene, disc, origin, span, vary, x_key, y_key):
    sc = scene.replace(x_key, xv).replace(y_key, yv)
    model = Structured(Input(vary))
    args = (sc, disc, origin, span)
    x0, ok0, *_ = ramp(sc.replace(vary, origin), disc)
    run = continuation_run(model, x0, 0.0, args, OPTIONS, CAPACITY, 1.0, spectrum=False)
    t = run.tangent_lam
    valid = jnp.arange(CAPACITY - 1) < run.num_points - 1
    change = valid & (jnp.sign(t[:-1]) * jnp.sign(t[1:]) < 0)
    count = jnp.sum(change)
    # the first two sign changes, refined from the point with the smaller |dv/ds|
    order = jnp.argsort(jnp.where(change, jnp.arange(CAPACITY - 1), CAPACITY))[:2]

    def refine(i):
        j = jnp.where(jnp.abs(t[i]) <= jnp.abs(t[i + 1]), i, i + 1)
        x, lam = run.x[j], run.lam[j]
        phi0 = jnp.linalg.eigh(model.hessian(x, lam, args))[1][:, 0]
        fp = moore_spence_solve(model, x, lam, phi0, args)
        return origin + span * fp.lam, fp.newton.converged

    values, conv = jax.vmap(refine)(order)
    have = jnp.arange(2) < count
    values = jnp.where(have, values, jnp.nan)
    good = ok0 & (run.status == REACHED_BOUND) & jnp.all(conv | ~have)
    status = jnp.where(good, int(Status.SUCCESS), int(Status.NOT_CONVERGED))
    return count, values[0], values[1], status


def _chunk_program(X, Y, scene, disc, origin, span, vary, x_key, y_key):
    return jax.vmap(lambda a, b: _point(a, b, scene, disc, origin, span, vary, x_key,
                                        y_key))(X, Y)


_chunk = jit(_chunk_program, static_argnames=("vary", "x_key", "y_key"))


def fold_map(scene: Scene, vary: str, vary_range: tuple[float, float],
             x: tuple[str, np.ndarray], y: tuple[str, np.ndarray], n: int = DEFAULT_N,
             progress: bool = True) -> FoldMap:
    """Folds of ``vary`` over ``vary_range`` at every point of the grid x = (key, values),
    y = (key, values). Ctrl-C raises ``Interrupted`` whose ``partial`` is the map so far."""
    start, stop = check_range(scene, vary, *vary_range)
    (x_key, xs), (y_key, ys) = x, y
    for key in (x_key, y_key):
        scene.check_key(key)
        if key == vary:
            raise ParameterError(f"the map's axes must differ from vary ({vary})")
    xs, ys = np.asarray(xs, float).ravel(), np.asarray(ys, float).ravel()
    if xs.size < 2 or ys.size < 2 or xs.size * ys.size > MAX_POINTS:
        raise ParameterError(f"a map needs 2 to {MAX_POINTS} points with at least 2 per axis, "
                             f"got {xs.size} x {ys.size}")
    if not (np.all(np.isfinite(xs)) and np.all(np.isfinite(ys))):
        raise ParameterError("the map's axis values must be finite")
    disc = discretise(scene, n)
    X, Y = (v.ravel() for v in np.meshgrid(xs, ys))
    total = X.size
    out = [np.full(total, -1), np.full(total, np.nan), np.full(total, np.nan),
           np.full(total, int(Status.NOT_CONVERGED))]
    bar = progress_bar(total, "fold map", unit="point", enabled=progress)

    def result():
        shape = (ys.size, xs.size)
        return FoldMap(vary, (start, stop), x_key, xs, y_key, ys,
                       *(o.reshape(shape) for o in out))

    for lo in range(0, total, CHUNK):
        idx = np.arange(lo, min(lo + CHUNK, total))
        pad = np.concatenate([idx, np.full(CHUNK - idx.size, idx[-1])])
        got = jax.device_get(_chunk(jnp.asarray(X[pad]), jnp.asarray(Y[pad]), scene, disc,
                                    start, stop - start, vary, x_key, y_key))
        for o, g in zip(out, got):
            o[idx] = np.asarray(g)[:idx.size]
        bar.update(idx.size)
        if interrupt_requested():
            bar.close()
            raise Interrupted(result(), f"after {idx[-1] + 1} of {total} points")
    bar.close()
    return result()
