"""``jaxrod cusp | foldcurve | map``: fold curves, the cusp and maps."""

from __future__ import annotations

import json
import sys

from jaxrod.cli._inputs import (
    _MAGNET_PHYSICAL,
    BATCH_N,
    _design_point_from_args,
    _entry,
    _float,
    add_magnet_inputs,
)
from jaxrod.cli._output import _fmt_cusp, _header, _output_dir, _write_fold_curves
from jaxrod.cli.framed_rod import add_grid_options
from jaxrod.cli.scene_curves import foldcurve_on_file, map_on_file
from jaxrod.cli.scene_file import add_scene_file_inputs, uses_scene_file
from jaxrod.params import (
    GROUP_NAMES,
    PHYSICAL_NAMES,
    ParameterError,
)


def cmd_cusp(args) -> int:
    from jaxrod.bistability.fold_curves import find_cusp

    point, inputs = _design_point_from_args(args)
    point.index(args.vary)
    cusp = find_cusp(point, args.vary, n=args.n)
    found = cusp.kind == "cusp"
    out = {"vary": args.vary, "cusp": cusp.as_dict() if found else None,
           "converged": bool(found and cusp.converged), "n": args.n,
           "point": point.as_dict(), "inputs": inputs}
    if not found:
        out["message"] = (f"no cusp found varying {args.vary} within a factor 20 of its "
                          "starting value (the fold curves leave the valid range first)")
    if args.json:
        print(json.dumps(out))
    else:
        G, M, D = point.groups()
        print(_header({"G": G, "M": M, "D": D, "inputs": inputs}) + f", varying {args.vary}")
        print(_fmt_cusp(cusp, args.vary) if found else out["message"])
        if found:
            print(f"converged: {cusp.converged} (residual {cusp.residual_norm:.2g}, "
                  f"{cusp.iterations} Newton iterations)")
    return 0 if out["converged"] else 1


def cmd_foldcurve(args) -> int:
    from jaxrod.bistability.fold_curves import fold_curves

    if uses_scene_file(args, vary_is_file_key=False):
        return foldcurve_on_file(args)
    if args.vary is None or args.to is None:
        raise ParameterError("vary: give --vary NAME --to VALUE (a group, or a physical "
                             "input with --preset)")
    point, inputs = _design_point_from_args(args)
    point.index(args.vary)
    out_dir = _output_dir(args.out) if args.out else None
    curves = fold_curves(point, args.vary, args.to, n=args.n)
    cusps = [p for c in curves for p in c.cusps]
    converged = all(c.converged for c in curves)
    summary = {"vary": args.vary, "to": args.to, "n": args.n, "point": point.as_dict(),
               "inputs": inputs, "cusp": cusps[0].as_dict() if cusps else None,
               "curves": {c.name: c.as_dict() for c in curves}, "converged": converged}
    if out_dir is not None:
        _write_fold_curves(curves, point, summary, out_dir)
    if args.json:
        print(json.dumps({k: v for k, v in summary.items() if k != "curves"}
                         | {"special_points": [p.as_dict() for c in curves
                                               for p in c.special_points],
                            "points": {c.name: len(c.values) for c in curves}}))
    else:
        G, M, D = point.groups()
        print(_header({"G": G, "M": M, "D": D, "inputs": inputs})
              + f", {args.vary} -> {args.to:g}")
        for c in curves:
            print(f"{c.name} fold: {len(c.values)} points, {args.vary} from "
                  f"{c.along_values[0]:.8g} to {c.along_values[-1]:.8g}, alpha* from "
                  f"{c.values[0]:.6f} to {c.values[-1]:.6f} deg ({c.status[0]})")
        print(_fmt_cusp(cusps[0], args.vary) if cusps else
              f"no cusp between {args.vary} = {point.values[point.index(args.vary)]:.8g} and "
              f"{args.to:g}: bistable throughout")
        for c in curves:
            for e in c.special_points:
                if e.kind.startswith("alpha"):
                    print(f"the {e.curve} fold reaches {e.kind} at {args.vary} = "
                          f"{e.along_value:.10g}")
        if out_dir is not None:
            print(f"wrote {out_dir / 'foldcurve.csv'}, foldcurve.json, foldcurve.png")
        print(f"converged: {converged}")
    return 0 if converged else 1


def _start_processes(args) -> None:
    """``jax.distributed`` for a map over several processes (each writes its own chunks)."""
    if args.num_processes > 1:
        import jax

        if args.coordinator is None or args.process_id is None:
            raise ParameterError("num-processes: a run over several processes needs "
                                 "--coordinator HOST:PORT and --process-id")
        jax.distributed.initialize(coordinator_address=args.coordinator,
                                   num_processes=args.num_processes,
                                   process_id=args.process_id)


