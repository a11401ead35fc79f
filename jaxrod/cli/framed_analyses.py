"""``jaxrod fit RIG`` and ``jaxrod map RIG`` for a rod that carries its frame
(``jaxrod.twisted``): its inputs fitted to measured folds along one of its inputs (the end
rotation, say), and the folds over a grid of two of its inputs. Each is done at the
command's degree, then again at twice the degree while a fold (or a point of a map's
branches) is under-resolved (``MOST_DEGREE`` at most)."""

from __future__ import annotations

import dataclasses
import json
import sys

import numpy as np

from jaxrod.cli.framed_rod import MOST_DEGREE, _degree, framed_range, twisted_rod
from jaxrod.cli.scene_curves import _axis
from jaxrod.cli.scene_inverse import _free_and_bounds, _report
from jaxrod.params import ParameterError
from jaxrod.status import Status


def framed_fit(args, file) -> int:
    """``jaxrod fit RIG --vary KEY --from A --to B --folds V1 .. --free K1,K2`` on a rod that
    carries its frame (``jaxrod.inverse.twist_fit.fit_twist_folds``)."""
    from jaxrod.inverse.twist_fit import fit_twist_folds

    if args.folds is None:
        raise ParameterError("folds: give the measured fold values (--folds V1 V2 ..., in "
                             "the order met along --vary; nan for one not measured)")
    vary, start, stop, factor = framed_range(args, file)
    keys, free, bounds = _free_and_bounds(args, file)
    sigma = 1.0 if args.sigma is None else args.sigma
    rod = twisted_rod(file, _degree(args), args)
    turns = file.framed.turns
    while True:
        fit = fit_twist_folds(rod, vary, (factor * start, factor * stop),
                              [factor * v for v in args.folds], [s for s, _ in free],
                              sigma * abs(factor), bounds, turns=turns)
        if fit.converged or rod.n >= MOST_DEGREE or "under-resolved" not in (fit.reason
                                                                               or ""):
            break
        # again at twice the degree, from the estimates
        for name, value in fit.estimates.items():
            if name == "turns":
                turns = value
            else:
                rod = rod.replace(name, value)
        rod = dataclasses.replace(rod, n=min(2 * rod.n, MOST_DEGREE))
    if not args.json:
        print(f"{args.rig}: n = {rod.n}")
    return _report(args, file, keys, free, fit, factor, "fit")


def framed_map(args, file) -> int:
    """``jaxrod map RIG --vary KEY --from A --to B --x KEY:A:B:N --y KEY:A:B:N --out DIR``
    on a rod that carries its frame (``jaxrod.twisted.fold_map.twist_fold_map``): map.json
    and map.png in DIR (map.json also when interrupted, with what was computed)."""
    from jaxrod.bistability.grid_store import NOT_COMPUTED
    from jaxrod.cli._output import _output_dir
    from jaxrod.progress import Interrupted
    from jaxrod.twisted.fold_map import twist_fold_map

    vary, start, stop, factor = framed_range(args, file)
    key = args.vary
    xk, xs_key, xf, xs = _axis(args.x, "x", file)
    yk, ys_key, yf, ys = _axis(args.y, "y", file)
    rod = twisted_rod(file, _degree(args), args)
    folds = 2 if args.max_folds is None else args.max_folds
    if folds not in (1, 2):
        raise ParameterError(f"max-folds: 1 or 2 for a map, got {folds}")
    out_dir = _output_dir(args.out)

    def write(m):
        out = {"rig": args.rig, "vary": key, "x": xk, "x_values": xs.tolist(), "y": yk,
               "y_values": ys.tolist(), "n": rod.n, "count": m.count.tolist(),
               "first": _scaled(m.first, factor), "second": _scaled(m.second, factor),
               "status": m.status.tolist(), "bistable_points": int(np.sum(m.bistable)),
               "failed_points": int(np.sum((m.status != int(Status.SUCCESS))
                                           & (m.status != NOT_COMPUTED))),
               "not_computed_points": int(np.sum(m.status == NOT_COMPUTED))}
        (out_dir / "map.json").write_text(json.dumps(out))
        return out

    while True:
        try:
            m = twist_fold_map(rod, vary, (factor * start, factor * stop), (xs_key, xf * xs),
                               (ys_key, yf * ys), turns=file.framed.turns, folds=folds,
                               progress=not args.quiet)
        except Interrupted as err:
            write(err.partial)
            print(f"jaxrod map: interrupted {err.where}; wrote what was computed to "
                  f"{out_dir / 'map.json'}", file=sys.stderr)
            return 130
        resolved = not np.any(m.status == int(Status.UNDER_RESOLVED))
        if resolved or rod.n >= MOST_DEGREE:
            break
        rod = dataclasses.replace(rod, n=min(2 * rod.n, MOST_DEGREE))
    out = write(m)
    if not args.no_plot:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(6, 4.5))
        m.plot(ax, factor=factor, label=f"the first fold's {key}")
        ax.set_xlabel(xk)
        ax.set_ylabel(yk)
        fig.savefig(out_dir / "map.png", dpi=120)
        plt.close(fig)
    summary = {k: out[k] for k in ("vary", "x", "y", "n", "bistable_points", "failed_points")}
    print(json.dumps(summary) if args.json else
          f"{args.rig}: {m.count.size} points (n = {rod.n}), {summary['bistable_points']} "
          f"with two folds in {key}, {summary['failed_points']} failed; wrote "
          f"{out_dir / 'map.json'}")
    return 0 if out["failed_points"] == 0 else 1


def _scaled(a, factor):
    return [[None if np.isnan(v) else float(v / factor) for v in row] for row in a]
