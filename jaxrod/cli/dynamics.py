"""``jaxrod modes``: vibration modes of an equilibrium: the uniform-field scene at the
straight state (--G --A), the permanent magnet (--G --M --D --alpha), or any scene file."""

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

    from jaxrod.dynamics.modes import in_hertz, resolved_modes

    scene, file, inputs = _scene(args)
    for name in ("damping", "kelvin_voigt"):
        v = getattr(args, name)
        if not (math.isfinite(v) and v >= 0):
            raise ParameterError(f"{name.replace('_', '-')} must be a finite number >= 0, got "
                                 f"{v!r}")
    r = resolved_modes(scene, args.count, n=args.n, straight=args.straight)
    m = r.modes
    out = {"inputs": inputs, "n": r.n, **m.as_dict(args.count),
           "resolved": r.resolved, "error_estimate": r.error_estimate.tolist(),
           "converged": r.converged, "status": r.status.name.lower(),
           "units": "omega in 1 / (L^2 sqrt(rho A_c / (E I)))"}
    if args.damping or args.kelvin_voigt:
        out["damping_ratio"] = [None if not math.isfinite(z) else float(z) for z in
                                m.damping_ratios(args.damping, args.kelvin_voigt)[:args.count]]
    rod = (file.data.get("rod", {}) if file is not None else {})
    if file is not None and file.length != 1.0 and "density" in rod:
        out["frequency_hz"] = [float(f) for f in in_hertz(
            np.nan_to_num(m.omega[:args.count]), rod["length"], rod["radius"],
            rod["youngs_modulus"], rod["density"])]
    if args.plot:
        from jaxrod.dynamics.figures import modes_figure

        modes_figure(scene, m, n=r.n, count=min(args.count, 4)).savefig(args.plot, dpi=150)
    if args.json:
        print(json.dumps(out))
    else:
        hz, zeta = out.get("frequency_hz"), out.get("damping_ratio")
        for k, w in enumerate(out["omega"]):
            extra = f"  ({hz[k]:.6g} Hz)" if hz else ""
            extra += f"  damping ratio {zeta[k]:.4g}" if zeta and zeta[k] is not None else ""
            print(f"mode {k + 1}: omega = {w if w is None else f'{w:.10g}'}{extra}")
        print("stable" if m.stable else "UNSTABLE: omega^2 < 0 (NaN omega)")
        print(f"N = {r.n}: " + (f"the {r.count} modes agree with the previous degree's to "
                                f"{max(r.error_estimate):.1e}" if r.converged else
                                f"UNDER-RESOLVED: only the lowest {r.resolved} of {r.count} "
                                "agree with the previous degree's"))
    return 0 if r.converged else 1


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
    mo.add_argument("--n", type=_degree("N"), default=24,
                    help="the first Chebyshev degree (default 24), raised until the modes "
                    "asked for agree with a coarser degree's to 1e-9")
    mo.add_argument("--damping", type=_float("damping"), default=0.0,
                    help="linear drag per unit length: print the damping ratios")
    mo.add_argument("--kelvin-voigt", type=_float("kelvin-voigt"), default=0.0,
                    help="internal damping eta = eta_KV / (E T): print the damping ratios")
    mo.add_argument("--json", action="store_true", help="print one JSON object")
    mo.add_argument("--plot", metavar="PATH", help="write a figure of the mode shapes")
    mo.set_defaults(func=cmd_modes)
