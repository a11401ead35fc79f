"""``jaxrod fit | design``: calibration on measured switching angles, inverse design (and
on any rig's scene file: ``scene_inverse``)."""

from __future__ import annotations

import argparse
import json
import math

from jaxrod.cli._inputs import (
    _MAGNET_PHYSICAL,
    BATCH_N,
    _design_point_from_args,
    _entry,
    _float,
    _inputs_line,
    _magnet_physical_from_args,
    _names,
    _pairs,
    _with_n,
    add_magnet_inputs,
    add_physical_inputs,
)
from jaxrod.cli._output import _not_converged, _output_dir
from jaxrod.cli.scene_file import uses_scene_file
from jaxrod.cli.scene_inverse import (
    _legacy_keys,
    add_design_scene_options,
    add_fit_scene_options,
    design_on_file,
    fit_on_file,
)
from jaxrod.params import GROUP_NAMES, PHYSICAL_NAMES, UNITS, Magnet, ParameterError


def _measured_from_args(args) -> list:
    from jaxrod.inverse.fit import ANGLE_NAMES

    named = [getattr(args, name) for name in ANGLE_NAMES]
    if args.angles is not None:
        if any(v is not None for v in named):
            raise ParameterError("angles: give --angles or the named angles, not both")
        measured = args.angles
    else:
        if all(v is None for v in named):
            raise ParameterError("angles: give --angles CW_CAPTURE CW_RELEASE CCW_CAPTURE "
                                 "CCW_RELEASE, or some of --cw-capture/--cw-release/"
                                 "--ccw-capture/--ccw-release")
        measured = [math.nan if v is None else v for v in named]
    if len(measured) != 4:
        raise ParameterError(f"angles: --angles takes 4 values ({', '.join(ANGLE_NAMES)}), "
                             f"got {len(measured)}")
    return measured


def _physical_point(args):
    """(DesignPoint, inputs used) of the wire and magnet: the user's, the rest the paper's."""
    from jaxrod.design_point import DesignPoint

    physical = _magnet_physical_from_args(args)
    if physical is None:
        args_empty = argparse.Namespace(**{k: None for k in _MAGNET_PHYSICAL + (
            "G", "M", "D", "magnet_radius")})
        args_empty.preset = "permanent-magnet"
        physical = _magnet_physical_from_args(args_empty)
        for entry in physical[2].values():
            entry["source"] = entry["source"].replace("given", "preset permanent-magnet")
    rod, magnet, inputs = physical
    if args.D_ratio is not None:
        magnet = Magnet(magnet.diameter, magnet.remanence, args.D_ratio * rod.length)
        inputs["track-radius"] = _entry(magnet.track_radius, "m", "from --D")
    return DesignPoint.from_physical(rod, magnet), inputs


def cmd_fit(args) -> int:
    from jaxrod.inverse.fit import ANGLE_NAMES, FREE_NAMES, OFFSET, Prior, fit, profile

    if uses_scene_file(args):
        return fit_on_file(args)
    measured = _measured_from_args(args)
    args.sigma_given = args.sigma_deg is not None
    args.sigma_deg = 1.0 if args.sigma_deg is None else args.sigma_deg
    if args.free is not None:
        free = _names(args.free, "free")
        if args.offset and OFFSET not in free:
            free += (OFFSET,)
    else:
        free = ("E", OFFSET) if args.offset else ("E",)
    priors = {}
    for k, v in _pairs(args.prior, "prior", FREE_NAMES).items():
        try:
            priors[k] = Prior(*v)
        except ParameterError as err:
            raise ParameterError(f"prior {k}: {err}") from None
    bounds = _pairs(args.bounds, "bounds", FREE_NAMES)
    out_dir = _output_dir(args.out) if args.out else None
    if args.profile and out_dir is None:
        raise ParameterError("profile: --profile writes profile.png; give --out DIR")
    point, inputs = _physical_point(args)
    for name, prior in priors.items():
        if name == OFFSET:
            continue
        given = point.values[point.index(name)]
        if not 0.01 <= prior.mean / given <= 100.0:
            raise ParameterError(
                f"prior {name}: mean {prior.mean:g} {UNITS[name]} is {prior.mean / given:.3g} "
                f"times the wire's {given:g} {UNITS[name]}; give SI units"
                + (" or tesla with a T suffix (1.2T)" if UNITS[name] == "A/m" else ""))
    inputs["sigma-deg"] = _entry(args.sigma_deg, "deg", "given" if args.sigma_given
                                 else "default")
    cal = fit(measured, free, point, priors, args.sigma_deg, bounds)
    units = {n: "deg" if n == OFFSET else UNITS[n] for n in cal.free}
    out = cal.as_dict() | {"units": units, "inputs": inputs} | _legacy_keys(cal)
    profiles = []
    if args.profile:
        profiles = [profile(measured, name, free, point, priors, args.sigma_deg, fitted=cal)
                    for name in free]
        out["profiles"] = profiles
    if out_dir is not None:
        (out_dir / "fit.json").write_text(json.dumps(out, indent=1))
        if profiles:
            from jaxrod.plotting import profile_figure

            profile_figure(profiles, cal).savefig(out_dir / "profile.png", dpi=120)
    if args.json:
        print(json.dumps(out))
    else:
        print(_inputs_line(inputs))
        _print_calibration(cal, ANGLE_NAMES, units)
        if out_dir is not None:
            print(f"wrote {out_dir / 'fit.json'}" + (", profile.png" if profiles else ""))
    if not cal.converged:
        _not_converged("fit", cal.reason)
    return 0 if cal.converged else 1


