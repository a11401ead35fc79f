"""``jaxrod fit | foldcurve | map RIG`` for a rod that carries its frame
(``jaxrod.twisted``): its inputs fitted to measured folds along one of its inputs (the end
rotation, say), a fold's curve in a second input, and the folds over a grid of two. Each is
done at the command's degree, then again at twice the degree while a fold (or a point of
the branches) is under-resolved (``MOST_DEGREE`` at most)."""

from __future__ import annotations

import dataclasses
import json
import sys

import numpy as np

from jaxrod.cli.framed_rod import MOST_DEGREE, _degree, framed_range, twisted_rod
from jaxrod.cli.scene_curves import _axis, map_fields, map_figure
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
        if fit.status != Status.UNDER_RESOLVED or rod.n >= MOST_DEGREE:
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


def _resolved_map(rod, *args, **kwargs):
    """(``twist_fold_map`` at the rod's degree, then at twice it while a point is
    under-resolved, the rod of the last)."""
    from jaxrod.twisted.fold_map import twist_fold_map

    while True:
        m = twist_fold_map(rod, *args, **kwargs)
        if not np.any(m.status == int(Status.UNDER_RESOLVED)) or rod.n >= MOST_DEGREE:
            return m, rod
        rod = dataclasses.replace(rod, n=min(2 * rod.n, MOST_DEGREE))


def framed_foldcurve(args, file) -> int:
    """``jaxrod foldcurve RIG --vary KEY --from A --to B --along KEY2 --along-to C`` on a
    rod that carries its frame: the fold ``--which`` (0: the first met, or 1) along KEY at
    ``--points`` values of KEY2 evenly spaced from the file's value to C, each start solved
    from the last (``twist_fold_map`` along one axis)."""
    from jaxrod.cli.scene_curves import write_curve

    vary, start, stop, factor = framed_range(args, file)
    if args.along is None or args.along_to is None:
        raise ParameterError("along: give --along KEY --along-to VALUE with a scene file")
    along, a_factor = file.input_of(args.along, "along")
    if args.which not in (0, 1):
        raise ParameterError(f"which: 0 or 1 for a rod that carries its frame, got "
                             f"{args.which}")
    points = 11 if args.points is None else args.points
    if points < 2:
        raise ParameterError(f"points: at least 2, got {points}")
    values = np.linspace(file.value(args.along), args.along_to, points)
    m, rod = _resolved_map(twisted_rod(file, _degree(args), args), vary,
                           (factor * start, factor * stop), (along, a_factor * values), None,
                           turns=file.framed.turns, folds=args.which + 1)
    fold = (m.first if args.which == 0 else m.second)[0] / factor
    status = [Status(int(v)) if v >= 0 else Status.NOT_CONVERGED for v in m.status[0]]
    status = [s if s != Status.SUCCESS or c > args.which else Status.FOLD_OUT_OF_RANGE
              for s, c in zip(status, m.count[0])]
    overall = next((s for s in status if s != Status.SUCCESS), Status.SUCCESS)
    out = {"vary": args.vary, "along": args.along, "along_values": values.tolist(),
           "values": [None if np.isnan(v) else float(v) for v in fold],
           "curve_status": [s.name.lower() for s in status], "cusps": [], "ends": [],
           "status": overall.name.lower(), "converged": overall == Status.SUCCESS,
           "n": rod.n}
    if not write_curve(args, out):
        print(f"{args.rig}: the fold in {args.vary} at {points} values of {args.along} "
              f"(n = {rod.n})")
        for a, v, s in zip(values, out["values"], status):
            print(f"  {args.along} = {a:.8g}: {args.vary} = "
                  + (f"{v:.10g}" if v is not None else "none") + f" ({s})")
    return 0 if out["converged"] else 1


def framed_map(args, file) -> int:
    """``jaxrod map RIG --vary KEY --from A --to B --x KEY:A:B:N --y KEY:A:B:N --out DIR``
    on a rod that carries its frame (``jaxrod.twisted.fold_map.twist_fold_map``): map.json
    and map.png in DIR (map.json also when interrupted, with what was computed)."""
    from jaxrod.cli._output import _output_dir
    from jaxrod.progress import Interrupted

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
               "y_values": ys.tolist(), "n": rod.n, **map_fields(m, factor)}
        (out_dir / "map.json").write_text(json.dumps(out))
        return out

    try:
        m, rod = _resolved_map(rod, vary, (factor * start, factor * stop), (xs_key, xf * xs),
                               (ys_key, yf * ys), turns=file.framed.turns, folds=folds,
                               progress=not args.quiet)
    except Interrupted as err:
        write(err.partial)
        print(f"jaxrod map: interrupted {err.where}; wrote what was computed to "
              f"{out_dir / 'map.json'}", file=sys.stderr)
        return 130
    out = write(m)
    if not args.no_plot:
        map_figure(out_dir / "map.png", m, factor, key, xk, yk)
    summary = {k: out[k] for k in ("vary", "x", "y", "n", "bistable_points", "failed_points")}
    print(json.dumps(summary) if args.json else
          f"{args.rig}: {m.count.size} points (n = {rod.n}), {summary['bistable_points']} "
          f"with two folds in {key}, {summary['failed_points']} failed; wrote "
          f"{out_dir / 'map.json'}")
    return 0 if out["failed_points"] == 0 else 1

