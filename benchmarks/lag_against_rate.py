"""The switching lag against the sweep rate over four decades, beside the fold's normal form.

The magnet of the paper's rig (G = 2.2, M = 0.0236, D = 11.25 / 9.2) swept past the upper
fold at rates from 1e-5 to 1e-1 degrees per unit time (T = L^2 sqrt(rho A_c / (E I))), for a
linear drag c = 0 (inertial: eps^(4/5)), c = 1 (the crossover between the regimes near
1e-3 degrees per unit time) and c = 10 (damped: eps^(2/3)); each sweep by BDF2 with adaptive
steps (``jaxrod.dynamics.rate_sweep``; local accuracy 1e-6, or 1% of the predicted lag
where that is smaller), started on the quasi-static branch a few predicted
lags before the fold with the branch's own velocity, so no transient rings. The prediction
is ``jaxrod.dynamics.normal_form`` (the modal mass, dF/dalpha and d2F/dq2 at the fold).
Prints the table, the fitted exponents over the slowest two decades, and writes
benchmarks/results/lag_against_rate.{json,md,png}.

Run:  python benchmarks/lag_against_rate.py [--quick]   (quick: three rates per drag)
"""

from __future__ import annotations

import argparse
import json
import math
import time
from pathlib import Path

import numpy as np

import jaxrod as jr
from jaxrod.dynamics.figures import lag_figure
from jaxrod.dynamics.normal_form import normal_form
from jaxrod.dynamics.rate_sweep import rate_sweep

HERE = Path(__file__).resolve().parent
SCENE = jr.Scene({"bending": jr.Bending(), "gravity": jr.Gravity(2.2),
                  "magnet": jr.Dipole(0.0236, 11.25 / 9.2, 0.0)})
KEY = "magnet.alpha"


def start_on_branch(fold, held, lead):
    """The equilibrium ``lead`` before the fold and d(state)/d(alpha) there."""
    a0 = fold.value - lead
    h = 1e-7
    states = [jr.equilibrium(SCENE.replace(KEY, a), state=held).state
              for a in (a0 - h, a0, a0 + h)]
    return a0, states[1], (states[2] - states[0]) / (2 * h)


def one(fold, held, nf, rate):
    lead = max(6.0 * nf.lag(rate), math.radians(0.01))
    a0, state, dstate = start_on_branch(fold, held, lead)
    stop = fold.value + 1.5 * nf.lag(rate) + 20.0 * rate
    t0 = time.perf_counter()
    tol = min(1e-6, 1e-2 * nf.lag(rate))  # the state's accuracy well below the lag
    s = rate_sweep(SCENE.replace(KEY, a0), KEY, state, stop, rate, nf.damping, dt=5.0,
                   velocity=rate * dstate, max_steps=60000, tol=tol)
    wall = time.perf_counter() - t0
    lag = s.switches[0] - fold.value if len(s.switches) == 1 else float("nan")
    return {"rate_deg": math.degrees(rate), "lag_deg": math.degrees(lag),
            "predicted_deg": math.degrees(nf.lag(rate)), "steps": len(s.values),
            "converged": s.trajectory.converged, "wall_s": wall}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args()
    rates_deg = [1e-4, 1e-3, 1e-2] if args.quick else np.geomspace(1e-5, 1e-1, 9).tolist()
    fold = max(jr.folds(SCENE, KEY, 0.0, math.pi / 2), key=lambda f: f.value)
    held = jr.sweep(SCENE, KEY, np.radians(np.r_[0:39:0.5]).tolist()).states[-1]
    results, forms = {}, {}
    for c in (0.0, 1.0, 10.0):
        nf = normal_form(SCENE, fold, c)
        forms[c] = nf
        rows = [one(fold, held, nf, math.radians(r)) for r in rates_deg]
        slow = rows[: max(3, len(rows) // 2 + 1)]  # the slowest two decades
        slope = float(np.polyfit(np.log([r["rate_deg"] for r in slow]),
                                 np.log([r["lag_deg"] for r in slow]), 1)[0])
        to_deg = lambda p, b: p * (180 / math.pi) ** (1 - b)  # noqa: E731
        results[c] = {"rows": rows, "slope_slowest_two_decades": slope,
                      "damped_prefactor_deg": None if c == 0 else
                      to_deg(nf.damped_prefactor, 2 / 3),
                      "inertial_prefactor_deg": to_deg(nf.inertial_prefactor, 0.8),
                      "crossover_rate_deg": math.degrees(nf.crossover_rate)}
        print(f"c = {c:g}: slope {slope:.4f} over {slow[0]['rate_deg']:.0e}.."
              f"{slow[-1]['rate_deg']:.0e} deg/T; crossover at "
              f"{math.degrees(nf.crossover_rate):.3g} deg/T")
        for r in rows:
            print(f"  rate {r['rate_deg']:9.3g}  lag {r['lag_deg']:.6g}  normal form "
                  f"{r['predicted_deg']:.6g}  ratio {r['lag_deg'] / r['predicted_deg']:.4f}  "
                  f"({r['steps']} steps, {r['wall_s']:.2f} s)")
    out = HERE / "results"
    (out / "lag_against_rate.json").write_text(json.dumps(
        {"fold_deg": math.degrees(fold.value), "by_drag": {str(c): v for c, v in
                                                             results.items()}}, indent=1))
    lines = ["# The switching lag against the sweep rate", "",
             f"The paper's rig, upper fold at {math.degrees(fold.value):.8f} deg; rates in "
             "degrees per unit time T. Measured: BDF2, adaptive steps (tol 1e-6, or 1% of the "
             "predicted lag); predicted: "
             "the fold's normal form (`jaxrod.dynamics.normal_form`).", "",
             "| drag c | rate | lag (deg) | normal form (deg) | ratio | steps | wall (s) |",
             "|---|---|---|---|---|---|---|"]
    for c, v in results.items():
        for r in v["rows"]:
            lines.append(f"| {c:g} | {r['rate_deg']:.3g} | {r['lag_deg']:.6g} | "
                         f"{r['predicted_deg']:.6g} | {r['lag_deg'] / r['predicted_deg']:.4f} | "
                         f"{r['steps']} | {r['wall_s']:.2f} |")
    lines += ["", "| drag c | fitted exponent (slowest two decades) | theory | crossover rate |",
              "|---|---|---|---|"]
    for c, v in results.items():
        lo, hi = min(rates_deg), max(rates_deg)
        theory = "4/5" if c == 0 else "2/3" if v["crossover_rate_deg"] > hi else \
            "from 2/3 to 4/5 (the crossover inside the range)" if v["crossover_rate_deg"] > lo \
            else "4/5"
        lines.append(f"| {c:g} | {v['slope_slowest_two_decades']:.4f} | {theory} | "
                     f"{v['crossover_rate_deg']:.3g} |")
    (out / "lag_against_rate.md").write_text("\n".join(lines) + "\n")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 3, figsize=(16, 4.8))
    for ax, (c, v) in zip(axes, results.items()):
        rates = np.radians([r["rate_deg"] for r in v["rows"]])
        lags = np.radians([r["lag_deg"] for r in v["rows"]])
        lag_figure(rates, lags, forms[c], ax=ax)
        ax.set_title(f"drag c = {c:g}")
    fig.tight_layout()
    fig.savefig(out / "lag_against_rate.png", dpi=130)


if __name__ == "__main__":
    main()
