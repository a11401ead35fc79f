"""Maps of the folds of any scene over two of its inputs.

At every point (x, y) of a grid the branch in ``vary`` is traced from the ramped equilibrium
at the range's start (``jaxrod.equilibria``), its folds are counted (sign changes of dv/ds)
and the first two refined by Moore-Spence: two folds in the range mean a hysteresis loop
(bistability between them). One compiled program runs a square chunk of grid points
(vmapped, and laid out over the local devices with ``jax.shard_map``, each device running its
share independently); chunks run one after another with a progress bar, and Ctrl-C keeps the
finished ones. Given a folder, the map is written chunk by chunk into a resumable store
(``jaxrod.bistability.grid_store``), which the processes of a ``jax.distributed`` run share.
"""

from __future__ import annotations

import dataclasses
import functools
import json
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np

from jaxrod.bistability.grid_store import GridAxis, GridStore, Variable, read
from jaxrod.equilibria.equilibrium import DEFAULT_N, MODEL, discretise, run_from_rest
from jaxrod.equilibria.trace import check_range
from jaxrod.params import ParameterError
from jaxrod.programs import jit, padded
from jaxrod.progress import Interrupted, interrupt_requested, progress_bar
from jaxrod.scenes.files import FileScene
from jaxrod.scenes.path import along
from jaxrod.scenes.scene import Scene
from jaxrod.solvers.continuation import REACHED_BOUND, ContinuationOptions
from jaxrod.solvers.folds import moore_spence_solve
from jaxrod.status import Status

#: Points of a map point's branch: a hard-magnetic rod at load 10 turned by a field through
#: 270 degrees needs ~700 steps of ds_max; its first two folds come within the first 320.
CAPACITY = 320
MAX_POINTS = 1_000_000
OPTIONS = ContinuationOptions(ds=0.01, ds_min=1e-9, ds_max=0.05, lam_min=0.0, lam_max=1.0,
                              tol=1e-12, max_points=0)


