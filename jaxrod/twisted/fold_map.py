"""The folds of a twisted rod along one input over a grid of two others: a map.

At every point (x_i, y_j) of the grid the branch along ``vary`` is followed over its range
(``jaxrod.twisted.branch.folds_along``) to its second fold (or its first, where one is
all that is asked for): the map holds how many folds it met (0, 1 or 2: two folds bound a
hysteresis, the range of ``vary`` where two states are stable), the first two folds'
values and each point's status (SUCCESS where the branch up to its end is resolved). The
points are visited row by row, each row in the direction the last one ended (a
serpentine), and each start is solved by Newton from its neighbour's; a point whose start
fails is solved again by the rod's own path. Every point is one continuation of the same
compiled program; the inputs are traced, so the grid costs one compilation.
"""

from __future__ import annotations

import numpy as np

from jaxrod.bistability.fold_map import FoldMap
from jaxrod.bistability.grid_store import NOT_COMPUTED
from jaxrod.equilibria.resolution import TOLERANCE
from jaxrod.params import ParameterError
from jaxrod.progress import Interrupted, progress_bar
from jaxrod.solvers.continuation import REACHED_BOUND
from jaxrod.status import Status
from jaxrod.twisted.branch import folds_along
from jaxrod.twisted.rod import TwistedRod

__all__ = ["twist_fold_map"]


def _point_status(folds, branch) -> Status:
    """SUCCESS where the branch reached the range's end or its second fold, every fold
    refined and resolved; else why not."""
    if branch is None:
        return Status.NOT_CONVERGED
    if branch.status not in (int(REACHED_BOUND), int(Status.FOLDS_FOUND)):
        return Status(branch.status)
    if not all(f.converged for f in folds) or not all(p.converged for p in branch.points):
        return Status.NOT_CONVERGED
    tails = [p.tail for p in branch.points] + [f.state.tail for f in folds]
    return Status.UNDER_RESOLVED if max(tails) > TOLERANCE else Status.SUCCESS


def twist_fold_map(rod: TwistedRod, vary: str, vary_range: tuple[float, float], x, y, *,
                   turns: float = 0.0, folds: int = 2, progress: bool = False, **options
                   ) -> FoldMap:
    """The first two folds along ``vary`` (an input of the rod, or "turns") over
    ``vary_range`` at every point of the grid ``x`` = (key, values) by ``y`` = (key,
    values) (module docstring), or along ``x`` alone where ``y`` is None (one row: the
    folds' curve in x); ``turns``: the far end's rotation where neither ``vary``
    nor an axis is the turns; ``folds``: 1 (the branch ends at its first fold) or 2.
    ``options`` go to each ``twist_branch``. The record is the planar maps'
    ``jaxrod.bistability.fold_map.FoldMap``. Ctrl-C raises
    ``jaxrod.progress.Interrupted`` with the map so far (NOT_COMPUTED where not reached)
    as ``partial``."""
    (xk, xs), (yk, ys) = x, (None, [0.0]) if y is None else y
    xs, ys = np.atleast_1d(np.asarray(xs, float)), np.atleast_1d(np.asarray(ys, float))
    axes = [k for k in (xk, yk) if k is not None]
    if len({vary, *axes}) != 1 + len(axes):
        raise ParameterError(f"x, y: inputs other than vary ({vary!r}) and each other, "
                             f"got {xk!r} and {yk!r}")
    for key in axes:
        if key != "turns":
            rod.value(key)  # names a key the rod does not have
    if folds not in (1, 2):
        raise ParameterError(f"folds: 1 or 2 (the folds to look for), got {folds!r}")
    if not (np.all(np.isfinite(xs)) and np.all(np.isfinite(ys))):
        raise ParameterError("x, y: finite values")
    shape = (len(ys), len(xs))
    count = np.full(shape, NOT_COMPUTED)
    first, second = np.full(shape, np.nan), np.full(shape, np.nan)
    status = np.full(shape, NOT_COMPUTED)

    def record():
        return FoldMap(vary, tuple(vary_range), xk, xs, yk, ys, count.copy(), first.copy(),
                       second.copy(), status.copy())

    bar = progress_bar(count.size, "map", "point", progress)
    start = None
    try:
        for j, yv in enumerate(ys):
            for i in (range(len(xs)) if j % 2 == 0 else range(len(xs) - 1, -1, -1)):
                at, t = rod, float(turns)
                for key, v in ((xk, xs[i]), (yk, yv)):
                    if key is None:
                        continue
                    if key == "turns":
                        t = float(v)
                    else:
                        at = at.replace(key, float(v))
                found, state, branch = folds_along(at, vary, vary_range, t, folds, start,
                                                   **options)
                if branch is None and start is not None:  # again from the rod's own path
                    found, state, branch = folds_along(at, vary, vary_range, t, folds, None,
                                                       **options)
                start = state if state is not None and state.converged else None
                count[j, i] = len(found)
                for k, values in enumerate((first, second)):
                    if len(found) > k and found[k].converged:
                        values[j, i] = found[k].value
                status[j, i] = int(_point_status(found, branch))
                bar.update(1)
    except KeyboardInterrupt:
        raise Interrupted(record(), f"after {int(np.sum(status != NOT_COMPUTED))} of "
                                    f"{count.size} points") from None
    finally:
        bar.close()
    return record()
