"""Bad input never hangs, exhausts memory or prints a number: a table of the inputs users
tried, a generated set over every CLI command's numeric options, and the Python API.

Each case runs in this process with a wall-clock limit (SIGALRM) and a bound on the growth
of the peak resident memory; a refused input must exit 2 with one line on stderr naming
the parameter.
"""

from __future__ import annotations

import contextlib
import math
import re
import resource
import signal
import subprocess
import sys
import time

import jax
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from jaxrod.cli import build_parser, main
from jaxrod.inverse.youngs import FitSetup, fit_youngs_modulus
from jaxrod.magnet import diagram as magnet
from jaxrod.magnet import folds as magnet_folds
from jaxrod.magnet import sweep as magnet_sweep
from jaxrod.magnet.batch import fold_pairs
from jaxrod.params import NICKEL, RANGES, Magnet, ParameterError, Rod, preset
from jaxrod.uniform.greenhill import greenhill

SECONDS = 10  # per case
MEMORY_GROWTH_MB = 300  # of the peak resident memory, per case

PAPER = ["--G", "2.2", "--M", "0.0236", "--D", "1.2228"]
ANGLES = ["--angles", "-28", "25", "27.5", "-38.5"]


class _Hang(Exception):
    pass


@contextlib.contextmanager
def _limits():
    """Fail a case that runs over SECONDS or grows the peak memory by MEMORY_GROWTH_MB."""

    def alarm(*_):
        raise _Hang(f"ran over {SECONDS} s")

    previous = signal.signal(signal.SIGALRM, alarm)
    before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    signal.alarm(SECONDS)
    start = time.monotonic()
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, previous)
    grown_mb = (resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - before) / 1024.0
    assert grown_mb < MEMORY_GROWTH_MB, f"peak memory grew by {grown_mb:.0f} MB"
    assert time.monotonic() - start < SECONDS


def refused(argv, capsys) -> str:
    """Run the CLI on argv within the limits; it must exit 2 with one line; return it."""
    with _limits():
        try:
            code = main(argv)
        except SystemExit as stop:  # argparse's refusals
            code = stop.code
    captured = capsys.readouterr()
    lines = captured.err.strip().splitlines()
    assert code == 2, (argv, code, captured.out[-300:], captured.err[-300:])
    assert len(lines) == 1, captured.err
    assert captured.out == "", captured.out  # no result printed
    return lines[0]


# --- the inputs users tried (each was accepted, hung or printed a traceback before) ---------

