"""Does a map ever disagree with the folds of its own points? ``jr.fold_map`` of the
hard-magnetic cantilever under gravity (the folds in the field's angle over the load and
the gravity group) against the branch and its refined folds (``jr.branch``) run point by
point on the same sets.

The scene: a clamped hard-magnetic rod (magnetisation along the tangent) standing under
gravity G, in a uniform field of load lambda turned from 90 to 359 degrees
(``field.angle``); the map's axes are lambda in [2.6, 10] and G in [0, 3] (100 x 100 =
10,000 sets; ``--quick``: 10 x 10). A set agrees when the map's status is what ``folds``
says (both converged, or both not), the fold counts in the range agree as far as the map
counts them (its branch holds the first ``CAPACITY`` points: both have at least the two
folds it refines, or the same number below two), and the first two folds agree to
``TOL_RAD``. The target is zero disagreements.

Run:  python benchmarks/fold_map_against_folds.py [--quick]
Writes benchmarks/results/fold_map_against_folds.{json,md}.
"""

from __future__ import annotations

import math
import time

import numpy as np
from common import benchmark_main, write_results

import jaxrod as jr

N = 16
TOL_RAD = 1e-9
ANGLES = (math.pi / 2, math.radians(359.0))


def _scene():
    return jr.Scene({"bending": jr.Bending(), "gravity": jr.Gravity(1.0),
                     "field": jr.Zeeman(5.0, math.pi / 2)})


def run(quick: bool) -> dict:
    count = 10 if quick else 100
    loads, gs = np.linspace(2.6, 10.0, count), np.linspace(0.0, 3.0, count)
    scene = _scene()
    t0 = time.perf_counter()
    m = jr.fold_map(scene, "field.angle", ANGLES, ("field.load", loads), ("gravity.G", gs),
                    n=N, progress=not quick, chunk=10)
    map_seconds = time.perf_counter() - t0
    rows, t0 = [], time.perf_counter()
    for iy, g in enumerate(gs):
        for ix, load in enumerate(loads):
            at = scene.replace("field.load", load).replace("gravity.G", g)
            b = jr.branch(at, "field.angle", *ANGLES, n=N, throw=False)
            found = [p for p in b.special_points if p.kind == "fold"]
            values = [f.value for f in found]
            # what the map calls success: the first two folds converged, or fewer with the
            # whole range traced
            ok = all(f.converged for f in found[:2]) and (len(found) >= 2 or b.complete)
            map_ok = int(m.status[iy, ix]) == int(jr.Status.SUCCESS)
            first = [m.first[iy, ix], m.second[iy, ix]][:min(2, len(values))]
            agree = (ok == map_ok) and (
                not ok or (min(len(values), 2) == min(int(m.count[iy, ix]), 2)
                           and all(abs(a - b) <= TOL_RAD for a, b in zip(first, values))))
            if not agree:
                rows.append({"load": float(load), "G": float(g), "map_status":
                             int(m.status[iy, ix]), "map_count": int(m.count[iy, ix]),
                             "map_first": float(m.first[iy, ix]), "folds": values,
                             "folds_converged": ok})
    folds_seconds = time.perf_counter() - t0
    return {"sets": count * count, "disagreements": len(rows), "rows": rows[:50],
            "bistable_sets": int(np.sum(m.count >= 2)),
            "failed_sets": int(np.sum(m.status != int(jr.Status.SUCCESS))),
            "map_seconds": map_seconds, "folds_seconds": folds_seconds, "n": N,
            "tol_rad": TOL_RAD}


def write(result: dict, out) -> None:
    md = (f"# fold_map against folds, point by point\n\n"
          f"The hard-magnetic cantilever under gravity, its folds in the field's angle over "
          f"the load (2.6-10) and G (0-3), N = {result['n']}: {result['sets']} sets.\n\n"
          f"| | |\n|---|---|\n"
          f"| disagreements (status, fold count or value beyond {result['tol_rad']:g} rad) | "
          f"{result['disagreements']} |\n"
          f"| sets with two folds or more | {result['bistable_sets']} |\n"
          f"| sets the map reports failed | {result['failed_sets']} |\n"
          f"| the map, s | {result['map_seconds']:.1f} |\n"
          f"| folds point by point, s | {result['folds_seconds']:.1f} |\n")
    write_results(out, "fold_map_against_folds", result, md)


if __name__ == "__main__":
    raise SystemExit(benchmark_main(__doc__, run, write))
