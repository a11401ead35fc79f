"""``jaxrod equilibrium RIG``, and ``jaxrod branch | folds RIG --vary KEY --from A --to B``:
any rig described by a scene file (``jaxrod.scenes.files``), with ``--set KEY=VALUE``
overrides. Angles are from +z toward +x: ``tip_angle_deg`` is the direction of the tip's
position (the paper's tip angle), ``tip_tangent_deg`` the tangent's angle at the tip (its
rotation); ``tip_position`` is in the file's length unit."""

from __future__ import annotations

import json

import numpy as np

from jaxrod.cli._inputs import _degree, _float
from jaxrod.cli.framed_rod import add_grid_options, check_grid_options
from jaxrod.params import ParameterError
from jaxrod.status import Status


def add_scene_file_inputs(p, vary: bool, to: bool = True, vary_name: str = "--vary") -> None:
    """The scene-file options: the file (optional where the command also takes the paper's
    options), ``--set``, and for branches and folds ``--vary/--from/--to`` (``to`` False
    where the command has its own ``--vary`` and ``--to``; ``vary_name`` where its own
    ``--vary`` means something else)."""
    p.add_argument("rig", nargs="?", default=None,
                   help="a scene file (TOML, or JSON): the rig, its fields and magnets")
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                   help="override an entry of the scene file (dotted key, e.g. "
                   "field.0.angle_deg=120); repeatable")
    if vary:
        if to:
            p.add_argument(vary_name, metavar="KEY", help="the scene file's number to vary "
                           "(dotted key, e.g. field.0.angle_deg or rod.youngs_modulus)")
            p.add_argument("--to", dest="stop", type=_float("to"), default=None,
                           help="its last value")
        p.add_argument("--from", dest="start", type=_float("from"), default=None,
                       help="the varied input's first value (the file's units)")


def uses_scene_file(args, vary_is_file_key: bool = True) -> bool:
    """Whether a command runs on a scene file; ParameterError if scene-file options come
    without one (``vary_is_file_key`` False where the command's own ``--vary`` means an
    input of the paper's rig)."""
    if args.rig is not None:
        paper = [o for o in ("G", "M", "D", "preset") if getattr(args, o, None) is not None]
        if paper:
            raise ParameterError(f"rig: give a scene file or --{paper[0]}, not both")
        return True
    given = [o for o, v in (("set", args.set), ("from", getattr(args, "start", None)),
                            ("vary", getattr(args, "vary", None) if vary_is_file_key
                             else None), ("layer-width", getattr(args, "layer_width", None)),
                            ("centred", getattr(args, "centred", False)),
                            ("max-folds", getattr(args, "max_folds", None))) if v]
    if given:
        raise ParameterError(f"{given[0]}: name a scene file first (jaxrod COMMAND RIG.toml "
                             "...)")
    return False


def _load(args, framed: bool = False):
    from jaxrod.scenes.files import load

    return load(args.rig, args.set, framed=framed)


def _range(args, file):
    if getattr(args, "stop", None) is None and getattr(args, "to", None) is not None:
        args.stop = args.to
    if args.vary is None or args.start is None or args.stop is None:
        raise ParameterError("vary: give --vary KEY --from A --to B with a scene file")
    from jaxrod.scenes.path import along

    along(file, (args.vary,))  # any number of the file (its units), named if it is not one
    if args.start == args.stop:
        raise ParameterError(f"to: must differ from --from ({args.start:g})")
    return args.vary, args.start, args.stop, 1.0


def _at(eq_tip_deg, X, file) -> dict:
    return {"tip_angle_deg": eq_tip_deg, "tip_position": [float(v) * file.length for v in X]}


def cmd_equilibrium(args) -> int:

    if not uses_scene_file(args):
        raise ParameterError("rig: name a scene file (jaxrod equilibrium RIG.toml)")
    from jaxrod.equilibria.resolution import resolved_equilibrium

    file = _load(args, framed=True)
    check_grid_options(args, file)
    if file.framed is not None:
        from jaxrod.cli.framed_rod import framed_equilibrium

        return framed_equilibrium(args, file)
    r = resolved_equilibrium(file.scene, n=args.n)
    eq = r.equilibrium
    out = {"rig": args.rig, "set": args.set, **_at(eq.tip_angle_deg, eq.tip_position, file),
           "tip_tangent_deg": eq.tip_tangent_deg, "stable": eq.stable,
           "converged": r.converged, "status": r.status.name.lower(),
           "message": r.status.message, "smallest_eigenvalue": eq.smallest_eigenvalue,
           "residual_norm": eq.residual_norm, "error_estimate": r.error_estimate, "n": r.n}
    if args.json:
        print(json.dumps(out))
    else:
        X = out["tip_position"]
        print(f"{args.rig}: tip angle {eq.tip_angle_deg:.10f} deg, tip tangent "
              f"{eq.tip_tangent_deg:.10f} deg, tip at ({X[0]:.6g}, {X[1]:.6g}, {X[2]:.6g}); "
              f"{'stable' if eq.stable else 'UNSTABLE'}; {out['message']} (N = {r.n}, "
              f"error estimate {r.error_estimate:.1e} rad)")
    return 0 if r.converged else 1


