"""``jaxrod folds | certify | branch | sweep``: the permanent magnet on its circle."""

from __future__ import annotations

import json
import sys
from pathlib import Path

from jaxrod.cli._inputs import _entry, _float, _magnet_scene_from_args, _source, add_magnet_inputs
from jaxrod.cli._output import _header, _not_converged, _output_dir
from jaxrod.cli.framed_rod import add_grid_options
from jaxrod.cli.rate_sweep import add_rate_sweep_options
from jaxrod.cli.scene_file import (
    add_scene_file_inputs,
    branch_on_file,
    folds_on_file,
    uses_scene_file,
)
from jaxrod.params import ParameterError

NO_FOLD_NOTE = ("no fold on the branch through the straight rod for alpha in (0, 90] degrees: "
                "no hysteresis along the experiment's sweep")


def cmd_folds(args) -> int:
    if uses_scene_file(args):
        return folds_on_file(args)
    scene, info = _magnet_scene_from_args(args)
    if args.method == "reduced":
        return _folds_reduced(scene, info, args)
    from jaxrod.magnet.folds import locate_folds

    report = locate_folds(scene, n=args.n, throw=False)
    out = info | report.as_dict()
    if not report.folds:
        out["note"] = NO_FOLD_NOTE
    if args.json:
        print(json.dumps(out))
        return 0 if report.converged else 1
    print(_header(info))
    if not report.folds:
        print(out["note"])
    for f in report.folds:
        print(f"{f.kind:6s} fold: alpha* = {f.alpha_deg:.10f} deg  q* = {f.q:.10f}  "
              f"tip* = {f.tip_deg:.10f} deg  dF/dalpha = {f.dF_dalpha:+.6g}  "
              f"d2F/dq2 = {f.d2F_dq2:+.6g}  opens toward {f.opens}")
    if report.hysteresis_width_deg is not None:
        print(f"hysteresis width = {report.hysteresis_width_deg:.10f} deg")
    print(f"converged: {report.converged}")
    if not report.converged:
        _not_converged("folds", "; ".join(
            list(report.problems) + [f"{f.kind} fold: converged {f.converged}, residual "
                                     f"{f.residual_norm:.2e}, {f.iterations} iterations"
                                     for f in report.folds]) or "no fold solve converged")
    return 0 if report.converged else 1


def _folds_reduced(scene, info, args) -> int:
    from jaxrod.magnet.reduction import check_reducible, reduced_folds

    check_reducible(scene)
    folds = reduced_folds(scene, n=args.n)
    converged = bool(folds) and all(f.converged for f in folds)
    width = folds[1].alpha_deg - folds[0].alpha_deg if len(folds) == 2 else None
    out = info | {"method": "reduced", "n": args.n, "folds": [f.as_dict() for f in folds],
                  "hysteresis_width_deg": width, "converged": converged or not folds}
    if not folds:
        out["note"] = NO_FOLD_NOTE + " (one-mode diagram)"
    if args.json:
        print(json.dumps(out))
        return 0 if out["converged"] else 1
    print(_header(info) + ", "
          "reduced route (F = dF/dq = 0)")
    if not folds:
        print(out["note"])
    for f in folds:
        print(f"{f.kind:6s} fold: alpha* = {f.alpha_deg:.10f} deg  q* = {f.q:.10f}  "
              f"tip* = {f.tip_deg:.10f} deg  (one-mode start: alpha0 = {f.alpha0_deg:.5f} deg, "
              f"q0 = {f.q0:.6f})  dF/dalpha = {f.dF_dalpha:+.6g}  d2F/dq2 = {f.d2F_dq2:+.6g}"
              + ("" if f.converged else
                 f"  NOT CONVERGED (residual {f.residual_norm:.2e}, inner w-solve "
                 f"converged: {f.correction_converged})"))
    if width is not None:
        print(f"hysteresis width = {width:.10f} deg")
    print(f"converged: {out['converged']}")
    return 0 if out["converged"] else 1