TABLE = [
    (["greenhill", "--preset", "clamped-12cm", "--E", "1e3"], "G (gravity group)"),
    (["greenhill", "--diameter", "5e-5", "--length", "1e5"], "length"),
    (["greenhill", "--diameter", "5e-5", "--length", "50"], "G (gravity group)"),
    (["folds", *PAPER, "--n", "200"], "N (Chebyshev degree)"),
    (["folds", *PAPER, "--n", "2000"], "N (Chebyshev degree)"),
    (["greenhill", "--G", "10", "--n", "2000"], "N (Chebyshev degree)"),
    (["greenhill", "--G", "1e9"], "G (gravity group)"),
    (["fit", "--preset", "permanent-magnet", "--angles", "-28", "inf", "27.5", "-38.5"],
     "angles"),
    (["fit", *ANGLES, "--D", "1.0"], "D (track radius"),
    (["fit", "--angles", "-28", "25", "27.5", "95"], "angles"),
    (["fit", *ANGLES, "--sigma-deg", "0"], "sigma-deg"),
    (["fit", *ANGLES, "--sigma-deg", "-1"], "sigma-deg"),
    (["folds", "--magnet-diameter", "0"], "magnet-diameter"),
    (["folds", "--track-radius", "0"], "track-radius"),
    (["folds", "--preset", "permanent-magnet", "--length", "0.11"], "tip cannot touch"),
    (["folds", "--preset", "permanent-magnet", "--E", "1e4"], "G (gravity group)"),
    (["sweep", *PAPER, "--out", "unused", "--alpha-max", "-10"], "alpha-max"),
    (["sweep", *PAPER, "--out", "unused", "--alpha-max", "200"], "alpha-max"),
    (["sweep", *PAPER, "--out", "/proc/nope"], "out"),
    (["branch", *PAPER, "--out", "/proc/nope"], "out"),
    (["track", *PAPER, "--out", "/proc/nope"], "out"),
    (["reproduce", "--out", "/proc/nope"], "out"),
    (["track", *PAPER, "--tilt", "400"], "tilt"),
    (["track", *PAPER, "--alpha0", "95"], "alpha0"),
    (["greenhill", "--preset", "clamped-8cm", "--E", "-1e9"], "E (Young's modulus)"),
    (["greenhill", "--preset", "clamped-8cm", "--A", "6"], "A"),
    (["greenhill", "--G", "10", "--field", "off"], "field"),
    (["greenhill", "--G", "nan"], "G"),
    (["greenhill", "--G", "inf"], "G"),
    (["greenhill", "--G", "ten"], "G"),
    (["folds", "--G", "2.2", "--M", "0.0236", "--D", "1.05", "--magnet-radius", "0.1"],
     "tip cannot touch"),
    (["folds", "--G", "2e3", "--M", "0.0236", "--D", "1.2"], "G (gravity group)"),
    (["folds", *PAPER, "--n", "3"], "N (Chebyshev degree)"),
    (["folds", *PAPER, "--n", "16.5"], "N (Chebyshev degree)"),
    (["outofplane", *PAPER, "--alpha", "120"], "alpha"),
    (["cusp", *PAPER, "--vary", "E"], "vary"),
    (["foldcurve", *PAPER, "--vary", "D", "--to", "nan"], "to"),
    (["map", *PAPER, "--x", "D:1.1:1.3:4", "--y", "K:1:2:4", "--out", "unused"], "K"),
    (["fit", *ANGLES, "--free", "E,stiffness"], "stiffness"),
    (["fit", *ANGLES, "--free", "E,remanence", "--prior", "remanence=8e5:0"], "prior sd"),
    (["fit", *ANGLES, "--free", "E,remanence", "--prior", "remanence=8e5:-1"], "prior sd"),
    (["fit", *ANGLES, "--free", "E,remanence", "--prior", "remanence=1.2:0.05"],
     "prior remanence"),
    (["fit", *ANGLES, "--prior", "remanence"], "prior"),
    (["fit", *ANGLES, "--bounds", "E=3e11:1e11"], "bounds E"),
    (["fit", "--angles", "-28", "25", "27.5", "-91"], "angles"),
    (["design", "--capture", "40", "--release", "30", "--vary", "track-radius"], "release"),
    (["design", "--capture", "20", "--release", "95", "--vary", "track-radius"], "release"),
    (["design", "--capture", "20", "--release", "45", "--vary", "K"], "vary"),
    # sign slips in a scene file: refused, never the mirror image's answer
    (["equilibrium", "hard-magnetic-cantilever", "--set", "rod.youngs_modulus=-1.0e6"],
     "rod.youngs_modulus"),
    (["equilibrium", "hard-magnetic-cantilever", "--set", "rod.radius=-0.5e-3"], "rod.radius"),
    (["equilibrium", "hard-magnetic-cantilever", "--set", "rod.length=-0.05"], "rod.length"),
    (["equilibrium", "permanent-magnet", "--set", "field.0.diameter=-0.01"],
     "field.0.diameter"),
    # --set past the file's tables: a message, not a traceback
    (["equilibrium", "hard-magnetic-cantilever", "--set", "field.3.B=1"], "field.3.B"),
    # options that fail only after the work, checked first
    (["snap", *PAPER, "--animate", "snap.avi"], "animate"),
    (["snap", *PAPER, "--dt", "100"], "dt"),
    (["sweep", *PAPER, "--rate", "1e9", "--from", "38", "--to", "41"], "rate"),
    (["sweep", "hard-magnetic-cantilever", "--vary", "field.0.angle_deg", "--from", "90",
      "--to", "240", "--rate", "1e9"], "rate"),
    (["branch", "hard-magnetic-cantilever", "--vary", "field.0.angle_deg", "--from", "90",
      "--to", "120", "--modes", "1000"], "modes"),
]