def cmd_map(args) -> int:
    if args.chunk is not None and not 2 <= args.chunk <= 1000:
        raise ParameterError(f"chunk must be in [2, 1000], got {args.chunk}")
    _start_processes(args)
    if uses_scene_file(args):
        return map_on_file(args)
    import numpy as np

    from jaxrod.bistability.design_map import STORE, MapAxis, MapSpec, read_store, run_map

    x, y = MapAxis.parse(args.x), MapAxis.parse(args.y)
    axes = {}
    for axis in (x, y):  # a group on an axis need not be given: the grid sets it
        if axis.name in GROUP_NAMES and getattr(args, axis.name, None) is None \
                and all(getattr(args, k) is None for k in _MAGNET_PHYSICAL):
            setattr(args, axis.name, 0.5 * (axis.start + axis.stop))
            axes[axis.name] = axis
    point, inputs = _design_point_from_args(args)
    for name, axis in axes.items():
        inputs[name] = _entry(f"{axis.start:g} to {axis.stop:g}", "", "the map's axis")
    point.index(x.name)
    point.index(y.name)
    spec = MapSpec(point, x, y, chunk=args.chunk or 50, n=args.n)
    out = _output_dir(args.out)
    try:
        counts = run_map(spec, out / STORE, progress=not args.quiet)
    except KeyboardInterrupt:
        print(f"jaxrod map: interrupted; the finished chunks are kept in {out} (run the same "
              "command again to resume)", file=sys.stderr)
        return 130
    import jax

    summary = {"out": str(out), "x": x.name, "y": y.name, "points": x.count * y.count,
               "process": jax.process_index(), "processes": jax.process_count(),
               "inputs": inputs} | counts
    if jax.process_index() == 0 and jax.process_count() == 1:
        data = read_store(out)
        from jaxrod.status import Status

        codes = data["status"].ravel().astype(int)
        summary["status_counts"] = {
            name: int(np.sum(codes == int(code))) for name, code in (
                ("bistable", Status.SUCCESS), ("not_bistable", Status.NO_FOLD_PAIR),
                ("fold_beyond_90", Status.FOLD_OUT_OF_RANGE),
                ("invalid_input", Status.INVALID_INPUT),
                ("not_converged", Status.NOT_CONVERGED))}
        if not args.no_plot:
            from jaxrod.bistability.design_map import cusp_curve, fold_crossings
            from jaxrod.plotting import design_map_figure

            cusps, crossings = cusp_curve(spec, data), fold_crossings(spec, data)
            summary["cusps"], summary["fold_crossings_90"] = cusps, crossings
            design_map_figure(data, spec, cusps, crossings).savefig(out / "map.png", dpi=120)
        (out / "map.json").write_text(json.dumps(summary, indent=1))
    if args.json:
        print(json.dumps(summary))
    else:
        print(f"{summary['points']} points in {counts['chunks']} chunks ({counts['computed']} "
              f"computed, {counts['resumed']} already done) -> {out}")
        if "status_counts" in summary:
            print(", ".join(f"{k}: {v}" for k, v in summary["status_counts"].items()))
    # a point whose solve failed makes the map a failed solve (exit 1; the map is kept)
    return 1 if summary.get("status_counts", {}).get("not_converged", 0) else 0


def add_cusp(sub) -> None:
    cu = sub.add_parser("cusp", help="the cusp where the hysteresis ends, varying one input")
    add_magnet_inputs(cu)
    cu.add_argument("--vary", required=True, choices=GROUP_NAMES + PHYSICAL_NAMES,
                    help="the input that varies (a group, or a physical input with --preset)")
    cu.set_defaults(func=cmd_cusp)


def add_foldcurve(sub) -> None:
    fc = sub.add_parser("foldcurve", help="both fold curves in a second input, and the "
                        "cusp; or a fold curve of a scene file")
    add_scene_file_inputs(fc, vary=True, to=False)
    add_magnet_inputs(fc)
    fc.add_argument("--vary", help="the input that varies (a group, or a physical input "
                    f"with --preset: {', '.join(GROUP_NAMES + PHYSICAL_NAMES)}); with a "
                    "scene file, the input whose fold is followed")
    fc.add_argument("--to", type=_float("to"), default=None,
                    help="the value of the varied input where the curves end (with a scene "
                    "file: the end of --vary's range)")
    fc.add_argument("--along", metavar="KEY", help="scene file: the second input")
    fc.add_argument("--along-to", type=_float("along-to"), default=None,
                    help="scene file: where the curve ends in --along")
    fc.add_argument("--which", type=int, default=0, help="scene file: which fold along "
                    "--vary (0: the first met)")
    fc.add_argument("--points", type=int, default=None, help="a rod that carries its frame: "
                    "the values of --along, evenly spaced from the file's value to --along-to "
                    "(default 11)")
    add_grid_options(fc)
    fc.add_argument("--out", default=None, help="directory for foldcurve.csv/.json/.png")
    fc.set_defaults(func=cmd_foldcurve)


def add_map(sub) -> None:
    mp = sub.add_parser("map", help="capture/release angles and hysteresis width on a grid "
                        "of two inputs (chunked Zarr store, resumable); or the folds of a "
                        "scene file on a grid")
    add_scene_file_inputs(mp, vary=True)
    add_magnet_inputs(mp, BATCH_N)
    mp.add_argument("--x", required=True, help="name:start:stop:count of the first input")
    mp.add_argument("--y", required=True, help="name:start:stop:count of the second input")
    mp.add_argument("--out", required=True, help="directory for the Zarr store map.zarr and, "
                    "beside it, map.png and map.json")
    mp.add_argument("--chunk", type=int, default=None, help="chunk edge in grid points "
                    "(default 50; 8 with a scene file)")
    mp.add_argument("--quiet", action="store_true", help="no progress bar")
    mp.add_argument("--no-plot", action="store_true", help="skip map.png and the cusp curve")
    add_grid_options(mp, branch=True)
    mp.add_argument("--coordinator", default=None, help="HOST:PORT of process 0 "
                    "(jax.distributed), for a map over several processes or hosts")
    mp.add_argument("--num-processes", type=int, default=1)
    mp.add_argument("--process-id", type=int, default=None)
    mp.set_defaults(func=cmd_map)
