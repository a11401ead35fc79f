"""``jaxrod foldcurve | map RIG``: fold curves and maps of any rig given by a scene file
(``jaxrod.scenes.files``)."""

from __future__ import annotations

import json
import sys

import numpy as np

from jaxrod.cli.framed_rod import check_grid_options
from jaxrod.cli.scene_file import _load, _range
from jaxrod.params import ParameterError
from jaxrod.status import Status


def _axis(text: str, what: str, file):
    key, *rest = text.split(":")
    if len(rest) != 3:
        raise ParameterError(f"{what}: write KEY:START:STOP:COUNT, got {text!r}")
    try:
        a, b, count = float(rest[0]), float(rest[1]), int(rest[2])
    except ValueError:
        raise ParameterError(f"{what}: write KEY:START:STOP:COUNT, got {text!r}") from None
    if file.framed is not None:  # a rod that carries its frame: (its input, factor)
        return (key, *file.input_of(key, what), np.linspace(a, b, count))
    from jaxrod.scenes.path import along

    along(file, (key,))
    return key, key, 1.0, np.linspace(a, b, count)


def foldcurve_on_file(args) -> int:
    """``jaxrod foldcurve RIG --vary KEY --from A --to B --along KEY2 --along-to C``: the
    curve of the first fold met along KEY (``--which`` picks another) as KEY2 goes from the
    file's value to C, with the cusps it passes."""
    import jaxrod as jr

    file = _load(args, framed=True)
    check_grid_options(args, file)
    if file.framed is not None:
        from jaxrod.cli.framed_analyses import framed_foldcurve

        return framed_foldcurve(args, file)
    if args.points is not None:
        raise ParameterError("points: only for a rod that carries its frame (a fold curve of "
                             "any other rig is continued, not sampled)")
    key, start, stop, factor = _range(args, file)
    if args.along is None or args.along_to is None:
        raise ParameterError("along: give --along KEY --along-to VALUE with a scene file")
    from jaxrod.scenes.path import along

    a_factor = 1.0
    a0 = along(file, (args.along,)).start[0]
    curve = jr.fold_curve(file, key, (start, stop), args.along, (a0, args.along_to),
                          which=args.which, n=args.n)
    special = [{**c.as_dict(), "along": c.along_value / a_factor, "value": c.value / factor}
               for c in curve.special_points]
    cusps = [c for c in special if c["kind"] == "cusp"]
    status = curve.overall
    out = {"vary": args.vary, "along": args.along,
           "along_values": (curve.along_values / a_factor).tolist(),
           "values": (curve.values / factor).tolist(),
           "tip_angle_deg": curve.tip_angle_deg.tolist(), "cusps": cusps,
           "ends": [c for c in special if c["kind"] == "end"],
           "curve_status": [s.name.lower() for s in curve.status],
           "status": status.name.lower(), "converged": status == Status.SUCCESS}
    if not write_curve(args, out):
        print(f"{args.rig}: the fold in {args.vary} followed in {args.along} over "
              f"{len(curve.values)} points ({', '.join(str(s) for s in curve.status)})")
        for c in special:
            print(f"  {c['kind']} at {args.along} = {c['along']:.8g}, {args.vary} = "
                  f"{c['value']:.8g}")
    return 0 if out["converged"] else 1


def write_curve(args, out: dict) -> bool:
    """foldcurve.json and foldcurve.png in ``--out`` (where given); ``out`` printed as JSON
    with ``--json`` (True), else nothing printed (False: the caller's text follows)."""
    if args.out:
        from jaxrod.cli._output import _output_dir

        out_dir = _output_dir(args.out)
        (out_dir / "foldcurve.json").write_text(json.dumps(out, indent=1))
        _curve_figure(out_dir / "foldcurve.png", out, args)
    if args.json:
        print(json.dumps(out))
    return bool(args.json)


