"""Calibration checked by simulation, and the speed of one fit and one design.

1000 synthetic experiments with hidden parameters: E uniform in 150-250 GPa, the magnet's
remanence drawn from its prior N(8e5, 4e4) A/m, the track's offset uniform in +-2 degrees;
the four switching angles are the folds at the hidden parameters (``fold_pairs``: one-mode
brackets and Moore-Spence, vmapped) plus Gaussian noise of 0.5 degrees. Each is fitted with
(E, remanence, offset) free and the remanence's prior (``jaxrod.inverse.fit.fit``). Prints
the fraction of 68% intervals (estimate +- one Laplace standard deviation) that cover the
truth, per parameter, and the mean of (estimate - truth) / std with its standard error
(unbiased within it), then the warm time of one fit with three free parameters and of one
design (``jaxrod.inverse.design``), and the compile time of the first call.

Run:  python benchmarks/calibration.py [--quick]     (quick: 40 experiments)
Writes benchmarks/results/calibration.json and .md.
"""

from __future__ import annotations

import argparse
import json
import math
import time
from pathlib import Path

import numpy as np

import jaxrod as jr
from jaxrod.design_point import groups_of

HERE = Path(__file__).resolve().parent
NOISE_DEG = 0.5
PRIOR = {"remanence": jr.Prior(8e5, 4e4)}
FREE = ("E", "remanence", "offset")


def experiments(K: int, seed: int = 1):
    rng = np.random.default_rng(seed)
    base = np.array(jr.default_point().values)
    values = np.tile(base, (K, 1))
    values[:, 0] = rng.uniform(150e9, 250e9, K)
    values[:, 6] = rng.normal(PRIOR["remanence"].mean, PRIOR["remanence"].sd, K)
    offsets = rng.uniform(-2.0, 2.0, K)
    G, M, D = groups_of("physical", values.T)
    pairs = jr.fold_pairs(G, M, D)
    a, converged = pairs.alpha_deg, pairs.bistable
    clean = np.stack([-a[:, 0], a[:, 1], a[:, 0], -a[:, 1]], axis=1) + offsets[:, None]
    noisy = clean + NOISE_DEG * rng.normal(size=clean.shape)
    truth = {"E": values[:, 0], "remanence": values[:, 6], "offset": offsets}
    return truth, noisy, np.asarray(converged)


def run(K: int) -> dict:
    start = time.perf_counter()
    t = time.perf_counter()
    jr.fit([-25, 38, 24, -42], FREE, priors=PRIOR)
    compile_fit = time.perf_counter() - t
    truth, measured, ok = experiments(K)
    z = {n: [] for n in FREE}
    failed = 0
    t = time.perf_counter()
    for i in np.flatnonzero(ok):
        cal = jr.fit(measured[i], FREE, priors=PRIOR, sigma_deg=NOISE_DEG)
        if not cal.converged or any(cal.std[n] is None for n in FREE):
            failed += 1
            continue
        for n in FREE:
            z[n].append((cal.estimates[n] - truth[n][i]) / cal.std[n])
    batch_s = time.perf_counter() - t
    coverage = {}
    for n in FREE:
        v = np.asarray(z[n])
        coverage[n] = {"covered_68": float(np.mean(np.abs(v) <= 1.0)),
                       "mean_z": float(np.mean(v)),
                       "standard_error_of_mean_z": float(np.std(v) / math.sqrt(v.size)),
                       "std_z": float(np.std(v))}
    one = []
    for _ in range(20):
        t = time.perf_counter()
        jr.fit(measured[0], FREE, priors=PRIOR, sigma_deg=NOISE_DEG)
        one.append(time.perf_counter() - t)
    point = jr.default_point()
    t = time.perf_counter()
    jr.design(point, 20.0, 45.0, ("track-radius", "magnet-diameter"))
    compile_design = time.perf_counter() - t
    designs = []
    for _ in range(3):
        t = time.perf_counter()
        jr.design(point, 20.0, 45.0, ("track-radius", "magnet-diameter"))
        designs.append(time.perf_counter() - t)
    return {"experiments": K, "with_two_folds": int(ok.sum()), "fits_failed": failed,
            "noise_deg": NOISE_DEG, "free": list(FREE), "coverage": coverage,
            "batch_s": batch_s, "fit_warm_ms": 1e3 * min(one),
            "fit_warm_median_ms": 1e3 * float(np.median(one)),
            "design_warm_s": min(designs), "first_fit_s_including_compile": compile_fit,
            "first_design_s_including_compile": compile_design,
            "benchmark_wall_s": time.perf_counter() - start}


def markdown(res: dict) -> str:
    lines = [f"# Calibration by simulation ({res['experiments']} synthetic experiments)", "",
             f"Free: {', '.join(res['free'])}; remanence prior N(8e5, 4e4) A/m; noise "
             f"{res['noise_deg']} deg; {res['with_two_folds']} with two folds, "
             f"{res['fits_failed']} fits failed.", "",
             "| parameter | 68% intervals covering the truth | mean (est - truth)/std | "
             "its standard error | sd of (est - truth)/std |", "|---|---|---|---|---|"]
    for n, c in res["coverage"].items():
        lines.append(f"| {n} | {100 * c['covered_68']:.1f}% | {c['mean_z']:+.3f} | "
                     f"{c['standard_error_of_mean_z']:.3f} | {c['std_z']:.3f} |")
    lines += ["", f"One fit (3 free parameters), warm: {res['fit_warm_ms']:.1f} ms (best of 20; "
              f"median {res['fit_warm_median_ms']:.1f} ms). One design (2 inputs, 10 starts, "
              f"verified by locate_folds), warm: {res['design_warm_s']:.3f} s.",
              f"First fit including compilation: {res['first_fit_s_including_compile']:.1f} s; "
              f"first design: {res['first_design_s_including_compile']:.1f} s.",
              f"The {res['experiments']} fits: {res['batch_s']:.1f} s; whole benchmark "
              f"{res['benchmark_wall_s']:.1f} s."]
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--out", default=str(HERE / "results"))
    args = parser.parse_args()
    res = run(40 if args.quick else 1000)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "calibration.json").write_text(json.dumps(res, indent=1))
    (out / "calibration.md").write_text(markdown(res))
    print(markdown(res))


if __name__ == "__main__":
    main()
