"""``jaxrod snap``: the snap from a fold of the permanent-magnet scene (or the paper's wire
in seconds, --preset): duration, landing, peak speed and overshoot; the time series as JSON
or CSV, a figure and an animation of the rod."""

from __future__ import annotations

import csv
import json
import math

from jaxrod.cli._inputs import _degree, _float
from jaxrod.params import ParameterError


def cmd_snap(args) -> int:
    import jaxrod as jr
    from jaxrod.dynamics.snap import snap

    _check_before_work(args)
    from jaxrod.cli.scene_file import uses_scene_file

    if uses_scene_file(args):
        return snap_on_file(args)
    if args.fold not in ("lower", "upper"):
        raise ParameterError(f"fold: lower or upper for the paper's rig (a number K picks the "
                             f"K-th fold of a scene file's path), got {args.fold!r}")
    physical = _physical_snap(args)
    scene = jr.Scene({"bending": jr.Bending(), "gravity": jr.Gravity(args.G),
                      "magnet": jr.Dipole(args.M, args.D, 0.0)})
    folds = sorted(jr.folds(scene, "magnet.alpha", 0.0, math.pi / 2, n=args.n),
                   key=lambda f: f.value)
    if len(folds) < 2:
        raise ParameterError("G/M/D: this rig has no two folds in (0, 90] degrees (no snap)")
    fold = folds[0 if args.fold == "lower" else 1]
    kv = args.kelvin_voigt
    s = snap(scene, fold, args.damping, t_end=args.t_end, dt=args.dt, n=args.n,
             kelvin_voigt=kv, scheme=args.scheme)
    if physical is not None and args.medium == "air":  # Lamb's drag at the snap's peak speed
        from jaxrod.dynamics.drag import lamb_drag, nondimensional_damping

        for _ in range(3):
            speed = math.radians(s.peak_tip_speed) * physical["length"] / physical["T"]
            args.damping = nondimensional_damping(
                lamb_drag(physical["radius"], speed), physical["length"], physical["radius"],
                physical["E"], physical["density"])
            s = snap(scene, fold, args.damping, t_end=args.t_end, dt=args.dt, n=args.n,
                     kelvin_voigt=kv, scheme=args.scheme)
    out = {"G": args.G, "M": args.M, "D": args.D, "fold": args.fold,
           "fold_alpha_deg": math.degrees(fold.value), "alpha_deg": math.degrees(s.value),
           "damping": args.damping, "kelvin_voigt": kv, **s.as_dict(),
           "units": "time in L^2 sqrt(rho A_c / (E I)); angles in degrees"}
    out.pop("value")
    if physical is not None:
        T = physical["T"]
        out |= {"medium": args.medium, "time_scale_s": T, "damping": args.damping,
                "duration_s": None if s.duration is None else s.duration * T,
                "transit_s": None if s.transit is None else s.transit * T,
                "time_s": (s.trajectory.time * T).tolist()}
    _write_outputs(args, scene, s, out, "magnet.alpha")
    if args.json:
        print(json.dumps(out))
    else:
        d = "not settled by t_end" if s.duration is None else f"{s.duration:.6g}"
        if physical is not None:
            d += (f" ({out['duration_s']:.4g} s)" if out["duration_s"] is not None else "") \
                + f"; transit {out['transit_s']:.4g} s in {args.medium} (drag " \
                f"{args.damping:.3g})"
        print(_summary(f"snap from the {args.fold} fold (alpha* = "
                       f"{out['fold_alpha_deg']:.8f} deg, magnet at {out['alpha_deg']:.8f} "
                       "deg)", d, fold, s))
    return 0 if s.trajectory.converged else 1