@dataclasses.dataclass(frozen=True)
class FoldMap:
    """Folds of ``vary`` over a grid of ``x_key`` (columns) and ``y_key`` (rows).

    ``count``: folds met along the range (-1 where not computed); ``first``, ``second``: the
    first two folds' values of ``vary`` (NaN where fewer); ``status``: a ``Status`` code per
    point: SUCCESS where the first two folds converged (or the branch reached the range's
    end with fewer), NOT_CONVERGED where the ramp or a fold's refinement failed, the
    branch's own status (CAPACITY_FULL, STEP_TOO_SMALL) where it ended before the range's
    end with fewer than two folds (a later one may be missing).
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

    def plot(self, ax=None, factor: float = 1.0, label: str | None = None):
        """The first fold's value of ``vary`` per point (cells; divided by ``factor``, e.g.
        to a scene file's unit; ``label`` names it on the colour bar), white where there is
        none, failed points marked (x) and named in the legend."""
        import matplotlib.pyplot as plt

        ax = ax or plt.gca()
        ok = self.status == int(Status.SUCCESS)
        shown = np.ma.masked_where(~ok | np.isnan(self.first), self.first / factor)
        mesh = ax.pcolormesh(self.x_values, self.y_values, shown, shading="nearest",
                             cmap="viridis")
        ax.figure.colorbar(mesh, ax=ax, label=label or f"the first fold's {self.vary}")
        X, Y = np.meshgrid(self.x_values, self.y_values)
        bad = (self.status != int(Status.SUCCESS)) & (self.status >= 0)
        if bad.any():
            ax.plot(X[bad], Y[bad], "rx", ms=5, ls="none",
                    label=f"failed ({int(bad.sum())} of {bad.size}: see status)")
        none = ok & (self.count == 0)
        if none.any():
            ax.plot(X[none], Y[none], ".", color="0.6", ms=3, ls="none", label="no fold")
        if bad.any() or none.any():
            ax.legend(fontsize=8, loc="best")
        ax.set_xlabel(self.x_key)
        ax.set_ylabel(self.y_key)
        return ax


def _point(xv, yv, path, disc, origin, span):
    model = MODEL
    rest = jnp.stack([xv, yv])
    args = (path, disc, origin, span, rest)
    run, start, _ = run_from_rest(path, disc, origin, span, OPTIONS, CAPACITY, rest=rest,
                                  spectrum=False)
    ok0 = start.converged
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
    # a point's status is what its answer is: the first two folds, both converged, whatever
    # the branch met after them; fewer than two, the branch must have reached the range's end
    # (else its own status says why the rest is missing)
    refined = jnp.all(conv | ~have)
    status = jnp.where(
        ~ok0 | ~refined, int(Status.NOT_CONVERGED),
        jnp.where((count >= 2) | (run.status == REACHED_BOUND), int(Status.SUCCESS),
                  run.status))
    return count, values[0], values[1], status


def _chunk_program(X, Y, path, disc, origin, span):
    return jax.vmap(lambda a, b: _point(a, b, path, disc, origin, span))(X, Y)


@functools.lru_cache(maxsize=16)
def _per_device(devices: tuple):
    """The chunk's program as one independent program per device (``jax.shard_map`` over a
    one-axis mesh of the points; the scene and the range replicated): each device runs its
    own continuations to its own slowest point, with no collective in the loops."""
    mesh = jax.sharding.Mesh(np.asarray(devices), ("points",))
    points, same = jax.sharding.PartitionSpec("points"), jax.sharding.PartitionSpec()
    return jit(jax.shard_map(_chunk_program, mesh=mesh,
                             in_specs=(points, points, same, same, same, same),
                             out_specs=points, check_vma=False)), mesh


def _solve_chunk(X, Y, path, disc, start, span, devices, chunk):
    """(count, first, second, status) at the points (X, Y) of one chunk, padded to the
    chunk's size (one compiled shape for the edge chunks too) rounded up to a multiple of the
    devices, and laid out over them."""
    program, mesh = _per_device(tuple(devices))
    k = X.size
    X, Y = padded([X, Y], chunk * chunk, multiple=mesh.size)
    sharding = jax.sharding.NamedSharding(mesh, jax.sharding.PartitionSpec("points"))
    got = jax.device_get(program(jax.device_put(X, sharding), jax.device_put(Y, sharding),
                                 path, disc, start, span))
    return [np.asarray(g)[:k] for g in got]


#: The variables of a fold map's store (``status`` last: it marks a chunk complete).
VARIABLES = {
    "count": Variable("<i2", "1", "folds met along the range; -1 not computed"),
    "first": Variable("<f8", "1", "the first fold's value of the varied input"),
    "second": Variable("<f8", "1", "the second fold's value of the varied input"),
    "status": Variable("<i2", "1", "jaxrod.Status code: 0 success, 6 capacity full, 7 step "
                       "too small, 11 not converged; -1 not computed"),
}


def fold_map(scene: Scene | FileScene, vary: str, vary_range: tuple[float, float],
             x: tuple[str, np.ndarray], y: tuple[str, np.ndarray], n: int = DEFAULT_N,
             progress: bool = True, out=None, chunk: int = 8, devices=None,
             units: dict | None = None) -> FoldMap:
    """Folds of ``vary`` over ``vary_range`` at every point of the grid x = (key, values),
    y = (key, values), computed in square chunks of ``chunk`` points a side, each laid out
    over ``devices`` (default: all local devices).

    With ``out`` (a folder), the chunks are written into a store there
    (``jaxrod.bistability.grid_store``: Zarr, read back by ``read_fold_map``): a run
    started again with the same arguments resumes it, and with ``jax.distributed`` each
    process computes its own share of the chunks (the map returned then holds that share,
    count -1 elsewhere; ``read_fold_map`` reads the whole). ``units`` (key -> unit) labels the
    store's axes. Without ``out``, Ctrl-C raises ``Interrupted`` whose ``partial`` is the
    map so far; with it, the finished chunks are on disk."""
    start, stop = check_range(scene, vary, *vary_range)
    (x_key, xs), (y_key, ys) = x, y
    for key in (x_key, y_key):
        if key == vary:
            raise ParameterError(f"the map's axes must differ from vary ({vary})")
    path = along(scene, (vary, x_key, y_key))
    xs, ys = np.asarray(xs, float).ravel(), np.asarray(ys, float).ravel()
    if xs.size < 2 or ys.size < 2 or xs.size * ys.size > MAX_POINTS:
        raise ParameterError(f"a map needs 2 to {MAX_POINTS} points with at least 2 per axis, "
                             f"got {xs.size} x {ys.size}")
    if not (np.all(np.isfinite(xs)) and np.all(np.isfinite(ys))):
        raise ParameterError("the map's axis values must be finite")
    if not 2 <= chunk <= 1000:
        raise ParameterError(f"chunk must be in [2, 1000], got {chunk}")
    disc = discretise(path.template, n)
    devices = list(devices or jax.local_devices())
    units = units or {}
    store = GridStore(out, VARIABLES, GridAxis(x_key, tuple(xs), units.get(x_key, "1")),
                      GridAxis(y_key, tuple(ys), units.get(y_key, "1")), chunk,
                      json.dumps({"scene": repr(scene), "vary": vary, "range": [start, stop],
                                  "n": n, "chunk": chunk}),
                      {"title": f"jaxrod fold map of {vary} over {x_key} and {y_key}"})
    grid = [np.full(store.shape, v.fill, np.dtype(v.dtype)) for v in VARIABLES.values()]
    X, Y = np.meshgrid(xs, ys)

    def result():
        return FoldMap(vary, (start, stop), x_key, xs, y_key, ys, *grid)

    def solve(iy, ix):
        rows, cols = store.rows_and_columns(iy, ix)
        shape = X[rows, cols].shape
        got = _solve_chunk(X[rows, cols].ravel(), Y[rows, cols].ravel(), path, disc, start,
                           stop - start, devices, chunk)
        for g, part in zip(grid, got):
            g[rows, cols] = part.reshape(shape)
        return {name: part.reshape(shape) for name, part in zip(VARIABLES, got)}

    if out is not None:
        store.fill(solve, progress, "fold map")
        return result()
    bar = progress_bar(len(store.chunks()), "fold map", unit="chunk", enabled=progress)
    for k, (iy, ix) in enumerate(store.chunks()):
        solve(iy, ix)
        bar.update(1)
        if interrupt_requested():
            bar.close()
            raise Interrupted(result(), f"after {k + 1} of {len(store.chunks())} chunks")
    bar.close()
    return result()


def read_fold_map(out) -> FoldMap:
    """The fold map in the store ``out`` written by ``fold_map(..., out=...)`` (numpy only;
    count and status -1 where a chunk was not written yet)."""
    data = read(out)
    made = json.loads(json.loads((Path(out) / ".zattrs").read_text())["jaxrod_map"])
    dims = json.loads((Path(out) / "status" / ".zattrs").read_text())["_ARRAY_DIMENSIONS"]
    y_key, x_key = dims
    return FoldMap(made["vary"], tuple(made["range"]), x_key, data["x"], y_key, data["y"],
                   *(data[name] for name in VARIABLES))
