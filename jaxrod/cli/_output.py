"""The command line's output: report headers, output directories, 'not converged' lines."""

from __future__ import annotations

import json
import math
import os
import sys
from pathlib import Path

from jaxrod.cli._inputs import _inputs_line
from jaxrod.params import (
    ParameterError,
)


def _enable_compilation_cache() -> None:
    """The command line keeps its compiled programs between runs (``jr.enable_caches``);
    set JAXROD_NO_CACHE=1 to disable."""
    if os.environ.get("JAXROD_NO_CACHE"):
        return
    from jaxrod.stored import enable_caches

    enable_caches()


def _header(info: dict) -> str:
    """The first line(s) of a magnet-scene report: the inputs used and the groups."""
    inputs = info["inputs"]
    groups = (f"G = {info['G']:.8g}, M = {info['M']:.8g}, D = {info['D']:.10g}, "
              f"N = {inputs['N']['value']}")
    return (_inputs_line(inputs) + "\n" if "E" in inputs else "") + groups


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


def _not_converged(command: str, why: str) -> None:
    print(f"jaxrod {command}: not converged: {why}", file=sys.stderr)


def _write_fold_curves(curves, point, summary: dict, out_dir: Path) -> None:
    """foldcurve.csv (a row per point of each curve), foldcurve.json and foldcurve.png."""
    from jaxrod.plotting import fold_curve_figure

    with open(out_dir / "foldcurve.csv", "w") as fh:
        columns = list(curves[0].columns())
        fh.write("curve," + ",".join(columns) + "\n")
        for c in curves:
            cols = c.columns()
            for i in range(len(c.values)):
                fh.write(c.name + "," + ",".join(f"{cols[k][i]:.12g}" for k in columns) + "\n")
    (out_dir / "foldcurve.json").write_text(json.dumps(summary, indent=1))
    fold_curve_figure(curves, point).savefig(out_dir / "foldcurve.png", dpi=120)


def _fmt_cusp(c, vary: str) -> str:
    return (f"cusp: {vary} = {c.along_value:.12g}  alpha* = {c.value:.10f} deg  "
            f"q* = {c.q:.10f}  tip* = {c.tip_angle_deg:.10f} deg  "
            f"d3F/dq3 = {c.cubic_coefficient:.8g}  dF/dalpha = {math.degrees(c.dF_dvalue):.6g}")