def _print_calibration(cal, angle_names, units) -> None:
    if not cal.converged:
        print(f"NOT CONVERGED after {cal.iterations} iterations: {cal.reason}")
        print("last iterate (not an estimate): " + ", ".join(
            f"{n} = {v:.6g} {units[n]}" for n, v in cal.estimates.items()))
        for w in cal.warnings:
            if "signs" in w:
                print(f"hint: {w}")
        return
    priors = ", ".join(f"{n} = {p.mean:.6g} +- {p.sd:.3g} {units.get(n, '')}"
                       for n, p in cal.priors.items())
    print(f"free: {', '.join(cal.free)}" + (f"; priors: {priors}" if priors else "")
          + f"; sigma = {cal.sigma:g} deg per angle")
    for n, v in cal.estimates.items():
        scale, unit = (1e9, "GPa") if n == "E" else (1.0, units[n])
        sd = cal.std[n]
        spread = (f"+- {sd / scale:.6g}" if sd is not None else
                  "(no standard deviation: not fixed by the angles and priors)")
        print(f"  {n:16s} = {v / scale:.6g} {spread} {unit}")
    if len(cal.free) > 1:
        print("correlations: " + ", ".join(
            f"{a}/{b} {cal.correlation[i, j]:+.3f}" for i, a in enumerate(cal.free)
            for j, b in enumerate(cal.free) if j > i and math.isfinite(cal.correlation[i, j])))
    print("residuals (model - measured):")
    for name, r in zip(angle_names, cal.residuals):
        if r is not None:
            print(f"  {name:12s} {r:+.4f} deg")
    red = "undefined (no degree of freedom)" if cal.reduced_chi2 is None else \
        f"{cal.reduced_chi2:.4g}"
    print(f"chi^2 = {cal.chi2:.4g} (angles and priors), {cal.dof} degrees of freedom, "
          f"reduced chi^2 = {red} (~1 when sigma is right)")
    for e in cal.identifiability:
        print(("the angles fix " if e["fixed_by_data"] else "the angles CANNOT fix ")
              + e["combination_text"]
              + (f" (std {e['std']:.3g})" if e["std"] is not None else ""))
    for w in cal.warnings:
        print(f"warning: {w}")
    print(f"converged: True after {cal.iterations} iterations")


PAPER_GROUPS = {"G": 2.2, "M": 0.0236, "D": 11.25 / 9.2}


def cmd_design(args) -> int:
    from jaxrod.inverse.design import design

    if uses_scene_file(args, vary_is_file_key=False):
        return design_on_file(args)
    if args.vary is None or args.capture is None or args.release is None:
        raise ParameterError("vary: give --capture, --release and --vary NAMES")
    vary = _names(args.vary, "vary")
    groups = any(getattr(args, k) is not None for k in ("G", "M", "D", "magnet_radius")) or (
        all(k in GROUP_NAMES for k in vary)
        and all(getattr(args, k) is None for k in _MAGNET_PHYSICAL))
    allowed = GROUP_NAMES if groups else PHYSICAL_NAMES
    for name in vary:
        if name not in allowed:
            other = PHYSICAL_NAMES if groups else GROUP_NAMES
            hint = (f"{name} is a {'physical input' if groups else 'group'}: with "
                    + ("--G/--M/--D vary groups" if groups else "physical inputs vary "
                       "physical inputs") + f" ({', '.join(allowed)})" if name in other else
                    f"unknown input {name!r}; choose from {', '.join(allowed)}")
            raise ParameterError(f"vary: {hint}")
    if len(set(vary)) != len(vary):
        raise ParameterError(f"vary: an input is named twice in {args.vary!r}")
    if groups:
        filled = {}
        for k in GROUP_NAMES:
            if getattr(args, k) is None:
                if k not in vary:
                    raise ParameterError(f"{k}: give --{k} (only varied groups may be left "
                                         "out; they start from the paper's value)")
                filled[k] = PAPER_GROUPS[k]
                setattr(args, k, PAPER_GROUPS[k])
        point, inputs = _design_point_from_args(args)
        for k, v in filled.items():
            inputs[k] = _entry(v, "", "start: the paper's value")
    else:
        args.D_ratio = None
        point, inputs = _physical_point(args)
        inputs = _with_n(inputs, args)
    allowed = point.names
    bounds = _pairs(args.bounds, "bounds", allowed)
    result = design(point, args.capture, args.release, vary, bounds, n=args.n)
    out = result.as_dict() | {"inputs": inputs}
    if args.json:
        print(json.dumps(out))
    else:
        print(_inputs_line(inputs))
        print(f"targets: capture {result.capture_deg:g} deg, release {result.release_deg:g} deg"
              f"; varying {', '.join(vary)} within " + ", ".join(
                  f"[{lo:.6g}, {hi:.6g}]" for lo, hi in result.bounds.values())
              + f" ({result.starts} starts)")
        if result.family:
            print(f"{len(vary)} inputs for 2 targets: the designs form a {result.family}-"
                  f"parameter family; below are {len(result.designs)} of them (vary two "
                  "inputs, or fix the others, for isolated designs)")
        for i, d in enumerate(result.designs):
            values = ", ".join(f"{n} = {v:.10g} {UNITS[n]}".rstrip() for n, v in d.values.items())
            check = (f"fresh continuation: {d.verified_capture_deg:.10f} / "
                     f"{d.verified_release_deg:.10f} deg" if d.verified_capture_deg is not None
                     else d.check)
            print(f"design {i + 1}: {values}  (model folds {d.capture_deg:.10f} / "
                  f"{d.release_deg:.10f} deg; {check}; verified: {d.verified})")
    ok = bool(result.designs) and result.designs[0].verified
    if not ok:
        _not_converged("design", "the fresh continuation at the design disagrees with the "
                       "model's folds")
    return 0 if ok else 1


