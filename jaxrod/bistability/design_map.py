"""Bistability maps over two inputs: capture and release angles and the hysteresis width on
a grid, chunked on disk, resumable, sharded over devices and processes.

A map varies two inputs of a ``DesignPoint`` (groups or physical inputs, the others fixed)
over a grid ``name:start:stop:count`` each. Every grid point goes through up to four
tiers, those of ``jaxrod.magnet.batch.fold_pairs``, so no point is dropped silently:

1. the batched fold-pair path (``jaxrod.magnet.batch.fold_pair_states``: one-mode brackets
   and Moore-Spence, fixed cost per point), vmapped over a chunk;
2. points it does not converge are retried by the same path started from more bracketing
   cells (``batch.RETRY_CELLS`` at each end instead of one: the small clearances);
3. points still failing are retried by a batched continuation from the straight rod
   (the ``locate_folds`` algorithm, vmapped: pseudo-arclength in alpha up to 180 degrees,
   the first two folds refined by Moore-Spence), which also tells why there is no pair;
4. points still failing there are retried by ``locate_folds`` itself, one by one.

The retry tiers run on padded batches (``programs.retry_size``), so that a map compiles each
of their programs a few times, not once per number of failures.

Each point ends with a ``jaxrod.Status`` code (``REASONS``): OK, NOT_BISTABLE (the branch
through the straight rod has fewer than two folds with alpha in (0, 180] degrees),
FOLD_BEYOND_90 (a fold leaves alpha in (0, 90]: the experiment's magnet cannot reach it),
INVALID_INPUT (the magnet would touch the rod, or an input is not positive) or NOT_CONVERGED;
angles are NaN unless OK.

The grid is written chunk by chunk into a store of ``jaxrod.bistability.grid_store`` (Zarr
version 2, written with numpy; ``xarray.open_zarr`` reads it): variables ``capture_deg`` (the
lower fold: the magnet angle where the disengaged rod is captured), ``release_deg`` (the upper
fold), ``width_deg`` and ``status`` on dimensions named by the two inputs (y first), with
units and provenance attributes; ``status`` is -1 (``NOT_COMPUTED``, outside the codes) where
a chunk was not written yet. A killed run started again with the same arguments skips the
complete chunks and loses nothing.

Scale-out uses JAX's own machinery: a chunk's points are laid out over all local devices
with a ``jax.sharding.NamedSharding`` (one mesh axis, the points) and ``jax.shard_map`` runs
the batched program on each device's share independently (the retry tiers, a small share
of a map, run on the first device); with ``jax.distributed`` initialised, each process computes
and writes its own share of the chunks (``grid_store``).
"""

from __future__ import annotations

import dataclasses
import functools
import json
import math
from pathlib import Path

import jax
import numpy as np

from jaxrod.bistability.fold_curves import find_cusp, fold_curves
from jaxrod.bistability.grid_store import NOT_COMPUTED, GridAxis, GridStore, Variable, read
from jaxrod.design_point import DesignPoint, groups_of, range_of
from jaxrod.magnet.batch import (  # noqa: F401 (the status codes, re-exported)
    BISTABLE,
    FOLD_BEYOND_90,
    INVALID_INPUT,
    NOT_BISTABLE,
    NOT_CONVERGED,
    STATUS,
    batch_fold_angles,
    batch_fold_angles_program,
    resolve_failures,
)
from jaxrod.params import UNITS, ParameterError
from jaxrod.programs import bucket, jit, padded

#: The status codes of a map's points (``jaxrod.Status``; ``jaxrod.magnet.batch.STATUS``
#: says what each means for the paper's map; OK is BISTABLE, Status.SUCCESS).
OK, REASONS = BISTABLE, STATUS
VARIABLES = ("capture_deg", "release_deg", "width_deg", "status")
#: Chebyshev degree of the map's solves (the batched path's default: the fold angles reach
#: their round-off floor from N = 12 at the paper's parameters).
MAP_N = 12


