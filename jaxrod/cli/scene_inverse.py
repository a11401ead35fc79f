"""``jaxrod fit | design RIG``: the inputs of any rig given by a scene file whose folds sit
at measured (fit) or target (design) values (``jaxrod.inverse.scene_fit``)."""

from __future__ import annotations

import json

from jaxrod.cli._inputs import _degree, _float
from jaxrod.cli.framed_rod import add_grid_options, check_grid_options
from jaxrod.cli.scene_file import _load, _range, add_scene_file_inputs
from jaxrod.params import ParameterError


def add_fit_scene_options(ft) -> None:
    """``jaxrod fit RIG``'s options beside the paper's (its --free and --bounds serve both)."""
    add_scene_file_inputs(ft, vary=True)
    ft.add_argument("--folds", type=float, nargs="+", help="scene file: the measured folds "
                    "along --vary, in order (nan: not measured); with --free KEYS")
    ft.add_argument("--sigma", type=_float("sigma", "sigma-deg"), default=None,
                    help="scene file: the folds' standard deviation (--vary's units)")
    ft.add_argument("--n", type=_degree("N-magnet"), default=None,
                    help="scene file: Chebyshev degree, 4-64 (default 16; 48 for a rod that "
                    "carries its frame, raised while a fold is under-resolved)")
    add_grid_options(ft)
    ft.set_defaults(n_fallback=16)


def add_design_scene_options(de) -> None:
    """``jaxrod design RIG``'s options (its --vary names the paper's inputs: the path of a
    scene file is --path)."""
    add_scene_file_inputs(de, vary=True, vary_name="--path")
    de.add_argument("--targets", type=float, nargs="+", help="scene file: the folds' "
                    "targets along --path, in order; with --free KEYS")
    de.add_argument("--width", type=_float("width"), default=None,
                    help="scene file: the hysteresis width to design for, the first fold "
                    "met along --path less the second (with or without --targets)")
    de.add_argument("--free", action="append", default=[], metavar="KEY",
                    help="scene file: an input to solve for (a list's key frees all its "
                    "coefficients, e.g. magnetisation.strength_profile); repeatable, or "
                    "comma-separated")
    de.add_argument("--target-shape", default=None, metavar="FILE.csv",
                    help="scene file: design for a target shape, a CSV with header "
                    "s,tangent_deg (the tangent angle from +z toward +x at s in [0, 1]), "
                    "s,x,z (the centreline's points, rod lengths) or s,x,z,tangent_deg")
    de.add_argument("--target-tip", default=None, metavar="X,Z[,DEG]",
                    help="scene file: design for a tip pose, its position (rod lengths from "
                    "the clamp) and optionally its tangent angle in degrees")
    de.add_argument("--roughness", type=_float("roughness"), default=0.0,
                    help="a shape design's penalty on each free profile's int f''(s)^2 ds "
                    "(default 0)")
    de.add_argument("--margin", type=_float("margin"), default=0.0,
                    help="a shape design's stability margin: the smallest eigenvalue of the "
                    "second variation per unit int dtheta^2 ds to keep along the ramp of "
                    "the loads from zero (default 0: stable; pi^2/4 for the unloaded "
                    "clamped-free rod)")
    de.add_argument("--out", default=None, help="directory for design.json and shape.png "
                    "(a shape design)")


def _legacy_keys(cal) -> dict:
    """The keys of the one-parameter fit's JSON (E_Pa, offset_deg, ...), for scripts."""
    from jaxrod.inverse.youngs import fit_result

    flat = fit_result(cal, "offset" in cal.free)
    return {k: flat[k] for k in ("E_Pa", "E_std_Pa", "offset_deg", "offset_std_deg",
                                 "residuals_deg", "warning")}


def free_items(args) -> list[str]:
    """The keys of ``--free`` (repeatable, or comma-separated; the fit's is one string)."""
    items = [args.free] if isinstance(args.free, str) else args.free or []
    return [k.strip() for item in items for k in item.split(",") if k.strip()]