def add_fit(sub) -> None:
    ft = sub.add_parser("fit", help="calibrate E and other inputs on measured switching angles",
                        description="Angles in degrees, sign of the magnet angle (positive "
                        "towards e1), in the order of the protocol: capture and release of the "
                        "clockwise sweep (alpha increasing), then capture and release of the "
                        "counter-clockwise sweep. The wire and magnet are the paper's unless "
                        "given (--E, --length, --track-radius, ...).")
    add_fit_scene_options(ft)
    ft.add_argument("--preset", choices=["permanent-magnet"], default=None)
    ft.add_argument("--angles", type=_float("angles"), nargs="+",
                    help="CW_CAPTURE CW_RELEASE CCW_CAPTURE CCW_RELEASE (deg)")
    for name in ("cw_capture", "cw_release", "ccw_capture", "ccw_release"):
        ft.add_argument("--" + name.replace("_", "-"), dest=name, type=_float(name),
                        default=None, help="one measured angle (deg); omit the others")
    ft.add_argument("--sigma-deg", type=_float("sigma-deg", "sigma-deg"), default=None,
                    help="measurement error per angle (deg, default 1)")
    ft.add_argument("--free", default=None, help="comma-separated inputs to fit: E, "
                    "remanence, magnet-diameter, track-radius, length, diameter, offset, ... "
                    "(default E, and offset with --offset)")
    ft.add_argument("--prior", action="append", default=[], metavar="NAME=MEAN:SD",
                    help="Gaussian prior in the input's SI units (tesla allowed for "
                    "magnetisations: remanence=1.0T:0.05T); repeatable")
    ft.add_argument("--bounds", action="append", default=[], metavar="NAME=LO:HI",
                    help="bounds of a free input; repeatable")
    ft.add_argument("--offset", action="store_true", help="fit an offset of the angle scale")
    ft.add_argument("--D", dest="D_ratio", type=_float("D", "D"), default=None,
                    help="track radius / L (sets --track-radius)")
    add_physical_inputs(ft)
    ft.add_argument("--profile", action="store_true",
                    help="profile likelihood of each free input (profile.png in --out)")
    ft.add_argument("--out", default=None, help="directory for fit.json (and profile.png)")
    ft.add_argument("--json", action="store_true")
    ft.set_defaults(G=None, M=None, D=None, magnet_radius=None)
    ft.set_defaults(func=cmd_fit)


def add_design(sub) -> None:
    de = sub.add_parser("design", help="inputs whose folds capture and release at target "
                        "angles (inverse design)")
    add_magnet_inputs(de, BATCH_N)
    add_design_scene_options(de)
    de.add_argument("--capture", type=_float("capture", "angle"),
                    help="target capture angle (the lower fold), deg")
    de.add_argument("--release", type=_float("release", "angle"),
                    help="target release angle (the upper fold), deg")
    de.add_argument("--vary", help="comma-separated inputs to solve for, "
                    "e.g. track-radius,magnet-diameter or D,M")
    de.add_argument("--bounds", action="append", default=[], metavar="NAME=LO:HI",
                    help="bounds of a varied input (default: a factor 3 either side)")
    de.set_defaults(func=cmd_design)
