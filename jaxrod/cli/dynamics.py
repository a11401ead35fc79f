"""``jaxrod modes``: vibration modes of an equilibrium: the uniform-field scene at the
straight state (--G --A), the permanent magnet (--G --M --D --alpha), or any scene file.
``jaxrod snap``: the snap from a fold of the permanent-magnet scene."""

from __future__ import annotations

import json
import math

from jaxrod.cli._inputs import _degree, _float
from jaxrod.cli.scene_file import add_scene_file_inputs, uses_scene_file
from jaxrod.params import ParameterError


def _scene(args):
    import jaxrod as jr

    if uses_scene_file(args):
        from jaxrod.scenes.files import load

        file = load(args.rig, args.set)
        return file.scene, file, {"rig": args.rig, "set": args.set}
    if args.G is None:
        raise ParameterError("G: give --G (with --A for the uniform field, or --M --D for the "
                             "permanent magnet), or a scene file")
    for name in ("G", "A"):
        value = getattr(args, name)
        if value is not None and not (math.isfinite(value) and 0.0 <= value <= 1e7):
            raise ParameterError(f"{name} must be a finite number in [0, 1e7], got {value!r}")
    terms = {"bending": jr.Bending(), "gravity": jr.Gravity(args.G)}
    if args.M is not None or args.D is not None:
        if args.M is None or args.D is None or args.A is not None:
            raise ParameterError("M: the permanent magnet needs --M and --D (and no --A)")
        terms["magnet"] = jr.Dipole(args.M, args.D, math.radians(args.alpha))
        return jr.Scene(terms), None, {"G": args.G, "M": args.M, "D": args.D,
                                       "alpha_deg": args.alpha}
    terms["field"] = jr.Anisotropy(args.A or 0.0)
    return jr.Scene(terms), None, {"G": args.G, "A": args.A or 0.0}


def cmd_modes(args) -> int:
    import numpy as np

    from jaxrod.dynamics.modes import in_hertz, modes

    scene, file, inputs = _scene(args)
    state = np.zeros(scene_size(scene, args.n)) if args.straight else None
    m = modes(scene, state, n=args.n)
    out = {"inputs": inputs, "n": args.n, **m.as_dict(args.count),
           "units": "omega in 1 / (L^2 sqrt(rho A_c / (E I)))"}
    rod = (file.data.get("rod", {}) if file is not None else {})
    if file is not None and file.length != 1.0 and "density" in rod:
        out["frequency_hz"] = [float(f) for f in in_hertz(
            np.nan_to_num(m.omega[:args.count]), rod["length"], rod["radius"],
            rod["youngs_modulus"], rod["density"])]
    if args.json:
        print(json.dumps(out))
    else:
        hz = out.get("frequency_hz")
        for k, w in enumerate(out["omega"]):
            extra = f"  ({hz[k]:.6g} Hz)" if hz else ""
            print(f"mode {k + 1}: omega = {w if w is None else f'{w:.10g}'}{extra}")
        print("stable" if m.stable else "UNSTABLE: omega^2 < 0 (NaN omega)")
    return 0


def scene_size(scene, n: int) -> int:
    from jaxrod.equilibria.equilibrium import discretise

    return discretise(scene, n).size