def branch_on_file(args) -> int:
    """``jaxrod branch RIG --vary KEY --from A --to B``: the branch's points, its folds and
    its branch points (JSON with --json; branch.csv and branch.json with --out)."""


    if getattr(args, "modes", 0):
        from jaxrod.dynamics.modes import resolvable

        if not 0 <= args.modes <= resolvable(args.n):
            raise ParameterError(f"modes: degree {args.n} resolves the lowest 0 to "
                                 f"{resolvable(args.n)} modes (raise --n for more), got "
                                 f"{args.modes}")
    file = _load(args, framed=True)
    check_grid_options(args, file)
    if file.framed is not None:
        from jaxrod.cli.framed_rod import framed_branch, framed_range

        framed_range(args, file)
        return framed_branch(args, file, args.start, args.stop)
    key, start, stop, factor = _range(args, file)
    from jaxrod.equilibria.resolution import resolved_branch

    r = resolved_branch(file, key, start, stop, n=args.n)
    b, folds, points = r.branch, r.folds, r.branch_points
    values = np.asarray(b.value) / factor
    out = {"vary": args.vary, "points": len(values),
           "value": values.tolist(), "tip_angle_deg": np.degrees(b.tip).tolist(),
           "stable": [bool(s) for s in b.stable],
           "folds": [_fold(f, factor, file) for f in folds],
           "branch_points": [{"value": p.value / factor,
                              **_at(p.tip_angle_deg, p.tip_position, file),
                              "morse_index": list(p.morse_index), "converged": p.converged,
                              "residual_norm": p.residual_norm,
                              "error_estimate": p.error_estimate} for p in points],
           **_path_status(r, factor)}
    w2 = None
    if getattr(args, "modes", 0):  # the vibration modes as rows of the branch
        from jaxrod.dynamics.modes import modes_along

        w2 = modes_along(file, b, n=r.n, count=args.modes)
        out["omega_squared"] = w2.tolist()
    if args.out:
        from jaxrod.cli._output import _output_dir

        out_dir = _output_dir(args.out)
        (out_dir / "branch.json").write_text(json.dumps(out, indent=1))
        rows = np.column_stack([values, np.degrees(b.tip), b.min_eig, b.morse_index]
                               + ([w2] if w2 is not None else []))
        extra = "".join(f",omega_squared_{k + 1}" for k in range(args.modes)) if w2 is not \
            None else ""
        np.savetxt(out_dir / "branch.csv", rows, delimiter=",",
                   header=f"{args.vary},tip_angle_deg,min_eig,morse_index{extra}", comments="")
        branch_figure(out_dir / "branch.png", values, np.degrees(b.tip), b.stable, out,
                      args.vary)
    if args.json:
        print(json.dumps(out))
    else:
        print(f"{args.rig}: {len(values)} points along {args.vary} from {args.start:g} to "
              f"{args.stop:g}; {len(folds)} folds, {len(points)} branch points")
        print_points(out, args.vary, lambda f: f"tip angle {f['tip_angle_deg']:.6f} deg")
    return 0 if out["converged"] else 1


def print_points(out: dict, vary: str, describe) -> None:
    """The folds and branch points of a branch's report, a line each (``describe``: what
    to say of a point), and where it ended when it stopped early."""
    for kind, items in (("fold", out["folds"]), ("branch point", out["branch_points"])):
        for f in items:
            print(f"  {kind} at {vary} = {f['value']:.10g} ({describe(f)})"
                  + ("" if f["converged"] else "  NOT CONVERGED"))
    if not out["converged"]:
        print(f"  {out['status']} (the branch ended at {vary} = {out['last_value']:.10g}): "
              f"{out['message']}")