@pytest.mark.parametrize("argv, name", TABLE, ids=[" ".join(a) for a, _ in TABLE])
def test_table_of_bad_inputs(argv, name, capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("PATH", str(tmp_path))  # no ffmpeg: an animation other than .gif
    line = refused(argv, capsys)
    assert name in line, line


# --- generated: every numeric option of every command, out of its range --------------------

def _numeric_options():
    """(command, option, range name or None) for every option parsed as a number."""
    parser = build_parser()
    sub = next(a for a in parser._actions if a.choices and isinstance(a.choices, dict))
    for command, p in sub.choices.items():
        for action in p._actions:
            if hasattr(action.type, "valid") and action.option_strings:
                yield command, action.option_strings[0], action.type.valid


OPTIONS = sorted(set(_numeric_options()))
BASE = {"greenhill": ["--G", "10"], "fit": ANGLES, "reproduce": [],
        "sweep": [*PAPER, "--out", "unused"], "branch": [*PAPER, "--out", "unused"],
        "cusp": [*PAPER, "--vary", "D"], "foldcurve": [*PAPER, "--vary", "D", "--to", "1.3"],
        "map": [*PAPER, "--x", "D:1.1:1.3:4", "--y", "M:0.02:0.03:4", "--out", "unused"],
        "design": [*PAPER, "--capture", "25", "--release", "40", "--vary", "D"]}


def _outside(valid):
    """Values outside RANGES[valid] (or no number at all)."""
    bad_text = st.sampled_from(["nan", "inf", "-inf", "1e400", "abc", "", "0x10", "1,5"])
    if valid is None:
        return bad_text
    r = RANGES[valid]
    low = st.floats(max_value=r.low, allow_nan=False, allow_infinity=False,
                    exclude_max=not r.low_open) | st.just(r.low if r.low_open else
                                                          np.nextafter(r.low, -np.inf))
    high = st.floats(min_value=r.high, allow_nan=False, allow_infinity=False,
                     exclude_min=not r.high_open) | st.just(r.high if r.high_open else
                                                            np.nextafter(r.high, np.inf))
    return bad_text | (low | high).map(repr)


def _options(parser, command):
    sub = next(a for a in parser._actions if a.choices and isinstance(a.choices, dict))
    return sorted((a.dest, tuple(a.option_strings), str(a.default), a.required)
                  for a in sub.choices[command]._actions)


def test_one_command_parses_as_in_the_full_parser():
    """A command line builds its command's parser alone (and imports its module alone): the
    same options, defaults and requirements as in the parser of every command."""
    from jaxrod.cli import COMMANDS

    full = build_parser()
    for command in COMMANDS:
        alone = build_parser(command)
        assert _options(alone, command) == _options(full, command), command
    code = ("import sys; from jaxrod.cli import build_parser; build_parser('folds'); "
            "print(' '.join(m for m in sys.modules if m.startswith('jaxrod.cli.')))")
    loaded = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                            check=True).stdout.split()
    assert "jaxrod.cli.magnet" in loaded
    assert not {"jaxrod.cli.snap", "jaxrod.cli.inverse", "jaxrod.cli.bistability"} & set(loaded)


def test_every_numeric_option_is_listed():
    commands = {c for c, _, _ in OPTIONS}
    assert {"greenhill", "folds", "sweep", "track", "fit", "cusp", "map"} <= commands
    assert ("greenhill", "--E", "E") in OPTIONS and ("folds", "--n", "N-magnet") in OPTIONS


@pytest.mark.parametrize("command, option, valid", OPTIONS,
                         ids=[f"{c} {o}" for c, o, _ in OPTIONS])
