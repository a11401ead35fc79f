"""``jaxrod greenhill``: the uniform field (the magnetic Greenhill problem)."""

from __future__ import annotations

import json
import math
import sys

from jaxrod.cli._inputs import (
    _degree,
    _derived,
    _entry,
    _float,
    _inputs_line,
    _rod_from_args,
    _source,
)
from jaxrod.params import (
    EXPERIMENTS,
    ParameterError,
)


def cmd_greenhill(args) -> int:
    from jaxrod.uniform.greenhill import critical_length, greenhill

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


def add_greenhill(sub) -> None:
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