@dataclasses.dataclass(frozen=True)
class MapAxis:
    """One grid axis: ``count`` values of the input ``name`` from ``start`` to ``stop``."""

    name: str
    start: float
    stop: float
    count: int

    @classmethod
    def parse(cls, text: str) -> MapAxis:
        """``name:start:stop:count`` (as on the command line)."""
        parts = text.rsplit(":", 3)
        if len(parts) != 4:
            raise ParameterError(f"axis must be name:start:stop:count, got {text!r}")
        name, start, stop, count = parts
        try:
            start_v, stop_v, count_v = float(start), float(stop), int(count)
        except ValueError:
            raise ParameterError(f"axis {text!r}: start and stop must be numbers and count "
                                 "an integer") from None
        if not (math.isfinite(start_v) and math.isfinite(stop_v)) or start_v == stop_v:
            raise ParameterError(f"axis {name}: start and stop must be finite and differ, "
                                 f"got {start!r}, {stop!r}")
        if not 2 <= count_v <= 100_000:
            raise ParameterError(f"axis {name}: count must be in [2, 100000] (a map needs two "
                                 f"values per axis; one point is `jaxrod folds`), got {count_v}")
        return cls(name, start_v, stop_v, count_v)

    def values(self) -> np.ndarray:
        return np.linspace(self.start, self.stop, self.count)


#: The earlier name of ``MapAxis`` (deep imports keep working).
Axis = MapAxis


def _grid_values(point: DesignPoint, x: MapAxis, y: MapAxis) -> np.ndarray:
    """(y.count, x.count, len(point.values)): every grid point's inputs."""
    ix, iy = point.index(x.name), point.index(y.name)
    if ix == iy:
        raise ParameterError(f"x and y must be different inputs, both are {x.name!r}")
    base = np.broadcast_to(np.asarray(point.values, np.float64),
                           (y.count, x.count, len(point.values))).copy()
    base[:, :, ix] = x.values()[None, :]
    base[:, :, iy] = y.values()[:, None]
    return base


def _validity(point: DesignPoint, values: np.ndarray) -> np.ndarray:
    """True where every input and the groups they make lie in their ranges
    (``jaxrod.params.RANGES``) and the magnet clears the rod (D > 1 + a / L)."""
    names = point.names
    ok = np.ones(values.shape[:-1], bool)
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        for i, name in enumerate(names):
            v = values[..., i]
            ok &= np.isfinite(v) & range_of(name).contains(v)
        G, M, D = groups_of(point.kind, np.moveaxis(values, -1, 0))
        radius = (point.magnet_radius if point.kind == "groups"
                  else 0.5 * values[..., 7] / values[..., 4])
        return (ok & range_of("G").contains(G) & range_of("M").contains(M)
                & range_of("D").contains(D) & (D > 1.0 + radius))


# --- tier 1 sharded over devices; tiers 2 to 4 are ``batch.resolve_failures`` -----------


@functools.lru_cache(maxsize=16)
def _per_device(devices: tuple, n: int):
    """The batched fold-pair program as one independent program per device
    (``jax.shard_map`` over a one-axis mesh of the points): each device runs its own Newton
    loops to its own slowest point, with no collective in the loop conditions. On one device
    it is ``batch_fold_angles_program`` itself (kept in the command line's store)."""
    mesh = jax.sharding.Mesh(np.asarray(devices), ("points",))
    if len(devices) == 1:
        return functools.partial(batch_fold_angles_program, n=n, cells=1), mesh
    spec = jax.sharding.PartitionSpec("points")
    fn = functools.partial(batch_fold_angles, n=n)
    return jit(jax.shard_map(fn, mesh=mesh, in_specs=(spec, spec, spec),
                             out_specs=(spec, spec), check_vma=False)), mesh


def _sharded(arrays, mesh, size: int | None = None):
    """Pad the 1-D arrays to ``size`` points (at least their own) rounded up to a multiple of
    the mesh's device count and lay them out over it (the points split between devices)."""
    k = arrays[0].shape[0]
    size = max(k, size or k)
    sharding = jax.sharding.NamedSharding(mesh, jax.sharding.PartitionSpec("points"))
    # padding repeats the first point (a valid parameter set), dropped afterwards
    return [jax.device_put(a, sharding)
            for a in padded(arrays, size, multiple=mesh.size)], k