def branch_figure(path, values, y, stable, out, vary, key: str = "tip_angle_deg",
                  label: str = "tip angle (deg)") -> None:
    """A branch's ``y`` (the tip angle; ``key`` of its points in ``out``) against the
    varied input: stable solid, unstable dashed, the folds (x) and branch points (o), the
    branch's end marked when it stopped early."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.5, 4.5))
    for mask, style, colour, name in ((stable, "-", "C0", "stable"),
                                      (~stable, "--", "C3", "unstable")):
        ax.plot(values, np.where(mask, y, np.nan), style, color=colour, label=name)
    if np.ptp(y) < 1e-6:  # a straight branch: its round-off is not a shape
        ax.set_ylim(np.mean(y) - 1.0, np.mean(y) + 1.0)
    for kind, marker, name in (("folds", "kx", "fold"), ("branch_points", "ko",
                                                          "branch point")):
        pts = out[kind]
        if pts:
            ax.plot([p["value"] for p in pts], [p[key] for p in pts], marker, mfc="none",
                    label=name)
    if not out["complete"]:
        ax.plot(values[-1:], y[-1:], "r|", ms=14, label=f"ended: {out['status']}")
    ax.set_xlabel(vary)
    ax.set_ylabel(label)
    ax.legend(fontsize=8)
    fig.savefig(path, dpi=120)
    plt.close(fig)


def _path_status(r, factor) -> dict:
    """What a resolved branch and its refined points say, as the commands print it:
    ``converged`` (the branch reached the end of its range, every point converged and the
    degree resolves them), ``status`` (why not: the branch's first failing status, else
    ``not_converged`` for a point, else ``under_resolved``), the branch's statuses,
    ``complete``, ``last_value`` (where it ended), ``n`` and ``error_estimate``."""
    b = r.branch
    failed = [s for s in b.status if not s.ok]
    status = failed[0] if failed else (
        Status.NOT_CONVERGED if not all(p.converged for p in r.folds + r.branch_points) else
        Status.SUCCESS if r.resolved else Status.UNDER_RESOLVED)
    return {"converged": status == Status.SUCCESS and b.complete,
            "status": status.name.lower(), "message": status.message,
            "branch_status": [s.name.lower() for s in b.status], "complete": b.complete,
            "last_value": float(b.value[-1]) / factor, "n": r.n,
            "error_estimate": r.error_estimate}


def _fold(f, factor, file) -> dict:
    return {"value": f.value / factor, **_at(f.tip_angle_deg, f.tip_position, file),
            "dF_dvalue": f.dF_dvalue * factor, "normal_form_c": f.normal_form_c,
            "converged": f.converged, "residual_norm": f.residual_norm,
            "error_estimate": f.error_estimate}


def folds_on_file(args) -> int:
    """``jaxrod folds RIG --vary KEY --from A --to B``: the folds met along the path, in
    order (a rod that carries its frame: ``jaxrod branch``'s report, its ``folds`` among
    it)."""
    from jaxrod.equilibria.resolution import resolved_branch

    file = _load(args, framed=True)
    check_grid_options(args, file)
    if file.framed is not None:  # its branch, with the folds refined on it
        from jaxrod.cli.framed_rod import framed_branch, framed_range

        framed_range(args, file)
        return framed_branch(args, file, args.start, args.stop)
    key, start, stop, factor = _range(args, file)
    r = resolved_branch(file, key, start, stop, n=args.n, points=False)
    out = {"vary": args.vary, "folds": [_fold(f, factor, file) for f in r.folds],
           **_path_status(r, factor)}
    if args.json:
        print(json.dumps(out))
    else:
        print(f"{args.rig}: {len(r.folds)} folds along {args.vary} from {args.start:g} to "
              f"{args.stop:g} (N = {r.n}, error estimate {r.error_estimate:.1e} rad)")
        for f in out["folds"]:
            print(f"  fold at {args.vary} = {f['value']:.12g} (tip angle "
                  f"{f['tip_angle_deg']:.10f} deg)"
                  + ("" if f["converged"] else "  NOT CONVERGED"))
        if not out["converged"]:
            print(f"  {out['status']} (the branch ended at {args.vary} = "
                  f"{out['last_value']:.10g}): {out['message']}")
    return 0 if out["converged"] else 1


def add_equilibrium(sub) -> None:
    e = sub.add_parser("equilibrium", help="the equilibrium of a rig given by a scene file")
    add_scene_file_inputs(e, vary=False)
    e.add_argument("--n", type=_degree("N-magnet"), default=None,
                   help="the first Chebyshev degree, 4-64 (default 16; 48 for a rod held at "
                   "both ends), raised until the state's Chebyshev tail is at most 1e-8 "
                   "rad (else under_resolved)")
    add_grid_options(e)
    e.add_argument("--json", action="store_true", help="print one JSON object")
    e.set_defaults(func=cmd_equilibrium, n_fallback=16)

