"""Command-line front end: ``jaxrod greenhill`` and ``jaxrod reproduce``.

Every command prints a human-readable report, or one JSON object with ``--json``. Invalid
input exits with status 2 and a one-line message naming the parameter.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
from pathlib import Path

from jaxrod.params import EXPERIMENTS, NICKEL, ParameterError, Rod, preset


def _enable_compilation_cache() -> None:
    """Persist compiled programs between runs (set JAXROD_NO_CACHE=1 to disable)."""
    if os.environ.get("JAXROD_NO_CACHE"):
        return
    import jax

    cache = os.environ.get("JAXROD_CACHE_DIR",
                           os.path.join(os.path.expanduser("~"), ".cache", "jaxrod", "xla"))
    try:
        os.makedirs(cache, exist_ok=True)
        jax.config.update("jax_compilation_cache_dir", cache)
        jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.2)
    except OSError:
        pass


def _float(name: str):
    def parse(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{name} must be a number, got {text!r}") from None
        if math.isnan(value):
            raise argparse.ArgumentTypeError(f"{name} must be a number, got NaN")
        return value

    return parse


def _rod_from_args(args) -> tuple[Rod, str] | None:
    physical = (args.preset, args.E, args.diameter, args.length)
    if all(v is None for v in physical):
        return None
    if args.G is not None:
        raise ParameterError("G: give either --G or physical inputs (--preset/--E/--diameter/"
                             "--length), not both")
    E = args.E if args.E is not None else NICKEL.youngs_modulus
    if args.preset is not None:
        rod, support = preset(args.preset, E)
    else:
        if args.diameter is None or args.length is None:
            raise ParameterError("diameter/length: physical input needs both --diameter and "
                                 "--length (m), or a --preset")
        rod, support = Rod(NICKEL.with_youngs_modulus(E), args.diameter, args.length), None
    if args.diameter is not None:
        rod = Rod(rod.material, args.diameter, rod.length)
    if args.length is not None:
        rod = rod.with_length(args.length)
    return rod, support


def cmd_greenhill(args) -> int:
    from jaxrod.analysis.greenhill import critical_length, greenhill

    physical = _rod_from_args(args)
    extra = {}
    A = args.A
    support = args.support
    if physical is not None:
        rod, preset_support = physical
        if support is None:
            support = preset_support or "clamped"
        G = rod.G
        if A is None:
            A = rod.A(args.field == "on")
        extra = {
            "E_Pa": rod.material.youngs_modulus, "diameter_m": rod.diameter,
            "length_m": rod.length, "field": args.field,
            "L_crit_m": critical_length(rod, support, field_on=args.field == "on"),
            "L_stab_m": rod.stabilisation_length,
        }
    else:
        if args.G is None:
            raise ParameterError("G: give --G (gravity group, > 0) or physical inputs "
                                 "(--preset, or --diameter and --length)")
        G = args.G
        support = support or "clamped"
    result = greenhill(G, support, A, n=args.n)
    out = result.as_dict() | extra
    if args.json:
        print(json.dumps(out))
        return 0
    lines = [
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
        lines.append(f"L_crit       {extra['L_crit_m']:.6g} m   (field {args.field})")
        lines.append(f"L_stab       {extra['L_stab_m']:.6g} m   (K_d / (rho g))")
    print("\n".join(lines))
    return 0


def cmd_reproduce(args) -> int:
    from jaxrod.reproduce import format_uniform_field_report, uniform_field_report

    report = {"uniform_field": uniform_field_report()}
    text = format_uniform_field_report(report["uniform_field"])
    if args.out is not None:
        out = Path(args.out)
        out.mkdir(parents=True, exist_ok=True)
        (out / "report.md").write_text(text + "\n")
        (out / "report.json").write_text(json.dumps(report, indent=2) + "\n")
        from jaxrod.plotting import stability_diagram_figure

        fig = stability_diagram_figure(report["uniform_field"])
        fig.savefig(out / "stability_diagram.png", dpi=120)
        text += f"\n\nWrote {out / 'report.md'}, report.json and stability_diagram.png"
    print(json.dumps(report) if args.json else text)
    return 0


class _OneLineErrorParser(argparse.ArgumentParser):
    """Usage errors as one line on stderr, exit status 2."""

    def error(self, message: str):
        self.exit(2, f"{self.prog}: error: {message}\n")


def build_parser() -> argparse.ArgumentParser:
    parser = _OneLineErrorParser(prog="jaxrod", description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_OneLineErrorParser)

    g = sub.add_parser("greenhill", help="stability of the upright rod in a uniform field")
    g.add_argument("--G", type=_float("G"), help="gravity group (> 0)")
    g.add_argument("--A", type=_float("A"), help="anisotropy group; gives the verdict")
    g.add_argument("--support", choices=["clamped", "pinned"], default=None)
    g.add_argument("--preset", choices=sorted(k for k in EXPERIMENTS if k != "permanent-magnet"),
                   help="one of the paper's nickel wires")
    g.add_argument("--E", type=_float("E"), help="Young's modulus, Pa (default 200e9)")
    g.add_argument("--diameter", type=_float("diameter"), help="wire diameter, m")
    g.add_argument("--length", type=_float("length"), help="rod length, m")
    g.add_argument("--field", choices=["on", "off"], default="on",
                   help="uniform saturating field on (A from K_d) or off (A = 0)")
    g.add_argument("--n", type=int, default=None, help="Chebyshev degree (default: from G)")
    g.add_argument("--json", action="store_true", help="print one JSON object")
    g.set_defaults(func=cmd_greenhill)

    r = sub.add_parser("reproduce", help="recompute the paper's tables and verdicts")
    r.add_argument("--out", default=None, help="directory for report.md, report.json, PNGs")
    r.add_argument("--json", action="store_true", help="print the report as JSON")
    r.set_defaults(func=cmd_reproduce)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    _enable_compilation_cache()
    try:
        return args.func(args)
    except ParameterError as err:
        print(f"jaxrod {args.command}: error: {err}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