def solve_points(point: DesignPoint, values: np.ndarray, n: int = MAP_N,
                 devices=None, size: int | None = None) -> dict[str, np.ndarray]:
    """Capture/release angles (deg), width and status for rows of input ``values`` (K, P);
    ``size``: the batch the first tier runs (the rows padded to it; a map's chunk size, so
    that its edge chunks run the same compiled program; default ``programs.bucket``)."""
    devices = list(devices or jax.local_devices())
    k = values.shape[0]
    valid = _validity(point, values)
    G, M, D = (np.asarray(v, np.float64) for v in groups_of(point.kind, values.T))
    # invalid rows get a harmless stand-in (the first valid row, or the design point)
    stand_in = values[np.argmax(valid)] if valid.any() else np.asarray(point.values)
    g0, m0, d0 = (float(v) for v in groups_of(point.kind, stand_in))
    G, M, D = (np.where(valid, v, s) for v, s in ((G, g0), (M, m0), (D, d0)))
    alphas = np.full((k, 2), np.nan)
    reason = np.where(valid, NOT_CONVERGED, INVALID_INPUT).astype(np.int8)
    if valid.any():
        program, mesh = _per_device(tuple(devices), n)
        inputs, _ = _sharded([G, M, D], mesh, size or bucket(k))
        a1, ok = jax.device_get(program(*inputs))
        a1, ok = np.asarray(a1)[:k], np.asarray(ok)[:k] & valid
        alphas[ok] = a1[ok]
        reason[ok] = OK
        with jax.default_device(devices[0]):  # the retry tiers: a small share of a map
            resolve_failures(G, M, D, alphas, reason, np.ones(k, np.int8), n)
    alphas = np.where((reason == OK)[:, None], alphas, np.nan)
    deg = np.degrees(alphas)
    return {"capture_deg": deg[:, 0], "release_deg": deg[:, 1],
            "width_deg": deg[:, 1] - deg[:, 0], "status": reason}


# --- the on-disk store (``jaxrod.bistability.grid_store``) --------------------------------

LONG_NAMES = {"capture_deg": "magnet angle of the lower fold (capture of the disengaged rod)",
              "release_deg": "magnet angle of the upper fold (release of the engaged rod)",
              "width_deg": "hysteresis width, release - capture",
              "status": f"jaxrod.Status code: {OK} bistable; {NOT_BISTABLE} not bistable; "
              f"{FOLD_BEYOND_90} a fold beyond 90 deg; {INVALID_INPUT} invalid input; "
              f"{NOT_CONVERGED} not converged; -1 not computed (missing chunk)"}
#: The map's variables (``status`` last: it marks a chunk complete).
_VARIABLES = {name: Variable("|i1" if name == "status" else "<f8",
                             "1" if name == "status" else "degree", LONG_NAMES[name])
              for name in VARIABLES}


#: The most points of one map: its inputs (up to 9 per point, float64) are laid out in memory
#: at once (1e7 points: 0.7 GB), and a map of 1e6 points takes ~20 min on 2 CPU cores.
MAX_POINTS = 10_000_000