def snap_on_file(args) -> int:
    """``jaxrod snap RIG --vary KEY --from A --to B --fold K``: the snap from the K-th fold
    (1 = the first) met along KEY, the input moved just past it; the same outputs as the
    paper's rig (time in L^2 sqrt(rho A_c / (E I)))."""
    import jaxrod as jr
    from jaxrod.cli.scene_file import _load, _range
    from jaxrod.dynamics.snap import snap

    try:
        k = {"lower": 1, "upper": 2}.get(args.fold) or int(args.fold)
    except ValueError:
        raise ParameterError(f"fold: a number K >= 1 (the K-th fold met), got "
                             f"{args.fold!r}") from None
    if k < 1:
        raise ParameterError(f"fold: a number K >= 1 (the K-th fold met), got {args.fold!r}")
    file = _load(args)
    key, start, stop, factor = _range(args, file)
    folds = jr.folds(file, key, start, stop, n=args.n)
    if len(folds) < k:
        raise ParameterError(f"fold: the path along {args.vary} from {args.start:g} to "
                             f"{args.stop:g} meets {len(folds)} fold(s); --fold {k} asks for "
                             f"fold {k}")
    fold = folds[k - 1]
    # past the fold by 1e-3 of the scene's input (radians for an angle), in the file's units;
    # a number that enters as a power (Young's modulus): by 1e-3 of its value
    past = 1e-3 / abs(file.inputs[key][1]) if key in file.inputs else 1e-3 * abs(fold.value)
    s = snap(file, fold, args.damping, t_end=args.t_end, dt=args.dt, n=args.n, past=past,
             kelvin_voigt=args.kelvin_voigt, scheme=args.scheme)
    out = {"rig": args.rig, "set": args.set, "vary": args.vary, "fold": k,
           "fold_value": fold.value / factor, "value": s.value / factor,
           "damping": args.damping, "kelvin_voigt": args.kelvin_voigt, **s.as_dict(),
           "units": "time in L^2 sqrt(rho A_c / (E I)); angles in degrees"}
    out["value"] = s.value / factor
    _write_outputs(args, file, s, out, fold.vary)
    if args.json:
        print(json.dumps(out))
    else:
        d = "not settled by t_end" if s.duration is None else f"{s.duration:.6g}"
        print(_summary(f"{args.rig}: snap from fold {k} ({args.vary} = "
                       f"{out['fold_value']:.10g}, moved to {out['value']:.10g})", d, fold, s))
    return 0 if s.trajectory.converged else 1


def _summary(head: str, duration: str, fold, s) -> str:
    return (f"{head}: duration {duration}, tip {fold.tip_angle_deg:.4f} -> "
            f"{s.rest_tip_deg:.4f} deg, peak tip speed {s.peak_tip_speed:.4g} deg per unit "
            f"time, overshoot {s.overshoot_deg:.4g} deg")


def _check_before_work(args) -> None:
    """The options that would fail only after the simulation, checked first: the damping,
    the time step against the simulated time, and the animation's writer (.gif: Pillow;
    anything else: ffmpeg, which must be on the PATH)."""
    for name in ("damping", "kelvin_voigt"):
        v = getattr(args, name)
        if v < 0 or not math.isfinite(v):
            raise ParameterError(f"{name.replace('_', '-')} must be a finite number >= 0, got "
                                 f"{v!r}")
    for name in ("t_end", "dt"):
        v = getattr(args, name)
        if not (math.isfinite(v) and v > 0):
            raise ParameterError(f"{name.replace('_', '-')} must be a finite number > 0, got "
                                 f"{v!r}")
    if args.dt > args.t_end / 10:
        raise ParameterError(f"dt: {args.dt:g} leaves fewer than 10 steps in --t-end "
                             f"{args.t_end:g} (a snap lasts ~1-10 time units; try 0.01)")
    if args.animate:
        import shutil

        if not str(args.animate).endswith(".gif") and shutil.which("ffmpeg") is None:
            raise ParameterError(f"animate: {args.animate} needs ffmpeg on the PATH (not "
                                 "found); write a .gif instead (Pillow)")