@settings(max_examples=12, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(data=st.data())
def test_generated_bad_values_are_refused(command, option, valid, data, capsys):
    value = data.draw(_outside(valid) if valid != "N-magnet" and valid != "N" else
                      st.sampled_from(["3", "0", "-5", "100000", "12.5", "nan"]) |
                      st.integers(max_value=3).map(str) |
                      st.integers(min_value=int(RANGES[valid].high) + 1).map(str))
    argv = [command, *BASE.get(command, PAPER), f"{option}={value}"]
    line = refused(argv, capsys)
    assert f"argument {option}" in line, line


# --- physical inputs: each in its range, the groups they make may not be -------------------

def _log_uniform(valid):
    r = RANGES[valid]
    low = max(r.low, 1e-12) if r.low_open else r.low
    return st.floats(math.log10(low) + 1e-9, math.log10(r.high) - 1e-9).map(lambda x: 10.0**x)


@settings(max_examples=60, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(E=_log_uniform("E"), diameter=_log_uniform("diameter"), length=_log_uniform("length"))
def test_physical_inputs_are_refused_or_computable(E, diameter, length, capsys, monkeypatch):
    """Any wire within the inputs' ranges is refused (exit 2, naming a group) or reaches the
    solver with groups inside their ranges: nothing out of range is ever computed."""
    reached = []

    def solver(G, support, A, n=None):
        reached.append((G, A))
        raise ParameterError("reached the solver")

    monkeypatch.setattr("jaxrod.uniform.greenhill.greenhill", solver)
    monkeypatch.setattr("jaxrod.uniform.greenhill.critical_length", lambda *a, **k: 1.0)
    argv = ["greenhill", "--E", repr(E), "--diameter", repr(diameter), "--length",
            repr(length)]
    line = refused(argv, capsys)
    if reached:
        (G, A), = reached
        assert RANGES["G"].contains(G) and RANGES["A"].contains(A)
    else:
        assert "G (gravity group)" in line or "A (anisotropy group)" in line, line


# --- the Python API --------------------------------------------------------------------------

API = [
    (lambda: Rod(NICKEL, "5e-5", 0.1), "diameter"),
    (lambda: preset("permanent-magnet", 1e15), "E (Young's modulus)"),
    (lambda: fold_pairs([2.2], [0.0236], [1.2228], dtype="foo"), "dtype"),
    (lambda: fold_pairs([2.2, math.nan], [0.0236] * 2, [1.2228] * 2), "row 1"),
    (lambda: fold_pairs([2.2], [0.0236], [0.9]), "D (track radius"),
    (lambda: magnet_folds.fold_angles(-2.2, 0.0236, 1.2228), "G (gravity group)"),
    (lambda: magnet_folds.fold_angles(2.2, 0.0236, 1.2228, n=500), "N (Chebyshev degree)"),
    (lambda: magnet.make_scene(2.2, 0.0236, 1.05, 0.1), "tip cannot touch"),
    (lambda: magnet_sweep.hysteresis_sweep(magnet.make_scene(2.2, 0.0236, 1.2228),
                                     alpha_max_deg=math.nan), "alpha-max"),
    (lambda: magnet_folds.locate_folds(magnet.make_scene(2.2, 0.0236, 1.2228), n=200), "N"),
    (lambda: FitSetup(2.2, 0.0236, 0.9, 2e11), "D (track radius"),
    (lambda: fit_youngs_modulus([-28, 25, 27.5, -38.5], E0=-1.0), "E (Young's modulus)"),
    (lambda: fit_youngs_modulus([-28, math.inf, 27.5, -38.5]), "angles"),
    (lambda: greenhill(10.0, n=2000), "N (Chebyshev degree)"),
    (lambda: greenhill(1e12), "G (gravity group)"),
    (lambda: Magnet(0.0, 8e5, 0.1), "magnet-diameter"),
]


@pytest.mark.parametrize("call, name", API, ids=[n for _, n in API])
def test_python_api_refuses(call, name):
    with _limits(), pytest.raises(ParameterError, match=re.escape(name)):
        call()


def test_rod_stores_floats():
    rod = Rod(NICKEL, np.float32(5e-5), 1)
    assert type(rod.diameter) is float and type(rod.length) is float


def test_traced_out_of_range_is_nan_not_converged():
    """Inside a program nothing can raise: out-of-range groups give NaN, not converged."""
    alphas, converged = jax.jit(lambda g: magnet_folds.fold_angles(g, 0.0236, 1.2228))(-2.2)
    assert not bool(converged) and np.all(np.isnan(np.asarray(alphas)))


# --- Ctrl-C keeps what was computed ------------------------------------------------------------

@pytest.mark.xdist_group("sigint")
def test_sigint_keeps_the_partial_sweep(tmp_path):
    """SIGINT to a running ``jaxrod sweep``: exit 130, one line, the positions computed so
    far in sweep.csv and sweep.json, marked incomplete."""
    out = tmp_path / "loop"
    for delay in (8.0, 20.0, 45.0):  # the sweep must have started (imports, compilation)
        proc = subprocess.Popen(
            [sys.executable, "-m", "jaxrod.cli", "sweep", *PAPER, "--out", str(out),
             "--step", "0.0005"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        time.sleep(delay)
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=120)
        assert proc.returncode == 130, err
        assert len(err.strip().splitlines()) == 1, err
        if (out / "sweep.csv").exists() and len((out / "sweep.csv").read_text().splitlines()) > 2:
            break
    rows = (out / "sweep.csv").read_text().splitlines()
    assert rows[0].startswith("# incomplete: interrupted")
    assert rows[1] == "direction,alpha_deg,tip_deg,q,snapped" and len(rows) > 100
    import json

    summary = json.loads((out / "sweep.json").read_text())
    assert summary["complete"] is False and "interrupted" in summary["reason"]
    assert summary["positions"] == len(rows) - 2
    alphas = [float(r.split(",")[1]) for r in rows[2:]]
    assert alphas[0] == -50.0 and np.allclose(np.diff(alphas)[:10], 0.0005)