@dataclasses.dataclass(frozen=True)
class MapSpec:
    """What a map computes: the design point, both axes, the chunk size and N."""

    point: DesignPoint
    x: MapAxis
    y: MapAxis
    chunk: int = 50
    n: int = MAP_N

    def __post_init__(self):
        points = self.x.count * self.y.count
        if points > MAX_POINTS:
            raise ParameterError(f"x, y: the grid has {self.x.count} x {self.y.count} = "
                                 f"{points:.3g} points; at most {MAX_POINTS:.0e} in one map "
                                 "(split it into several maps over parts of the range)")
        if not 4 <= self.chunk <= 1000:
            raise ParameterError(f"chunk must be in [4, 1000], got {self.chunk}")

    def chunks(self) -> list[tuple[int, int]]:
        """(iy, ix) chunk indices, row-major."""
        ny, nx = -(-self.y.count // self.chunk), -(-self.x.count // self.chunk)
        return [(i, j) for i in range(ny) for j in range(nx)]

    def description(self) -> dict:
        return {"point": self.point.as_dict(), "kind": self.point.kind,
                "x": dataclasses.asdict(self.x), "y": dataclasses.asdict(self.y),
                "chunk": self.chunk, "n": self.n}


def map_store(out: Path, spec: MapSpec) -> GridStore:
    """The map's store at ``out`` (``jaxrod.bistability.grid_store``): its variables, axes,
    chunks, and the description a resumed run must match."""
    import importlib.metadata

    try:
        version = importlib.metadata.version("jaxrod")
    except importlib.metadata.PackageNotFoundError:
        version = "unknown"
    fixed = {k: v for k, v in spec.point.as_dict().items()
             if k not in (spec.x.name, spec.y.name)}
    attrs = {"title": f"jaxrod bistability map over {spec.x.name} and {spec.y.name}",
             "source": f"jaxrod {version} (jax {jax.__version__}), N = {spec.n} Chebyshev",
             "fixed_inputs": json.dumps(fixed), "status_codes": json.dumps(
                 {str(k): v for k, v in (REASONS | {NOT_COMPUTED: "not computed"}).items()})}
    axis = lambda a: GridAxis(a.name, tuple(a.values()), UNITS[a.name] or "1")
    return GridStore(Path(out), _VARIABLES, axis(spec.x), axis(spec.y), spec.chunk,
                     json.dumps(spec.description(), sort_keys=True), attrs)


STORE = "map.zarr"


def store_path(out: Path) -> Path:
    """The Zarr store of a map written to the folder ``out`` by the command line
    (``out/map.zarr``, beside map.png and map.json), or ``out`` itself when it is a store."""
    out = Path(out)
    return out / STORE if (out / STORE / ".zgroup").exists() else out


def read_store(out: Path) -> dict[str, np.ndarray]:
    """The map's variables and axes from a store written here (numpy only): the variables
    of ``VARIABLES`` (``status`` NOT_COMPUTED where a chunk was not written), the axes by
    their inputs' names and as ``x`` and ``y``. ``out``: the store, or the folder that holds
    it (``store_path``)."""
    return read(store_path(out))


def run_map(spec: MapSpec, out: Path, progress: bool = True, devices=None) -> dict:
    """Compute the map into the store ``out`` (resuming a partial one), this process's
    chunks only when ``jax.distributed`` runs several processes. Returns counts.

    Paper: the width of eq. ``intro-hysteresis`` over two inputs; the design rule of section
    ``s.discussion``.
    """
    values = _grid_values(spec.point, spec.x, spec.y)
    store = map_store(out, spec)

    def solve(iy, ix):
        rows, cols = store.rows_and_columns(iy, ix)
        block = values[rows, cols]
        h, w = block.shape[:2]
        res = solve_points(spec.point, block.reshape(h * w, -1), spec.n, devices,
                           spec.chunk * spec.chunk)
        return {k: v.reshape(h, w) for k, v in res.items()}

    return store.fill(solve, progress, "map")


def fold_crossings(spec, data, rows: int = 12) -> list[dict]:
    """Where the upper fold reaches alpha = 90 degrees on up to ``rows`` grid rows: the fold
    curves in x from each row's widest bistable point to both ends of the axis
    (``fold_curves``), their "alpha = 90 deg" events. With the cusps they bound the
    bistable region independently of the grid (paper: the folds of Proposition
    ``thm:planar_fold`` followed in x)."""
    out = []
    for iy in np.unique(np.linspace(0, spec.y.count - 1, rows).astype(int)):
        width = np.where(data["status"][iy] == OK, data["width_deg"][iy], -np.inf)
        if not np.isfinite(width.max()) or not (data["status"][iy] == FOLD_BEYOND_90).any():
            continue
        ix = int(np.argmax(width))
        start = spec.point.replace(spec.x.name, data["x"][ix]).replace(spec.y.name,
                                                                       data["y"][iy])
        for end in (spec.x.start, spec.x.stop):
            if end == data["x"][ix]:
                continue
            try:
                curves = fold_curves(start, spec.x.name, end)
            except ParameterError:
                continue
            out += [{spec.y.name: float(data["y"][iy]), spec.x.name: e.along_value}
                    for c in curves for e in c.special_points
                    if e.kind == "alpha = 90 deg" and e.converged]
    return out


def cusp_curve(spec, data, rows: int = 12) -> list[dict]:
    """The cusp in x on up to ``rows`` grid rows, each from the row's widest bistable
    point (``find_cusp``): the cusp curve in the map's plane, where the two fold curves of
    each row meet and the hysteresis closes (paper: the width of eq. ``intro-hysteresis``
    goes to zero)."""
    out = []
    for iy in np.unique(np.linspace(0, spec.y.count - 1, rows).astype(int)):
        width = np.where(data["status"][iy] == OK, data["width_deg"][iy], -np.inf)
        if not np.isfinite(width.max()):
            continue
        ix = int(np.argmax(width))
        start = spec.point.replace(spec.x.name, data["x"][ix]).replace(spec.y.name,
                                                                       data["y"][iy])
        try:
            cusp = find_cusp(start, spec.x.name)
        except ParameterError:
            continue
        if cusp.converged:
            out.append({spec.y.name: float(data["y"][iy]), spec.x.name: cusp.along_value,
                        "alpha_deg": cusp.value})
    return out
