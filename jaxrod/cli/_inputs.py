"""The command line's inputs: option parsers that validate each value once (a number in its
valid range, a Chebyshev degree), and the rod, magnet, scene or design point built from them."""

from __future__ import annotations

import argparse
import dataclasses
import math
import textwrap

from jaxrod.params import (
    NDFEB_MAGNET,
    NICKEL,
    RANGES,
    Magnet,
    ParameterError,
    Rod,
    check,
    check_degree,
    preset,
)

#: The default Chebyshev degree of ``map`` and ``design`` (their batched and least-squares
#: programs: ``design_map.MAP_N``, ``calibration.MODEL_N``; the fold angles reach their
#: round-off floor from N = 12 at the paper's parameters); other commands default to 16.
BATCH_N = 12


MU0_TESLA = 4e-7 * math.pi


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


def _magnet_scene_from_args(args):
    """(scene, description dict with the groups and the inputs used)."""
    from jaxrod.magnet.diagram import make_scene

    G, M, D, radius, inputs = _magnet_groups_from_args(args)
    scene = make_scene(G, M, D, radius)
    return scene, {"G": G, "M": M, "D": D, "inputs": _with_n(inputs, args)}


def _design_point_from_args(args):
    """(DesignPoint, inputs used)."""
    from jaxrod.design_point import DesignPoint

    G, M, D, radius, inputs = _magnet_groups_from_args(args)
    physical = _magnet_physical_from_args(args)
    if physical is not None:
        return DesignPoint.from_physical(*physical[:2]), _with_n(inputs, args)
    return DesignPoint.from_groups(G, M, D, radius), _with_n(inputs, args)


def add_physical_inputs(p):
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


def add_magnet_inputs(p, default_n: int = 16):
    p.add_argument("--G", type=_float("G", "G-magnet"), help="gravity group, in (0, 1e3]")
    p.add_argument("--M", type=_float("M", "M"), help="magnet group, in [0, 1e3]")
    p.add_argument("--D", type=_float("D", "D"), help="track radius / rod length, in "
                   "(1, 1e3]")
    p.add_argument("--magnet-radius", type=_float("magnet radius"), default=None,
                   help="magnet radius / rod length (refuses D <= 1 + radius)")
    p.add_argument("--preset", choices=["permanent-magnet"],
                   help="the paper's nickel wire and NdFeB magnet")
    add_physical_inputs(p)
    p.add_argument("--n", type=_degree("N-magnet"), default=None,
                   help=f"Chebyshev degree, 4-64 (default {default_n})")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(n_fallback=default_n)


def _names(text: str, what: str) -> tuple[str, ...]:
    names = tuple(n.strip() for n in text.split(",") if n.strip())
    if not names:
        raise ParameterError(f"{what}: give a comma-separated list of names, got {text!r}")
    return names


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