def cmd_certify(args) -> int:
    from jaxrod.magnet.contraction import certify

    scene, info = _magnet_scene_from_args(args)
    out = info | certify(scene, n=args.n)
    if args.json:
        print(json.dumps(out))
        return 0
    mark = lambda ok: "holds " if ok else "FAILS "
    print(_header(info))
    print("scene:")
    for v in out["scene"]:
        print(f"  {mark(v['holds'])} {v['name']:38s} margin {v['margin']:+.4g}  ({v['detail']})")
    for f in out["folds"]:
        c = {k: float("inf") if v is None else v for k, v in f["constants"].items()}
        print(f"{f['kind']} fold (alpha* = {f['alpha_deg']:.6f} deg, q* = {f['q']:.6f}): "
              + "  ".join(f"{k} = {c[k]:.4g}" for k in
                          ("eta", "S", "E", "Delta", "H", "K", "epsilon")))
        for v in f["hypotheses"]:
            print(f"  {mark(v['holds'])} {v['name']:38s} margin {v['margin']:+.4g}")
    if out["branch"] is None:
        print(out["note"])
        return 0
    b = out["branch"]
    print(f"branch from the straight rod (alpha > 0): {b['points_certified']} of {b['points']} "
          f"points certified; K max {b['K_max']:.4g}, Delta min {b['Delta_min']:.4g}")
    if b["first_failure"]:
        ff = b["first_failure"]
        print(f"  first failure at alpha = {ff['alpha_deg']:.4f} deg, q = {ff['q']:.4f} "
              f"(K = {ff['K']:.4g}, Delta = {ff['Delta']:.4g}); last certified point alpha = "
              f"{ff['last_certified_alpha_deg']:.4f} deg, q = {ff['last_certified_q']:.4f}")
    print(f"all hypotheses (scene and folds) hold: {out['all_hold']}")
    return 0


def cmd_branch(args) -> int:
    from jaxrod.magnet.diagram import figure_options, trace_diagram
    from jaxrod.magnet.folds import locate_folds
    from jaxrod.plotting import diagram_figure

    if uses_scene_file(args):
        return branch_on_file(args)
    if args.out is None:
        raise ParameterError("out: give --out DIR (the diagram's branch.csv, branch.png and "
                             "branch.json)")
    scene, info = _magnet_scene_from_args(args)
    out_dir = _output_dir(args.out)
    branch = trace_diagram(scene, args.n, figure_options())  # dense, for a smooth figure
    if not branch.complete:  # a long branch filled the capacity: the default steps
        branch = trace_diagram(scene, args.n)
    report = locate_folds(scene, n=args.n, branch=branch, throw=False)
    report.branch.write_csv(out_dir / "branch.csv")
    diagram_figure(report).savefig(out_dir / "branch.png", dpi=120)
    summary = info | report.as_dict() | {"points": len(report.branch)}
    (out_dir / "branch.json").write_text(json.dumps(summary, indent=2))
    print(json.dumps(summary) if args.json else
          f"{_header(info)}\n{len(report.branch)} branch points, {len(report.folds)} folds "
          f"with alpha > 0; wrote {out_dir / 'branch.csv'}, branch.png, branch.json")
    if not report.converged:
        _not_converged("branch", "; ".join(report.problems) or "a fold solve failed")
    return 0 if report.converged else 1


def _write_sweep(out_dir: Path, sweep: dict, summary: dict) -> None:
    with open(out_dir / "sweep.csv", "w") as fh:
        if not sweep["complete"]:
            fh.write(f"# incomplete: {sweep['reason']}\n")
        fh.write("direction,alpha_deg,tip_deg,q,snapped\n")
        for i in range(sweep["alpha_deg"].size):
            fh.write(f"{sweep['direction'][i]},{sweep['alpha_deg'][i]:.10g},"
                     f"{sweep['tip_deg'][i]:.10g},{sweep['q'][i]:.10g},"
                     f"{int(sweep['snapped'][i])}\n")
    (out_dir / "sweep.json").write_text(json.dumps(summary, indent=2))