def _curve_figure(path, out, args) -> None:
    """The fold's value of ``vary`` against ``along``, the refined cusps marked."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.5, 4.5))
    ax.plot(out["along_values"], out["values"], "-", label=f"fold in {args.vary}")
    if out["cusps"]:
        ax.plot([c["along"] for c in out["cusps"]], [c["value"] for c in out["cusps"]], "k^",
                label="cusp (refined)")
    ax.set_xlabel(args.along)
    ax.set_ylabel(args.vary)
    ax.legend(fontsize=8)
    fig.savefig(path, dpi=120)
    plt.close(fig)


def map_on_file(args) -> int:
    """``jaxrod map RIG --vary KEY --from A --to B --x KEY:A:B:N --y KEY:A:B:N --out DIR``:
    the folds along KEY at every grid point, into the resumable store DIR/map.zarr (each
    process of a ``jax.distributed`` run its own chunks), with map.json and map.png beside
    it."""
    import jax

    import jaxrod as jr
    from jaxrod.bistability.fold_map import read_fold_map
    from jaxrod.cli._output import _output_dir

    file = _load(args, framed=True)
    check_grid_options(args, file)
    if file.framed is not None:
        from jaxrod.cli.framed_analyses import framed_map

        return framed_map(args, file)
    key, start, stop, factor = _range(args, file)
    xk, xs_key, xf, xs = _axis(args.x, "x", file)
    yk, ys_key, yf, ys = _axis(args.y, "y", file)
    out_dir = _output_dir(args.out)
    store = out_dir / "map.zarr"
    try:
        jr.fold_map(file, key, (start, stop), (xs_key, xf * xs), (ys_key, yf * ys),
                    n=args.n, progress=not args.quiet, out=store, chunk=args.chunk or 8)
    except KeyboardInterrupt:
        print(f"jaxrod map: interrupted; the finished chunks are kept in {store} (run the "
              "same command again to resume)", file=sys.stderr)
        return 130
    if jax.process_index() != 0:
        return 0
    m = read_fold_map(store)
    out = {"vary": args.vary, "x": xk, "x_values": xs.tolist(), "y": yk,
           "y_values": ys.tolist(), **map_fields(m, factor), "store": str(store)}
    missing = out["not_computed_points"]
    (out_dir / "map.json").write_text(json.dumps(out))
    if not args.no_plot:
        map_figure(out_dir / "map.png", m, factor, args.vary, xk, yk)
    summary = {k: out[k] for k in ("vary", "x", "y", "bistable_points", "failed_points",
                                   "not_computed_points", "store")}
    print(json.dumps(summary) if args.json else
          f"{args.rig}: {m.count.size} points, {summary['bistable_points']} with two folds "
          f"in {args.vary}, {summary['failed_points']} failed"
          + (f", {missing} not computed yet (other processes)" if missing else "")
          + f"; wrote {out_dir / 'map.json'} and the store {store}")
    return 0 if out["failed_points"] == 0 else 1


def map_fields(m, factor: float) -> dict:
    """A ``FoldMap``'s points for map.json: the counts, the folds' values divided by
    ``factor`` (None where fewer), the statuses and the tallies."""
    from jaxrod.bistability.grid_store import NOT_COMPUTED

    return {"count": m.count.tolist(),
            "first": np.where(np.isnan(m.first), None, m.first / factor).tolist(),
            "second": np.where(np.isnan(m.second), None, m.second / factor).tolist(),
            "status": m.status.tolist(), "bistable_points": int(np.sum(m.bistable)),
            "failed_points": int(np.sum((m.status != 0) & (m.status != NOT_COMPUTED))),
            "not_computed_points": int(np.sum(m.status == NOT_COMPUTED))}


def map_figure(path, m, factor: float, vary: str, xk: str, yk: str) -> None:
    """map.png: the first fold's value over the grid (``FoldMap.plot``)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 4.5))
    m.plot(ax, factor=factor, label=f"the first fold's {vary}")
    ax.set_xlabel(xk)
    ax.set_ylabel(yk)
    fig.savefig(path, dpi=120)
    plt.close(fig)