def cmd_snap(args) -> int:
    import jaxrod as jr
    from jaxrod.dynamics.snap import snap

    physical = _physical_snap(args)
    if args.damping < 0 or not math.isfinite(args.damping):
        raise ParameterError(f"damping must be a finite number >= 0, got {args.damping!r}")
    scene = jr.Scene({"bending": jr.Bending(), "gravity": jr.Gravity(args.G),
                      "magnet": jr.Dipole(args.M, args.D, 0.0)})
    folds = sorted(jr.scene_folds(scene, "magnet.alpha", 0.0, math.pi / 2, n=args.n),
                   key=lambda f: f.value)
    if len(folds) < 2:
        raise ParameterError("G/M/D: this rig has no two folds in (0, 90] degrees (no snap)")
    fold = folds[0 if args.fold == "lower" else 1]
    s = snap(scene, fold, args.damping, t_end=args.t_end, dt=args.dt, n=args.n)
    if physical is not None and args.medium == "air":  # Lamb's drag at the snap's peak speed
        from jaxrod.dynamics.drag import lamb_drag, nondimensional_damping

        for _ in range(3):
            speed = math.radians(s.peak_tip_speed) * physical["length"] / physical["T"]
            args.damping = nondimensional_damping(
                lamb_drag(physical["radius"], speed), physical["length"], physical["radius"],
                physical["E"], physical["density"])
            s = snap(scene, fold, args.damping, t_end=args.t_end, dt=args.dt, n=args.n)
    out = {"G": args.G, "M": args.M, "D": args.D, "fold": args.fold,
           "fold_alpha_deg": math.degrees(fold.value), "alpha_deg": math.degrees(s.value),
           "damping": args.damping, **s.as_dict(),
           "units": "time in L^2 sqrt(rho A_c / (E I)); angles in degrees"}
    out.pop("value")
    if physical is not None:
        T = physical["T"]
        out |= {"medium": args.medium, "time_scale_s": T, "damping": args.damping,
                "duration_s": None if s.duration is None else s.duration * T,
                "transit_s": None if s.transit is None else s.transit * T,
                "time_s": (s.trajectory.time * T).tolist()}
    if args.json:
        print(json.dumps(out))
    else:
        d = "not settled by t_end" if s.duration is None else f"{s.duration:.6g}"
        if physical is not None:
            d += (f" ({out['duration_s']:.4g} s)" if out["duration_s"] is not None else "") \
                + f"; transit {out['transit_s']:.4g} s in {args.medium} (drag " \
                f"{args.damping:.3g})"
        print(f"snap from the {args.fold} fold (alpha* = {out['fold_alpha_deg']:.8f} deg, "
              f"magnet at {out['alpha_deg']:.8f} deg): duration {d}, tip "
              f"{fold.tip_angle_deg:.4f} -> {s.rest_tip_deg:.4f} deg, peak tip speed "
              f"{s.peak_tip_speed:.4g} deg per unit time, overshoot {s.overshoot_deg:.4g} deg")
    return 0 if s.trajectory.converged else 1


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
    sn = sub.add_parser("snap", help="the snap from a fold of the permanent-magnet scene "
                        "(time series, duration)")
    sn.add_argument("--G", type=_float("G", "G-magnet"), help="gravity group")
    sn.add_argument("--M", type=_float("M", "M"), help="magnet group")
    sn.add_argument("--D", type=_float("D", "D"), help="track radius / length")
    sn.add_argument("--preset", choices=["permanent-magnet"], default=None,
                    help="the paper's nickel wire and magnet, in seconds")
    sn.add_argument("--medium", choices=["air", "vacuum"], default="air",
                    help="with --preset: the drag (air: Lamb's law; vacuum: none)")
    sn.add_argument("--fold", choices=["lower", "upper"], default="upper")
    sn.add_argument("--damping", type=_float("damping"), default=1.0,
                    help="linear drag per unit length, units sqrt(rho A_c E I) / L^2")
    sn.add_argument("--t-end", type=_float("t-end"), default=60.0)
    sn.add_argument("--dt", type=_float("dt"), default=0.01)
    sn.add_argument("--n", type=_degree("N-magnet"), default=16)
    sn.add_argument("--json", action="store_true", help="print one JSON object")
    sn.set_defaults(func=cmd_snap)


def add_modes(sub) -> None:
    mo = sub.add_parser("modes", help="vibration modes (natural frequencies) of an equilibrium")
    add_scene_file_inputs(mo, vary=False)
    mo.add_argument("--G", type=_float("G"), help="gravity group, >= 0 (0: no gravity)")
    mo.add_argument("--A", type=_float("A"), help="anisotropy group (uniform field), >= 0")
    mo.add_argument("--M", type=_float("M", "M"), help="magnet group")
    mo.add_argument("--D", type=_float("D", "D"), help="track radius / rod length")
    mo.add_argument("--alpha", type=_float("alpha", "alpha"), default=0.0,
                    help="magnet angle, deg (default 0)")
    mo.add_argument("--straight", action="store_true",
                    help="about the straight rod (default: the ramped equilibrium)")
    mo.add_argument("--count", type=int, default=6, help="how many modes (default 6)")
    mo.add_argument("--n", type=_degree("N"), default=24, help="Chebyshev degree (default 24)")
    mo.add_argument("--json", action="store_true", help="print one JSON object")
    mo.set_defaults(func=cmd_modes)
