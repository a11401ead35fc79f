"""Command-line front end: ``jaxrod greenhill | folds | branch | sweep | fit | certify |
outofplane | track | cusp | foldcurve | reproduce`` (``jaxrod -h`` lists them).

Every command prints a human-readable report, or one JSON object with ``--json``. Invalid
input exits with status 2 and a one-line message naming the parameter.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import os
import re
import sys
import textwrap
from pathlib import Path

from jaxrod.params import (
    EXPERIMENTS,
    GROUP_NAMES,
    NDFEB_MAGNET,
    NICKEL,
    PHYSICAL_NAMES,
    RANGES,
    UNITS,
    Magnet,
    ParameterError,
    Rod,
    check,
    check_degree,
    preset,
)
from jaxrod.progress import ctrl_c_guard

#: The default Chebyshev degree of ``map`` and ``design`` (their batched and least-squares
#: programs: ``design_map.MAP_N``, ``calibration.MODEL_N``; the fold angles reach their
#: round-off floor from N = 12 at the paper's parameters); other commands default to 16.
BATCH_N = 12


def _enable_compilation_cache() -> None:
    """The command line keeps its compiled programs between runs (``jr.enable_caches``);
    set JAXROD_NO_CACHE=1 to disable."""
    if os.environ.get("JAXROD_NO_CACHE"):
        return
    from jaxrod.stored import enable_caches

    enable_caches()


def _float(name: str, valid: str | None = None):
    """An option's parser: a finite number, within ``RANGES[valid]`` when given."""

    def parse(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{name} must be a number, got {text!r}") from None
        if not math.isfinite(value):
            raise argparse.ArgumentTypeError(f"{name} must be a finite number, got {text!r}")
        if valid is not None:
            try:
                RANGES[valid].check(value)
            except ParameterError as err:
                raise argparse.ArgumentTypeError(str(err)) from None
        return value

    parse.valid = valid  # the range an option's value is checked against (None: any number)
    return parse


def _degree(valid: str):
    """The --n parser: an integer Chebyshev degree within ``RANGES[valid]``."""

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(
                f"N (Chebyshev degree) must be an integer, got {text!r}") from None
        try:
            return check_degree(value, valid)
        except ParameterError as err:
            raise argparse.ArgumentTypeError(str(err)) from None

    parse.valid = valid
    return parse


def _derived(name: str, value: float, inputs: str) -> float:
    """A group computed from physical inputs, checked against its range."""
    try:
        return check(name, value)
    except ParameterError:
        r = RANGES[name]
        raise ParameterError(f"{r.label} = {value:.4g} from {inputs} is outside "
                             f"{r.interval()} ({r.why})") from None


def _entry(value, unit: str, source: str) -> dict:
    return {"value": value, "unit": unit, "source": source}


def _source(args, attr: str, fallback: str) -> str:
    return "given" if getattr(args, attr, None) is not None else fallback


def _rod_inputs(args, rod: Rod, fallback: str) -> dict:
    """The wire's inputs as used: value, unit and source (given, preset or default)."""
    m = rod.material
    material = "default: the paper's nickel"
    return {
        "E": _entry(m.youngs_modulus, "Pa", _source(args, "E", "default: 200 GPa")),
        "diameter": _entry(rod.diameter, "m", _source(args, "diameter", fallback)),
        "length": _entry(rod.length, "m", _source(args, "length", fallback)),
        "density": _entry(m.density, "kg/m^3", material),
        "gravity": _entry(rod.gravity, "m/s^2", "default: 9.81"),
        "rod-magnetisation": _entry(m.saturation_magnetisation, "A/m",
                                    _source(args, "rod_magnetisation", material)),
    }


def _inputs_line(inputs: dict) -> str:
    """One line of the inputs used, with units and, where not given, their source."""
    parts = []
    for name, e in inputs.items():
        value = e["value"] if isinstance(e["value"], str) else f"{e['value']:.6g}"
        unit = f" {e['unit']}" if e["unit"] else ""
        source = "" if e["source"] == "given" else f" ({e['source']})"
        parts.append(f"{name} = {value}{unit}{source}")
    return textwrap.fill("inputs: " + ", ".join(parts), width=100, subsequent_indent="  ",
                         break_long_words=False, break_on_hyphens=False)


def _rod_from_args(args) -> tuple[Rod, str, dict] | None:
    physical = (args.preset, args.E, args.diameter, args.length)
    if all(v is None for v in physical):
        return None
    if args.G is not None or args.A is not None:
        raise ParameterError(f"{'G' if args.G is not None else 'A'}: give either the groups "
                             "(--G, --A) or physical inputs (--preset/--E/--diameter/--length "
                             "with --field on/off), not both")
    E = args.E if args.E is not None else NICKEL.youngs_modulus
    if args.preset is not None:
        rod, support = preset(args.preset, E)
        fallback = f"preset {args.preset}"
    else:
        if args.diameter is None or args.length is None:
            raise ParameterError("diameter/length: physical input needs both --diameter and "
                                 "--length (m), or a --preset")
        rod, support = Rod(NICKEL.with_youngs_modulus(E), args.diameter, args.length), None
        fallback = "given"
    if args.diameter is not None:
        rod = Rod(rod.material, args.diameter, rod.length)
    if args.length is not None:
        rod = rod.with_length(args.length)
    return rod, support, _rod_inputs(args, rod, fallback)


def cmd_greenhill(args) -> int:
    from jaxrod.analysis.greenhill import critical_length, greenhill

    args.field_given = args.field is not None
    args.field = args.field or "on"
    physical = _rod_from_args(args)
    if physical is None and args.field_given:
        raise ParameterError("field: --field applies to physical inputs; with --G give --A "
                             "(A = 0 is the field off)")
    extra = {}
    A = args.A
    support = args.support
    if physical is not None:
        rod, preset_support, inputs = physical
        if support is None:
            support = preset_support or "clamped"
        field_on = args.field == "on"
        G = _derived("G", rod.G, "E, diameter and length")
        A = _derived("A", rod.A(field_on), "E, K_d, diameter and length")
        inputs["field"] = _entry(
            "on (saturating uniform field: A = 4 K_d L^2 / (E b^2))" if field_on else
            "off (A = 0)", "", "given" if args.field_given else "default")
        inputs["anisotropy"] = _entry(rod.material.anisotropy_constant, "J/m^3",
                                      "default: the paper's nickel")
        extra = {"L_crit_m": critical_length(rod, support, field_on=field_on),
                 "L_stab_m": rod.stabilisation_length}
    else:
        if args.G is None:
            raise ParameterError("G: give --G (gravity group, > 0) or physical inputs "
                                 "(--preset, or --diameter and --length)")
        G = args.G
        inputs = {"G": _entry(G, "", "given")}
        if A is not None:
            inputs["A"] = _entry(A, "", "given")
        support = support or "clamped"
    inputs["support"] = _entry(support, "", _source(args, "support", "default"
                                                    if physical is None or not args.preset
                                                    else f"preset {args.preset}"))
    result = greenhill(G, support, A, n=args.n)
    inputs["N"] = _entry(result.n, "", "given" if args.n is not None else "default: from G")
    out = result.as_dict() | extra | {"inputs": inputs}
    bad = [k for k in ("beta0", "A2", "G_crit") if not math.isfinite(getattr(result, k))]
    bad += [k for k, v in extra.items() if not math.isfinite(v)]
    if bad:
        message = (f"greenhill: {', '.join(bad)} not finite at N = {result.n}: the "
                   "eigenvalue solve failed (lower N, or G within its range)")
        if args.json:
            print(json.dumps(out | {"converged": False, "message": message}, default=str))
        print(f"jaxrod greenhill: {message}", file=sys.stderr)
        return 1
    if args.json:
        print(json.dumps(out | {"converged": True}))
        return 0
    lines = [
        _inputs_line(inputs),
        f"support      {result.support}",
        f"G            {result.G:.12g}",
        f"beta0        {result.beta0:.15g}",
        f"A_crit       {result.A_crit:.15g}   (straight rod stable iff A > A_crit)",
        f"A2           {result.A2:.12g}   ({result.criticality} pitchfork)",
        f"G_crit       {result.G_crit:.15g}   (clamped Greenhill load)",
    ]
    if result.A is not None:
        lines.append(f"A            {result.A:.12g}")
        lines.append(f"straight rod {'STABLE' if result.stable else 'UNSTABLE (buckles)'}"
                     f"   (A - A_crit = {result.A - result.A_crit:.6g})")
    if extra:
        field = ("on: A = 4 K_d L^2 / (E b^2)" if args.field == "on" else "off: A = 0")
        lines.append(f"L_crit       {extra['L_crit_m']:.6g} m   (field {field})")
        lines.append(f"L_stab       {extra['L_stab_m']:.6g} m   (K_d / (rho g))")
    print("\n".join(lines))
    return 0


_MAGNET_PHYSICAL = ("preset", "E", "length", "diameter", "magnet_diameter", "track_radius",
                    "remanence", "rod_magnetisation")


def _magnet_physical_from_args(args) -> tuple[Rod, Magnet, dict] | None:
    """(rod, magnet, inputs used) from --preset/--E/--diameter/--length/--magnet-diameter/
    --track-radius/--remanence/--rod-magnetisation, or None when only the groups are given.
    Inputs not given are the paper's permanent-magnet experiment's."""
    if all(getattr(args, k) is None for k in _MAGNET_PHYSICAL):
        return None
    if any(v is not None for v in (args.G, args.M, args.D, args.magnet_radius)):
        raise ParameterError("G/M/D: give either the groups --G --M --D (--magnet-radius) or "
                             "physical inputs (--preset/--E/--length/...), not both")
    E = args.E if args.E is not None else NICKEL.youngs_modulus
    rod, _ = preset("permanent-magnet", E)
    if args.rod_magnetisation is not None:
        rod = dataclasses.replace(rod, material=dataclasses.replace(
            rod.material, saturation_magnetisation=args.rod_magnetisation))
    if args.diameter is not None:
        rod = Rod(rod.material, args.diameter, rod.length)
    if args.length is not None:
        rod = rod.with_length(args.length)
    pick = lambda given, default: default if given is None else given
    magnet = Magnet(diameter=pick(args.magnet_diameter, NDFEB_MAGNET.diameter),
                    remanence=pick(args.remanence, NDFEB_MAGNET.remanence),
                    track_radius=pick(args.track_radius, NDFEB_MAGNET.track_radius))
    fallback = "preset permanent-magnet"
    inputs = _rod_inputs(args, rod, fallback) | {
        "remanence": _entry(magnet.remanence, "A/m", _source(args, "remanence", fallback)),
        "magnet-diameter": _entry(magnet.diameter, "m",
                                  _source(args, "magnet_diameter", fallback)),
        "track-radius": _entry(magnet.track_radius, "m",
                               _source(args, "track_radius", fallback)),
    }
    return rod, magnet, inputs


def _magnet_groups_from_args(args):
    """(G, M, D, magnet radius a/L or None, inputs used) from the groups or the physical
    inputs; the groups from physical inputs are checked against their ranges."""
    physical = _magnet_physical_from_args(args)
    if physical is not None:
        rod, magnet, inputs = physical
        G = _derived("G-magnet", rod.G, "E, diameter and length")
        M = _derived("M", rod.M(magnet), "the wire's and the magnet's inputs")
        D = rod.D(magnet)
        return G, M, D, 0.5 * magnet.diameter / rod.length, inputs
    missing = [k for k in ("G", "M", "D") if getattr(args, k) is None]
    if missing:
        raise ParameterError(f"{'/'.join(missing)}: give --G, --M and --D (or physical "
                             "inputs such as --preset permanent-magnet --E 200e9)")
    inputs = {k: _entry(getattr(args, k), "", "given") for k in ("G", "M", "D")}
    if args.magnet_radius is not None:
        inputs["magnet-radius"] = _entry(args.magnet_radius, "", "given")
    return args.G, args.M, args.D, args.magnet_radius, inputs


def _with_n(inputs: dict, args) -> dict:
    return inputs | {"N": _entry(args.n, "", "default" if args.n_default else "given")}


def _header(info: dict) -> str:
    """The first line(s) of a magnet-scene report: the inputs used and the groups."""
    inputs = info["inputs"]
    groups = (f"G = {info['G']:.8g}, M = {info['M']:.8g}, D = {info['D']:.10g}, "
              f"N = {inputs['N']['value']}")
    return (_inputs_line(inputs) + "\n" if "E" in inputs else "") + groups


def _magnet_scene_from_args(args):
    """(scene, description dict with the groups and the inputs used)."""
    from jaxrod.analysis.magnet import make_scene

    G, M, D, radius, inputs = _magnet_groups_from_args(args)
    scene = make_scene(G, M, D, radius)
    return scene, {"G": G, "M": M, "D": D, "inputs": _with_n(inputs, args)}


def _design_point_from_args(args):
    """(DesignPoint, inputs used)."""
    from jaxrod.analysis.fold_curves import DesignPoint

    G, M, D, radius, inputs = _magnet_groups_from_args(args)
    physical = _magnet_physical_from_args(args)
    if physical is not None:
        return DesignPoint.from_physical(*physical[:2]), _with_n(inputs, args)
    return DesignPoint.from_groups(G, M, D, radius), _with_n(inputs, args)


def _fmt_cusp(c) -> str:
    return (f"cusp: {c.vary} = {c.value:.12g}  alpha* = {c.alpha_deg:.10f} deg  "
            f"q* = {c.q:.10f}  tip* = {c.tip_deg:.10f} deg  d3F/dq3 = {c.cubic_coefficient:.8g}"
            f"  dF/dalpha = {c.dF_dalpha:.6g}")


def cmd_cusp(args) -> int:
    from jaxrod.analysis.fold_curves import find_cusp

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
        print(_fmt_cusp(cusp) if found else out["message"])
        if found:
            print(f"converged: {cusp.converged} (residual {cusp.residual_norm:.2g}, "
                  f"{cusp.iterations} Newton iterations)")
    return 0 if out["converged"] else 1


def cmd_foldcurve(args) -> int:
    from jaxrod.analysis.fold_curves import fold_curves

    point, inputs = _design_point_from_args(args)
    point.index(args.vary)
    out_dir = _output_dir(args.out) if args.out else None
    curves = fold_curves(point, args.vary, args.to, n=args.n)
    summary = curves.as_dict() | {"inputs": inputs}
    if out_dir is not None:
        _write_fold_curves(curves, out_dir)
    if args.json:
        print(json.dumps({k: v for k, v in summary.items() if k != "curves"}
                         | {"points": {c.start: len(c.value) for c in curves.curves}}))
    else:
        G, M, D = point.groups()
        print(_header({"G": G, "M": M, "D": D, "inputs": inputs})
              + f", {args.vary} -> {args.to:g}")
        for c in curves.curves:
            print(f"{c.start} fold: {len(c.value)} points, {args.vary} from {c.value[0]:.8g} "
                  f"to {c.value[-1]:.8g}, alpha* from {c.alpha_deg[0]:.6f} to "
                  f"{c.alpha_deg[-1]:.6f} deg ({c.status})")
        print(_fmt_cusp(curves.cusp) if curves.cusp is not None else
              f"no cusp between {args.vary} = {point.values[point.index(args.vary)]:.8g} and "
              f"{args.to:g}: bistable throughout")
        for e in curves.events:
            print(f"the {e.fold} fold reaches {e.kind} at {args.vary} = {e.value:.10g}")
        if out_dir is not None:
            print(f"wrote {out_dir / 'foldcurve.csv'}, foldcurve.json, foldcurve.png")
        print(f"converged: {curves.converged}")
    return 0 if curves.converged else 1


def cmd_map(args) -> int:
    if args.num_processes > 1:
        import jax

        if args.coordinator is None or args.process_id is None:
            raise ParameterError("num-processes: a run over several processes needs "
                                 "--coordinator HOST:PORT and --process-id")
        jax.distributed.initialize(coordinator_address=args.coordinator,
                                   num_processes=args.num_processes,
                                   process_id=args.process_id)
    import numpy as np

    from jaxrod.analysis.design_map import STORE, MapAxis, MapSpec, read_store, run_map

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
    spec = MapSpec(point, x, y, chunk=args.chunk, n=args.n)
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
        reasons = np.bincount(data["reason"].ravel().astype(int), minlength=5)
        summary["reason_counts"] = {name: int(c) for name, c in zip(
            ("bistable", "not_bistable", "fold_beyond_90", "invalid_input", "not_converged"),
            reasons, strict=True)}
        if not args.no_plot:
            from jaxrod.analysis.design_map import cusp_curve, fold_crossings
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
        if "reason_counts" in summary:
            print(", ".join(f"{k}: {v}" for k, v in summary["reason_counts"].items()))
    return 0


def _output_dir(path: str) -> Path:
    """Create the output directory before any work starts (ParameterError if it cannot be)."""
    out = Path(path)
    try:
        out.mkdir(parents=True, exist_ok=True)
        probe = out / ".jaxrod-write-test"
        probe.write_text("")
        probe.unlink()
    except OSError as err:
        raise ParameterError(f"out: cannot write to {path!r} ({err.strerror})") from None
    return out


def _write_fold_curves(curves, out_dir: Path) -> None:
    from jaxrod.plotting import fold_curve_figure

    with open(out_dir / "foldcurve.csv", "w") as fh:
        columns = list(curves.curves[0].columns())
        fh.write("curve," + ",".join(curves.vary if k == "value" else k for k in columns) + "\n")
        for c in curves.curves:
            cols = c.columns()
            for i in range(len(c.value)):
                fh.write(c.start + "," + ",".join(f"{cols[k][i]:.12g}" for k in columns) + "\n")
    (out_dir / "foldcurve.json").write_text(json.dumps(curves.as_dict(), indent=1))
    fold_curve_figure(curves).savefig(out_dir / "foldcurve.png", dpi=120)


def cmd_folds(args) -> int:
    scene, info = _magnet_scene_from_args(args)
    if args.method == "reduced":
        return _folds_reduced(scene, info, args)
    from jaxrod.analysis.magnet import locate_folds

    report = locate_folds(scene, n=args.n)
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


def _not_converged(command: str, why: str) -> None:
    print(f"jaxrod {command}: not converged: {why}", file=sys.stderr)


NO_FOLD_NOTE = ("no fold on the branch through the straight rod for alpha in (0, 90] degrees: "
                "no hysteresis along the experiment's sweep")


def _folds_reduced(scene, info, args) -> int:
    from jaxrod.analysis.reduction import check_reducible, reduced_folds

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


def cmd_outofplane(args) -> int:
    import numpy as np

    from jaxrod.analysis.magnet import _equilibrium, trace_diagram
    from jaxrod.analysis.outofplane import out_of_plane_at_rows
    from jaxrod.discretise.planar import planar_discretisation

    scene, info = _magnet_scene_from_args(args)
    branch = trace_diagram(scene, args.n)
    disc = planar_discretisation(args.n, "clamped")
    if args.alpha is None:
        theta, alpha, stable = branch.theta, branch.alpha, branch.stable
    else:
        a = np.radians(args.alpha)
        crossing = np.nonzero((branch.alpha[:-1] - a) * (branch.alpha[1:] - a) <= 0.0)[0]
        theta, alpha, stable = [], [], []
        for i in crossing:
            res = _equilibrium(branch.theta[i], a, scene, disc)
            if bool(res.converged):
                theta.append(np.asarray(res.x))
                alpha.append(a)
                stable.append(bool(branch.stable[i] and branch.stable[i + 1]))
        theta, alpha, stable = np.array(theta), np.array(alpha), np.array(stable)
    rows = []
    if len(alpha):
        r = out_of_plane_at_rows(theta, alpha, scene, disc)
        for i in range(len(alpha)):
            rows.append({"alpha_deg": float(np.degrees(alpha[i])), "planar_stable": bool(stable[i]),
                         "min_eig_perp": float(r["min_eig_perp"][i]),
                         "min_eig_perp_formula": float(r["min_eig_perp_formula"][i]),
                         "min_eig_plane": float(r["min_eig_plane"][i]),
                         "coupling": float(r["coupling"][i]),
                         "theta_in_0_pi": bool(r["theta_in_0_pi"][i]), "g1": float(r["g1"][i])})
    out = info | {"n": args.n, "points": rows,
                  "min_eig_perp_on_stable": min((x["min_eig_perp"] for x in rows
                                                 if x["planar_stable"]), default=None)}
    if args.json:
        print(json.dumps(out))
        return 0
    print(_header(info) + f": "
          f"{len(rows)} planar equilibria")
    print(f"{'alpha deg':>11} {'planar':>8} {'min eig perp':>13} {'(formula)':>11} "
          f"{'min eig plane':>14} {'coupling':>9}")
    for x in rows:
        print(f"{x['alpha_deg']:11.5f} {'stable' if x['planar_stable'] else 'unstable':>8} "
              f"{x['min_eig_perp']:13.6g} {x['min_eig_perp_formula']:11.6g} "
              f"{x['min_eig_plane']:14.6g} {x['coupling']:9.1e}")
    if out["min_eig_perp_on_stable"] is not None:
        print(f"smallest out-of-plane eigenvalue on planar-stable points: "
              f"{out['min_eig_perp_on_stable']:.6g} (> 0: out-of-plane stable)")
    return 0


def cmd_certify(args) -> int:
    from jaxrod.analysis.contraction import certify

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
    from jaxrod.analysis.magnet import figure_options, locate_folds, trace_diagram
    from jaxrod.plotting import diagram_figure

    scene, info = _magnet_scene_from_args(args)
    out_dir = _output_dir(args.out)
    branch = trace_diagram(scene, args.n, figure_options())  # dense, for a smooth figure
    if not branch.complete:  # a long branch filled the capacity: the default steps
        branch = trace_diagram(scene, args.n)
    report = locate_folds(scene, n=args.n, branch=branch)
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
    from jaxrod.analysis.magnet import hysteresis_sweep, locate_folds
    from jaxrod.plotting import hysteresis_figure
    from jaxrod.progress import Interrupted, progress_bar

    scene, info = _magnet_scene_from_args(args)
    out_dir = _output_dir(args.out)
    for name, default in (("alpha_max", 50.0), ("step", 0.25)):
        info["inputs"][name.replace("_", "-")] = _entry(
            default if getattr(args, name) is None else getattr(args, name), "deg",
            _source(args, name, "default"))
        if getattr(args, name) is None:
            setattr(args, name, default)
    total = None
    bar = None

    def progress(done, of):
        nonlocal bar, total
        if bar is None:
            bar, total = progress_bar(of, "sweep", "position", not args.quiet), 0
        bar.update(done - total)
        total = done

    try:
        sweep = hysteresis_sweep(scene, n=args.n, alpha_max_deg=args.alpha_max,
                                 step_deg=args.step, progress=progress)
    except Interrupted as stop:
        if bar is not None:
            bar.close()
        sweep = stop.partial
        summary = info | {"snaps": sweep["snaps"], "converged": sweep["converged"],
                          "complete": False, "reason": sweep["reason"],
                          "positions": int(sweep["alpha_deg"].size)}
        _write_sweep(out_dir, sweep, summary)
        print(f"jaxrod sweep: {sweep['reason']}; wrote what was computed to "
              f"{out_dir / 'sweep.csv'} and sweep.json (marked incomplete)", file=sys.stderr)
        return 130
    if bar is not None:
        bar.close()
    report = locate_folds(scene, n=args.n)
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


def _names(text: str, what: str) -> tuple[str, ...]:
    names = tuple(n.strip() for n in text.split(",") if n.strip())
    if not names:
        raise ParameterError(f"{what}: give a comma-separated list of names, got {text!r}")
    return names


MU0_TESLA = 4e-7 * math.pi


def _quantity(name: str, text: str, what: str) -> float:
    """A number in the parameter's SI units; magnetisations may be given in tesla (1.2T)."""
    scale = 1.0
    if text.strip().upper().endswith("T") and name in ("remanence", "rod-magnetisation"):
        text, scale = text.strip()[:-1], 1.0 / MU0_TESLA
    try:
        value = float(text)
    except ValueError:
        raise ParameterError(f"{what} {name}: {text!r} is not a number") from None
    if not math.isfinite(value):
        raise ParameterError(f"{what} {name}: must be finite, got {text!r}")
    return value * scale


def _pairs(items, what: str, allowed) -> dict:
    """NAME=A:B options (priors, bounds) as name -> (a, b)."""
    out = {}
    for item in items:
        name, sep, rest = item.partition("=")
        name = name.strip()
        a, sep2, b = rest.partition(":")
        if not sep or not sep2:
            raise ParameterError(f"{what}: write NAME={'MEAN:SD' if what == 'prior' else 'LO:HI'}"
                                 f", got {item!r}")
        if name not in allowed:
            raise ParameterError(f"{what}: unknown parameter {name!r}; choose from "
                                 f"{', '.join(allowed)}")
        if name in out:
            raise ParameterError(f"{what}: {name} given twice")
        out[name] = (_quantity(name, a, what), _quantity(name, b, what))
    return out


def _measured_from_args(args) -> list:
    from jaxrod.analysis.fit import ANGLE_NAMES

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
    from jaxrod.analysis.fold_curves import DesignPoint

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
    from jaxrod.analysis.fit import ANGLE_NAMES, FREE_NAMES, OFFSET, Prior, fit, profile

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
    out = cal.as_dict() | {"inputs": inputs} | _legacy_fit_keys(cal)
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
        _print_calibration(cal, ANGLE_NAMES)
        if out_dir is not None:
            print(f"wrote {out_dir / 'fit.json'}" + (", profile.png" if profiles else ""))
    if not cal.converged:
        _not_converged("fit", cal.reason)
    return 0 if cal.converged else 1


def _legacy_fit_keys(cal) -> dict:
    """The keys of the one-parameter fit's JSON (E_Pa, offset_deg, ...), for scripts."""
    est, std = cal.estimates, cal.std
    return {"E_Pa": est.get("E"), "E_std_Pa": std.get("E"),
            "offset_deg": est.get("offset", 0.0), "offset_std_deg": std.get("offset", 0.0),
            "warning": "; ".join(cal.warnings) or None}


def _print_calibration(cal, angle_names) -> None:
    if not cal.converged:
        print(f"NOT CONVERGED after {cal.iterations} iterations: {cal.reason}")
        print("last iterate (not an estimate): " + ", ".join(
            f"{n} = {v:.6g} {cal.units[n]}" for n, v in cal.estimates.items()))
        for w in cal.warnings:
            if "signs" in w:
                print(f"hint: {w}")
        return
    priors = ", ".join(f"{n} = {p.mean:.6g} +- {p.sd:.3g} {cal.units.get(n, '')}"
                       for n, p in cal.priors.items())
    print(f"free: {', '.join(cal.free)}" + (f"; priors: {priors}" if priors else "")
          + f"; sigma = {cal.sigma_deg:g} deg per angle")
    for n, v in cal.estimates.items():
        scale, unit = (1e9, "GPa") if n == "E" else (1.0, cal.units[n])
        sd = cal.std[n]
        spread = (f"+- {sd / scale:.6g}" if sd is not None else
                  "(no standard deviation: not fixed by the angles and priors)")
        print(f"  {n:16s} = {v / scale:.6g} {spread} {unit}")
    if len(cal.free) > 1:
        print("correlations: " + ", ".join(
            f"{a}/{b} {cal.correlation[i, j]:+.3f}" for i, a in enumerate(cal.free)
            for j, b in enumerate(cal.free) if j > i and math.isfinite(cal.correlation[i, j])))
    print("residuals (model - measured):")
    for name, r in zip(angle_names, cal.residuals_deg):
        if r is not None:
            print(f"  {name:12s} {r:+.4f} deg")
    red = "undefined (no degree of freedom)" if cal.reduced_chi2 is None else \
        f"{cal.reduced_chi2:.4g}"
    print(f"chi^2 = {cal.chi2:.4g} (angles and priors), {cal.dof} degrees of freedom, "
          f"reduced chi^2 = {red} (~1 when sigma is right)")
    for e in cal.identifiability:
        print(("the angles fix " if e["fixed_by_angles"] else "the angles CANNOT fix ")
              + e["combination_text"]
              + (f" (std {e['std']:.3g})" if e["std"] is not None else ""))
    for w in cal.warnings:
        print(f"warning: {w}")
    print(f"converged: True after {cal.iterations} iterations")


PAPER_GROUPS = {"G": 2.2, "M": 0.0236, "D": 11.25 / 9.2}


def cmd_design(args) -> int:
    from jaxrod.analysis.design import design

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
            check = (f"locate_folds: {d.verified_capture_deg:.10f} / "
                     f"{d.verified_release_deg:.10f} deg" if d.verified_capture_deg is not None
                     else d.check)
            print(f"design {i + 1}: {values}  (model folds {d.capture_deg:.10f} / "
                  f"{d.release_deg:.10f} deg; {check}; verified: {d.verified})")
    ok = bool(result.designs) and result.designs[0].verified
    if not ok:
        _not_converged("design", "the fresh locate_folds at the design disagrees with the "
                       "model's folds")
    return 0 if ok else 1


def cmd_track(args) -> int:
    from jaxrod.analysis.magnet_track import trace_track

    scene, info = _magnet_scene_from_args(args)
    path = _output_dir(args.out) if args.out is not None else None
    track = trace_track(scene, args.alpha0, args.tilt, n=args.n, t_max_deg=args.t_max)
    folds = [{"t_deg": f.t_deg, "magnet_polar_deg": f.magnet_polar_deg,
              "magnet_azimuth_deg": f.magnet_azimuth_deg, "rod_azimuth_deg": f.rod_azimuth_deg,
              "hessian_smallest": list(f.hessian_smallest), "converged": f.converged,
              "residual_norm": f.residual_norm} for f in track.folds]
    out = info | {"n": args.n, "alpha0_deg": args.alpha0, "tilt_deg": args.tilt,
                  "t_max_deg": args.t_max, "status": track.status, "points": len(track.t_deg),
                  "max_out_of_plane": float(track.out_of_plane.max()), "folds": folds,
                  "converged": all(f["converged"] for f in folds)}
    if path is not None:
        with open(path / "track.csv", "w") as fh:
            fh.write("t_deg,magnet_polar_deg,magnet_azimuth_deg,tip_x,tip_y,tip_z,stable\n")
            for i in range(len(track.t_deg)):
                fh.write(f"{track.t_deg[i]:.12g},{track.magnet_polar_deg[i]:.12g},"
                         f"{track.magnet_azimuth_deg[i]:.12g},"
                         + ",".join(f"{c:.12g}" for c in track.tip[i])
                         + f",{int(track.stable[i])}\n")
        (path / "track.json").write_text(json.dumps(out, indent=2) + "\n")
    if args.json:
        print(json.dumps(out))
        return 0 if out["converged"] else 1
    print(_header(info) + f": "
          f"magnet from {args.alpha0} deg in the plane along a great circle tilted "
          f"{args.tilt} deg; {len(track.t_deg)} points ({track.status}); largest out-of-plane "
          f"chart value {out['max_out_of_plane']:.4f} rad")
    for f in folds:
        print(f"fold at t = {f['t_deg']:.10f} deg: magnet polar {f['magnet_polar_deg']:.10f} "
              f"deg, azimuth {f['magnet_azimuth_deg']:.6f} deg; rod azimuth "
              f"{f['rod_azimuth_deg']:.6f} deg{'' if f['converged'] else ' (NOT converged)'}")
    if not folds:
        print("no fold along the track")
    if not out["converged"]:
        _not_converged("track", "a fold refinement did not converge (see the fold lines)")
    return 0 if out["converged"] else 1


def cmd_reproduce(args) -> int:
    from jaxrod.progress import progress_bar
    from jaxrod.reproduce import (
        format_permanent_magnet_report,
        format_uniform_field_report,
        format_youngs_modulus_report,
        permanent_magnet_report,
        uniform_field_report,
        youngs_modulus_report,
    )

    out = _output_dir(args.out) if args.out is not None else None
    sections = (("permanent_magnet", permanent_magnet_report),
                ("uniform_field", uniform_field_report),
                ("youngs_modulus_fit", youngs_modulus_report))
    report = {}
    bar = progress_bar(len(sections), "reproduce", "section", not args.quiet)
    try:
        for name, make in sections:
            report[name] = make()
            bar.update(1)
    except KeyboardInterrupt:
        bar.close()
        report.get("permanent_magnet", {}).pop("_sweep_arrays", None)
        if out is not None:
            partial = report | {"complete": False, "reason": "interrupted (Ctrl-C) after "
                                f"{len(report)} of {len(sections)} sections"}
            (out / "report.json").write_text(json.dumps(partial, indent=2) + "\n")
        print(f"jaxrod reproduce: interrupted after {len(report)} of {len(sections)} sections"
              + (f"; wrote them to {out / 'report.json'} (marked incomplete)" if out else ""),
              file=sys.stderr)
        return 130
    bar.close()
    magnet = report["permanent_magnet"]
    sweep = magnet.pop("_sweep_arrays")
    report = {k: report[k] for k in ("uniform_field", "permanent_magnet", "youngs_modulus_fit")}
    text = (format_uniform_field_report(report["uniform_field"]) + "\n\n"
            + format_permanent_magnet_report(magnet) + "\n\n"
            + format_youngs_modulus_report(report["youngs_modulus_fit"]))
    if out is not None:
        (out / "report.md").write_text(text + "\n")
        (out / "report.json").write_text(json.dumps(report, indent=2) + "\n")
        from jaxrod.plotting import hysteresis_figure, stability_diagram_figure

        stability_diagram_figure(report["uniform_field"]).savefig(
            out / "stability_diagram.png", dpi=120)
        hysteresis_figure(sweep).savefig(out / "hysteresis_E200.png", dpi=120)
        text += (f"\n\nWrote {out / 'report.md'}, report.json, stability_diagram.png and "
                 "hysteresis_E200.png")
    print(json.dumps(report) if args.json else text)
    return 0


class _OneLineErrorParser(argparse.ArgumentParser):
    """Usage errors as one line on stderr, exit status 2; negative numbers in any notation
    (``--E -1e9``, ``--alpha -2.5e1``) are values, not options."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self._negative_number_matcher = re.compile(
            r"^-(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?$|^-inf(inity)?$", re.IGNORECASE)

    def error(self, message: str):
        self.exit(2, f"{self.prog}: error: {message}\n")


def build_parser() -> argparse.ArgumentParser:
    parser = _OneLineErrorParser(
        prog="jaxrod", description="Stability, folds and hysteresis of slender ferromagnetic "
        "rods under gravity and magnetic fields. Each command prints a report, or one JSON "
        "object with --json; bad input exits with status 2, a failed solve with status 1.")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_OneLineErrorParser)

    g = sub.add_parser("greenhill", help="stability of the upright rod in a uniform field")
    g.add_argument("--G", type=_float("G", "G"), help="gravity group, in (0, 1e7]")
    g.add_argument("--A", type=_float("A", "A"), help="anisotropy group; gives the verdict")
    g.add_argument("--support", choices=["clamped", "pinned"], default=None)
    g.add_argument("--preset", choices=sorted(k for k in EXPERIMENTS if k != "permanent-magnet"),
                   help="one of the paper's nickel wires")
    g.add_argument("--E", type=_float("E", "E"), help="Young's modulus, Pa (default 200e9)")
    g.add_argument("--diameter", type=_float("diameter", "diameter"), help="wire diameter, m")
    g.add_argument("--length", type=_float("length", "length"), help="rod length, m")
    g.add_argument("--field", choices=["on", "off"], default=None,
                   help="uniform saturating field on (A from K_d) or off (A = 0)")
    g.add_argument("--n", type=_degree("N"), default=None,
                   help="Chebyshev degree, 4-256 (default: from G)")
    g.add_argument("--json", action="store_true", help="print one JSON object")
    g.set_defaults(func=cmd_greenhill)

    def physical_inputs(p):
        """The wire's and the magnet's physical inputs (defaults: the paper's)."""
        p.add_argument("--E", type=_float("E", "E"), help="Young's modulus, Pa (default 200e9)")
        p.add_argument("--diameter", type=_float("diameter", "diameter"),
                       help="wire diameter, m")
        p.add_argument("--length", type=_float("length", "length"), help="rod length, m")
        p.add_argument("--rod-magnetisation", type=_float("rod-magnetisation",
                                                          "rod-magnetisation"),
                       help="the wire's saturation magnetisation, A/m (default nickel's 4.8e5)")
        p.add_argument("--magnet-diameter", type=_float("magnet-diameter", "magnet-diameter"),
                       help="m (default 15e-3)")
        p.add_argument("--remanence", type=_float("remanence", "remanence"),
                       help="the magnet's remanent magnetisation, A/m (default 8e5)")
        p.add_argument("--track-radius", type=_float("track-radius", "track-radius"),
                       help="m (default 0.1125)")

    def magnet_inputs(p, default_n: int = 16):
        p.add_argument("--G", type=_float("G", "G-magnet"), help="gravity group, in (0, 1e3]")
        p.add_argument("--M", type=_float("M", "M"), help="magnet group, in [0, 1e3]")
        p.add_argument("--D", type=_float("D", "D"), help="track radius / rod length, in "
                       "(1, 1e3]")
        p.add_argument("--magnet-radius", type=_float("magnet radius"), default=None,
                       help="magnet radius / rod length (refuses D <= 1 + radius)")
        p.add_argument("--preset", choices=["permanent-magnet"],
                       help="the paper's nickel wire and NdFeB magnet")
        physical_inputs(p)
        p.add_argument("--n", type=_degree("N-magnet"), default=None,
                       help=f"Chebyshev degree, 4-64 (default {default_n})")
        p.add_argument("--json", action="store_true", help="print one JSON object")
        p.set_defaults(n_fallback=default_n)

    f = sub.add_parser("folds", help="fold (switching) angles of the permanent-magnet scene")
    magnet_inputs(f)
    f.add_argument("--method", choices=["moore-spence", "reduced"], default="moore-spence")
    f.set_defaults(func=cmd_folds)

    o = sub.add_parser("outofplane", help="out-of-plane stability of planar equilibria (3D)")
    magnet_inputs(o)
    o.add_argument("--alpha", type=_float("alpha", "alpha"), default=None,
                   help="magnet angle (deg): the equilibria at this angle; default: the branch")
    o.add_argument("--branch", action="store_true", help="the whole diagram (the default)")
    o.set_defaults(func=cmd_outofplane)

    t = sub.add_parser("track", help="3D equilibria and folds along a magnet track that leaves "
                       "the plane")
    magnet_inputs(t)
    t.add_argument("--alpha0", type=_float("alpha0", "alpha0"), default=20.0,
                   help="start of the track in the plane, polar angle (deg, in (0, 90))")
    t.add_argument("--tilt", type=_float("tilt", "tilt"), default=90.0,
                   help="angle of the great circle to the meridian (deg; 0: planar track)")
    t.add_argument("--t-max", type=_float("t-max", "t-max"), default=60.0,
                   help="length of the track (deg of arc, in (0, 180])")
    t.add_argument("--out", default=None, help="directory for track.csv and track.json")
    t.set_defaults(func=cmd_track)

    c = sub.add_parser("certify", help="hypotheses of the paper's reduction, with margins")
    magnet_inputs(c)
    c.set_defaults(func=cmd_certify)

    b = sub.add_parser("branch", help="whole bifurcation diagram (CSV, PNG, JSON)")
    magnet_inputs(b)
    b.add_argument("--out", required=True, help="output directory")
    b.set_defaults(func=cmd_branch)

    w = sub.add_parser("sweep", help="quasi-static hysteresis sweep (CSV, PNG, JSON)")
    magnet_inputs(w)
    w.add_argument("--out", required=True, help="output directory")
    w.add_argument("--alpha-max", type=_float("alpha-max", "alpha-max"), default=None,
                   help="sweep from -alpha_max to +alpha_max and back (deg, in (0, 90]; "
                   "default 50)")
    w.add_argument("--step", type=_float("step", "step"), default=None,
                   help="magnet step (deg, in (0, 5]; default 0.25)")
    w.add_argument("--quiet", action="store_true", help="no progress bar")
    w.set_defaults(func=cmd_sweep)

    ft = sub.add_parser("fit", help="calibrate E and other inputs on measured switching angles",
                        description="Angles in degrees, sign of the magnet angle (positive "
                        "towards e1), in the order of the protocol: capture and release of the "
                        "clockwise sweep (alpha increasing), then capture and release of the "
                        "counter-clockwise sweep. The wire and magnet are the paper's unless "
                        "given (--E, --length, --track-radius, ...).")
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
    physical_inputs(ft)
    ft.add_argument("--profile", action="store_true",
                    help="profile likelihood of each free input (profile.png in --out)")
    ft.add_argument("--out", default=None, help="directory for fit.json (and profile.png)")
    ft.add_argument("--json", action="store_true")
    ft.set_defaults(G=None, M=None, D=None, magnet_radius=None)
    ft.set_defaults(func=cmd_fit)

    de = sub.add_parser("design", help="inputs whose folds capture and release at target "
                        "angles (inverse design)")
    magnet_inputs(de, BATCH_N)
    de.add_argument("--capture", type=_float("capture", "angle"), required=True,
                    help="target capture angle (the lower fold), deg")
    de.add_argument("--release", type=_float("release", "angle"), required=True,
                    help="target release angle (the upper fold), deg")
    de.add_argument("--vary", required=True, help="comma-separated inputs to solve for, "
                    "e.g. track-radius,magnet-diameter or D,M")
    de.add_argument("--bounds", action="append", default=[], metavar="NAME=LO:HI",
                    help="bounds of a varied input (default: a factor 3 either side)")
    de.set_defaults(func=cmd_design)

    cu = sub.add_parser("cusp", help="the cusp where the hysteresis ends, varying one input")
    magnet_inputs(cu)
    cu.add_argument("--vary", required=True, choices=GROUP_NAMES + PHYSICAL_NAMES,
                    help="the input that varies (a group, or a physical input with --preset)")
    cu.set_defaults(func=cmd_cusp)

    fc = sub.add_parser("foldcurve", help="both fold curves in a second input, and the cusp")
    magnet_inputs(fc)
    fc.add_argument("--vary", required=True, choices=GROUP_NAMES + PHYSICAL_NAMES,
                    help="the input that varies (a group, or a physical input with --preset)")
    fc.add_argument("--to", type=_float("to"), required=True,
                    help="the value of the varied input where the curves end")
    fc.add_argument("--out", default=None, help="directory for foldcurve.csv/.json/.png")
    fc.set_defaults(func=cmd_foldcurve)

    mp = sub.add_parser("map", help="capture/release angles and hysteresis width on a grid "
                        "of two inputs (chunked Zarr store, resumable)")
    magnet_inputs(mp, BATCH_N)
    mp.add_argument("--x", required=True, help="name:start:stop:count of the first input")
    mp.add_argument("--y", required=True, help="name:start:stop:count of the second input")
    mp.add_argument("--out", required=True, help="directory for the Zarr store map.zarr and, "
                    "beside it, map.png and map.json")
    mp.add_argument("--chunk", type=int, default=50, help="chunk edge in grid points")
    mp.add_argument("--quiet", action="store_true", help="no progress bar")
    mp.add_argument("--no-plot", action="store_true", help="skip map.png and the cusp curve")
    mp.add_argument("--coordinator", default=None, help="HOST:PORT of process 0 "
                    "(jax.distributed), for a map over several processes or hosts")
    mp.add_argument("--num-processes", type=int, default=1)
    mp.add_argument("--process-id", type=int, default=None)
    mp.set_defaults(func=cmd_map)

    r = sub.add_parser("reproduce", help="recompute the paper's tables and verdicts")
    r.add_argument("--out", default=None, help="directory for report.md, report.json, PNGs")
    r.add_argument("--json", action="store_true", help="print the report as JSON")
    r.add_argument("--quiet", action="store_true", help="no progress bar")
    r.set_defaults(func=cmd_reproduce)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if getattr(args, "n_fallback", None) is not None:
        args.n_default = args.n is None
        args.n = args.n_fallback if args.n is None else args.n
    _enable_compilation_cache()
    try:
        with ctrl_c_guard():
            return args.func(args)
    except ParameterError as err:
        print(f"jaxrod {args.command}: error: {err}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"jaxrod {args.command}: interrupted (Ctrl-C)", file=sys.stderr)
        return 130


def run() -> None:
    """The ``jaxrod`` command. After Ctrl-C the process ends at once (os._exit): compiler
    threads interrupted midway must not run the interpreter's teardown."""
    code = main()
    if code == 130:
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(130)
    sys.exit(code)


if __name__ == "__main__":
    run()
