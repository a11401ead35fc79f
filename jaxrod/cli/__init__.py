"""Command-line front end: ``jaxrod greenhill | equilibrium | folds | branch | sweep | fit |
design | certify | outofplane | track | cusp | foldcurve | map | modes | snap | reproduce``
(``jaxrod -h`` lists them); ``equilibrium``, ``folds``, ``branch``, ``foldcurve``, ``map``,
``fit``, ``design`` and ``modes`` also take a scene file (any rig).

Every command prints a human-readable report, or one JSON object with ``--json``. Invalid
input exits with status 2 and a one-line message naming the parameter. One module per
question (``uniform``, ``magnet``, ``three_d``, ``bistability``, ``inverse``, ``reproduce``,
``scene_file``),
each with its commands and their options; ``_inputs`` validates the options once and builds
the rod, magnet or design point from them; ``_output`` writes what the commands share. The
commands call only public functions of jaxrod (imported inside each command), and the
command line imports only the module of the command it runs (``COMMANDS``), so that its
start-up stays that of ``import jax``.
"""

from __future__ import annotations

import argparse
import os
import re
import sys

from jaxrod.cli._inputs import BATCH_N
from jaxrod.cli._output import _enable_compilation_cache
from jaxrod.params import ParameterError
from jaxrod.progress import ctrl_c_guard

#: Every command, in the order ``jaxrod -h`` lists them: name -> (module, the function that
#: adds its parser). A command line names one: only its module is imported.
COMMANDS = {
    "greenhill": ("uniform", "add_greenhill"),
    "equilibrium": ("scene_file", "add_equilibrium"),
    "folds": ("magnet", "add_folds"),
    "outofplane": ("three_d", "add_outofplane"),
    "track": ("three_d", "add_track"),
    "certify": ("magnet", "add_certify"),
    "branch": ("magnet", "add_branch"),
    "sweep": ("magnet", "add_sweep"),
    "fit": ("inverse", "add_fit"),
    "design": ("inverse", "add_design"),
    "cusp": ("bistability", "add_cusp"),
    "foldcurve": ("bistability", "add_foldcurve"),
    "map": ("bistability", "add_map"),
    "modes": ("dynamics", "add_modes"),
    "snap": ("snap", "add_snap"),
    "reproduce": ("reproduce", "add_reproduce"),
}

__all__ = ["BATCH_N", "COMMANDS", "build_parser", "main", "run"]


class _OneLineErrorParser(argparse.ArgumentParser):
    """Usage errors as one line on stderr, exit status 2; negative numbers in any notation
    (``--E -1e9``, ``--alpha -2.5e1``) are values, not options."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self._negative_number_matcher = re.compile(
            r"^-(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?$|^-inf(inity)?$", re.IGNORECASE)

    def error(self, message: str):
        self.exit(2, f"{self.prog}: error: {message}\n")


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The parser of every command, or of ``command`` alone (the start-up of one command
    then imports its own module only)."""
    import importlib

    parser = _OneLineErrorParser(
        prog="jaxrod", description="Stability, folds and hysteresis of slender ferromagnetic "
        "rods under gravity and magnetic fields. Each command prints a report, or one JSON "
        "object with --json; bad input exits with status 2, a failed solve with status 1.")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_OneLineErrorParser)
    for name, (module, add) in COMMANDS.items():
        if command is None or name == command:
            getattr(importlib.import_module(f"jaxrod.cli.{module}"), add)(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    # a known command first: its parser alone; anything else (-h, a typo) sees them all
    parser = build_parser(argv[0] if argv and argv[0] in COMMANDS else None)
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