def bounds_of(args, keys, scale=lambda key: (key, 1.0)) -> dict:
    """``--bounds KEY=LO:HI`` of free inputs: scale(key) -> (the bound's key, its factor)."""
    bounds = {}
    for item in args.bounds:
        key, sep, rest = item.partition("=")
        lo, sep2, hi = rest.partition(":")
        if not sep or not sep2 or key.strip() not in keys:
            raise ParameterError(f"bounds: write KEY=LO:HI for a free input, got {item!r}")
        name, factor = scale(key.strip())
        try:
            bounds[name] = tuple(sorted((factor * float(lo), factor * float(hi))))
        except ValueError:
            raise ParameterError(f"bounds: {item!r} is not KEY=LO:HI") from None
    return bounds


def _free_and_bounds(args, file):
    keys = free_items(args)
    if not keys:
        raise ParameterError("free: name the inputs to solve for (--free KEY1,KEY2) with a "
                             "scene file")
    free = [file.input_of(k, "free") for k in keys]
    return keys, free, bounds_of(args, keys, lambda k: file.input_of(k, "bounds"))


def _report(args, file, keys, free, fit, factor, what: str) -> int:
    est = {k: fit.estimates[s] / f for k, (s, f) in zip(keys, free)}
    std = None if fit.std is None else {k: fit.std[s] / abs(f) for k, (s, f) in zip(keys, free)}
    out = {"vary": args.vary, "free": keys, "estimates": est, "std": std,
           "folds": [v / factor for v in fit.folds],
           "width": (fit.folds[0] - fit.folds[1]) / factor if len(fit.folds) >= 2 else None,
           "residuals": [None if r is None else r / factor for r in fit.residuals],
           "converged": fit.converged, "iterations": fit.iterations, "reason": fit.reason}
    if getattr(args, "out", None):
        from jaxrod.cli._output import _output_dir

        (_output_dir(args.out) / f"{what}.json").write_text(json.dumps(out, indent=1))
    if args.json:
        print(json.dumps(out))
    else:
        for k in keys:
            spread = f" +- {std[k]:.6g}" if std else ""
            print(f"{k} = {est[k]:.10g}{spread}")
        print(f"folds along {args.vary}: " + ", ".join(f"{v:.10g}" for v in out["folds"]))
        if out["width"] is not None:
            print(f"hysteresis width (the first fold less the second): {out['width']:.10g}")
        print(f"converged: {fit.converged}" + (f" ({fit.reason})" if fit.reason else ""))
    return 0 if fit.converged else 1


def fit_on_file(args) -> int:
    """``jaxrod fit RIG --vary KEY --from A --to B --folds V1 V2 --free K1,K2``."""
    from jaxrod.inverse.scene_fit import fit_folds

    file = _load(args, framed=True)
    check_grid_options(args, file)
    if file.framed is not None:
        from jaxrod.cli.framed_analyses import framed_fit

        return framed_fit(args, file)
    key, start, stop, factor = _range(args, file)
    if not args.folds:
        raise ParameterError("folds: give the measured fold values (--folds V1 V2 ..., in "
                             "the order met along --vary; nan for one not measured)")
    keys, free, bounds = _free_and_bounds(args, file)
    sigma = 1.0 if args.sigma is None else args.sigma
    fit = fit_folds(file, key, (start, stop), [factor * v for v in args.folds],
                    [s for s, _ in free], sigma * abs(factor), bounds, n=args.n)
    return _report(args, file, keys, free, fit, factor, "fit")


def design_on_file(args) -> int:
    """``jaxrod design RIG --path KEY --from A --to B --targets V1 V2 --free K1,K2``, or
    ``jaxrod design RIG --free KEY --target-shape FILE.csv`` (``shape_on_file``)."""
    from jaxrod.inverse.scene_fit import design_folds

    if args.target_shape is not None or args.target_tip is not None:
        from jaxrod.cli.shape_design import shape_on_file

        return shape_on_file(args)
    file = _load(args)
    args.vary = args.path
    key, start, stop, factor = _range(args, file)
    if not args.targets and args.width is None:
        raise ParameterError("targets: give the folds' target values (--targets V1 V2 ..., "
                             "in the order met along --path; nan: not targeted) or a "
                             "hysteresis width (--width W)")
    keys, free, bounds = _free_and_bounds(args, file)
    fit = design_folds(file, key, (start, stop), [factor * v for v in args.targets or []],
                       [s for s, _ in free], bounds, n=args.n,
                       width=None if args.width is None else factor * args.width)
    return _report(args, file, keys, free, fit, factor, "design")