def _physical_snap(args):
    """With --preset: the groups and the time scale of the paper's wire and magnet; the
    drag from --medium (vacuum: none; air: Lamb's, set after the first run)."""
    if args.preset is None:
        if args.G is None or args.M is None or args.D is None:
            raise ParameterError("G: give --G --M --D, or --preset permanent-magnet")
        return None
    from jaxrod.dynamics.drag import time_scale
    from jaxrod.params import NDFEB_MAGNET, preset

    rod, _ = preset(args.preset)
    args.G, args.M, args.D = rod.G, rod.M(NDFEB_MAGNET), rod.D(NDFEB_MAGNET)
    args.damping = 0.0 if args.medium == "vacuum" else 1.0
    m = rod.material
    return {"length": rod.length, "radius": 0.5 * rod.diameter, "E": m.youngs_modulus,
            "density": m.density, "T": time_scale(rod.length, 0.5 * rod.diameter,
                                                  m.youngs_modulus, m.density)}


def add_snap(sub) -> None:
    from jaxrod.cli.scene_file import add_scene_file_inputs

    sn = sub.add_parser("snap", help="the snap from a fold of the permanent-magnet scene, or "
                        "of any scene file's path (time series, duration)")
    sn.add_argument("--G", type=_float("G", "G-magnet"), help="gravity group")
    sn.add_argument("--M", type=_float("M", "M"), help="magnet group")
    sn.add_argument("--D", type=_float("D", "D"), help="track radius / length")
    sn.add_argument("--preset", choices=["permanent-magnet"], default=None,
                    help="the paper's nickel wire and magnet, in seconds")
    sn.add_argument("--medium", choices=["air", "vacuum"], default="air",
                    help="with --preset: the drag (air: Lamb's law; vacuum: none)")
    add_scene_file_inputs(sn, vary=True)
    sn.add_argument("--fold", default="upper",
                    help="the paper's rig: lower or upper (default upper); a scene file: K, "
                    "the K-th fold met along --vary (lower = 1, upper = 2)")
    sn.add_argument("--damping", type=_float("damping"), default=1.0,
                    help="linear drag per unit length, units sqrt(rho A_c E I) / L^2")
    sn.add_argument("--t-end", type=_float("t-end"), default=60.0)
    sn.add_argument("--dt", type=_float("dt"), default=0.01)
    sn.add_argument("--n", type=_degree("N-magnet"), default=16)
    sn.add_argument("--kelvin-voigt", type=_float("kelvin-voigt"), default=0.0,
                    help="internal damping eta = eta_KV / (E T) (default 0)")
    sn.add_argument("--scheme", choices=["bdf2", "discrete-gradient", "midpoint"],
                    default=None, help="the integrator (default: bdf2 with damping, "
                    "discrete-gradient, which conserves the energy, without)")
    sn.add_argument("--json", action="store_true", help="print one JSON object")
    sn.add_argument("--csv", metavar="PATH", help="write the time series as CSV")
    sn.add_argument("--plot", metavar="PATH", help="write a figure (tip and energy in time)")
    sn.add_argument("--animate", metavar="PATH",
                    help="write an animation of the rod (.gif; .mp4 needs ffmpeg)")
    sn.set_defaults(func=cmd_snap)




def _write_outputs(args, scene, s, out, vary: str) -> None:
    """--csv, --plot, --animate (the scene at the snap's value of ``vary``)."""
    tr = s.trajectory
    scale = out.get("time_scale_s")
    if args.csv:
        with open(args.csv, "w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(["time", "tip_angle_deg", "tip_x", "tip_z", "kinetic", "potential"]
                       + (["time_s"] if scale else []))
            for k in range(len(tr.time)):
                w.writerow([f"{tr.time[k]:.10g}", f"{tr.tip_angle_deg[k]:.12g}",
                            f"{tr.tip_position[k, 0]:.12g}", f"{tr.tip_position[k, 2]:.12g}",
                            f"{tr.kinetic[k]:.12g}", f"{tr.potential[k]:.12g}"]
                           + ([f"{tr.time[k] * scale:.10g}"] if scale else []))
    if args.plot or args.animate:
        from jaxrod.dynamics import figures
        from jaxrod.scenes.path import along

        at = along(scene, (vary,)).at_host(s.value)
        if args.plot:
            figures.snap_figure(s, time_scale=scale).savefig(args.plot, dpi=150)
        if args.animate:
            figures.snap_animation(at, s, n=args.n, path=args.animate, time_scale=scale)