def cmd_sweep(args) -> int:
    from jaxrod.magnet.folds import locate_folds
    from jaxrod.magnet.sweep import hysteresis_sweep
    from jaxrod.plotting import hysteresis_figure
    from jaxrod.progress import Interrupted

    if args.rig is not None or args.rate is not None:
        from jaxrod.cli.rate_sweep import rate_sweep_command, sweep_on_file

        return sweep_on_file(args) if args.rig is not None else rate_sweep_command(args)
    uses_scene_file(args)  # --set or --vary without a scene file is an error
    if args.out is None:
        raise ParameterError("out: give --out DIR (sweep.csv, sweep.png, sweep.json)")
    scene, info = _magnet_scene_from_args(args)
    out_dir = _output_dir(args.out)
    for name, default in (("alpha_max", 50.0), ("step", 0.25)):
        info["inputs"][name.replace("_", "-")] = _entry(
            default if getattr(args, name) is None else getattr(args, name), "deg",
            _source(args, name, "default"))
        if getattr(args, name) is None:
            setattr(args, name, default)
    try:
        sweep = hysteresis_sweep(scene, n=args.n, alpha_max_deg=args.alpha_max,
                                 step_deg=args.step, progress=not args.quiet, throw=False)
    except Interrupted as stop:
        sweep = stop.partial
        summary = info | {"snaps": sweep["snaps"], "converged": sweep["converged"],
                          "complete": False, "reason": sweep["reason"],
                          "positions": int(sweep["alpha_deg"].size)}
        _write_sweep(out_dir, sweep, summary)
        print(f"jaxrod sweep: {sweep['reason']}; wrote what was computed to "
              f"{out_dir / 'sweep.csv'} and sweep.json (marked incomplete)", file=sys.stderr)
        return 130
    report = locate_folds(scene, n=args.n, throw=False)
    summary = info | {"snaps": sweep["snaps"], "converged": sweep["converged"],
                      "complete": True, "positions": int(sweep["alpha_deg"].size),
                      "folds": [f.as_dict() for f in report.folds],
                      "hysteresis_width_deg": report.hysteresis_width_deg}
    _write_sweep(out_dir, sweep, summary)
    hysteresis_figure(sweep, report).savefig(out_dir / "sweep.png", dpi=120)
    if args.json:
        print(json.dumps(summary))
    else:
        print(_header(info))
        for snap in sweep["snaps"]:
            print(f"{snap['direction']}: snap at alpha = {snap['alpha_deg']:.4f} deg "
                  f"(tip {snap['tip_before_deg']:.3f} -> {snap['tip_after_deg']:.3f} deg)")
        print(f"wrote {out_dir / 'sweep.csv'}, sweep.png, sweep.json")
    if not sweep["converged"]:
        _not_converged("sweep", "a Newton step or an energy descent did not converge")
    return 0 if sweep["converged"] else 1


def add_folds(sub) -> None:
    f = sub.add_parser("folds", help="fold (switching) angles of the permanent-magnet scene, "
                       "or the folds along any input of a scene file")
    add_scene_file_inputs(f, vary=True)
    add_magnet_inputs(f)
    f.add_argument("--method", choices=["moore-spence", "reduced"], default="moore-spence")
    add_grid_options(f, branch=True)
    f.set_defaults(func=cmd_folds)


def add_certify(sub) -> None:
    c = sub.add_parser("certify", help="hypotheses of the paper's reduction, with margins")
    add_magnet_inputs(c)
    c.set_defaults(func=cmd_certify)


def add_branch(sub) -> None:
    b = sub.add_parser("branch", help="whole bifurcation diagram (CSV, PNG, JSON), or the "
                       "branch along any input of a scene file")
    add_scene_file_inputs(b, vary=True)
    add_magnet_inputs(b)
    b.add_argument("--out", help="output directory (required for the paper's diagram)")
    b.add_argument("--modes", type=int, default=0, metavar="K",
                   help="scene file: the lowest K omega^2 of the vibration modes at every "
                   "point (0 at a fold: the snap's soft mode)")
    add_grid_options(b, branch=True)
    b.set_defaults(func=cmd_branch)


def add_sweep(sub) -> None:
    w = sub.add_parser("sweep", help="quasi-static hysteresis sweep (CSV, PNG, JSON), or at a "
                       "finite rate (--rate)")
    add_magnet_inputs(w)
    w.add_argument("--out", help="output directory (the quasi-static sweep)")
    add_rate_sweep_options(w)
    w.add_argument("--alpha-max", type=_float("alpha-max", "alpha-max"), default=None,
                   help="sweep from -alpha_max to +alpha_max and back (deg, in (0, 90]; "
                   "default 50)")
    w.add_argument("--step", type=_float("step", "step"), default=None,
                   help="magnet step (deg, in (0, 5]; default 0.25)")
    w.add_argument("--quiet", action="store_true", help="no progress bar")
    w.set_defaults(func=cmd_sweep)
