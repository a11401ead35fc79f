"""Fold pairs per second for batches of K parameter sets (vmap), float64 and float32, on the
default JAX backend (CPU here; a GPU where JAX has one).

Parameter sets: the paper's permanent-magnet wire with E uniform in 80-250 GPa (G, M scale
as 1/E; D = 11.25/9.2). For each K and precision: compile time, warm time (best of 3 for
small K), fold pairs per second, the fraction converged, the error against float64 (and of
float64 against the continuation-based ``fold_angles`` on the first 256 sets), and the
memory per parameter set from XLA's compiled-memory analysis. The baseline row is
``fold_angles`` (continuation + Moore-Spence) vmapped.

Run:  python benchmarks/throughput.py [--quick] [--max-k K]
Writes benchmarks/results/throughput_<backend>.{json,md}.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import sys
import time
from pathlib import Path

import jax
import numpy as np

import jaxrod as jr
from jaxrod.magnet.batch import fold_pairs_program
from jaxrod.programs import jit, padded  # as jaxrod compiles its own programs

HERE = Path(__file__).resolve().parent
D_EXP = 11.25 / 9.2


def device() -> str:
    d = jax.devices()[0]
    cores = os.cpu_count()
    if d.platform == "cpu":
        return f"CPU ({platform.machine()}, {cores} cores), jax {jax.__version__}"
    return f"{d.device_kind} ({d.platform}), host {cores} cores, jax {jax.__version__}"


def parameter_sets(K: int, seed: int = 0):
    E = np.random.default_rng(seed).uniform(80.0, 250.0, K)
    return 2.2 * 200.0 / E, 0.0236 * 200.0 / E, np.full(K, D_EXP)


def timed(fn, repeat):
    t0 = time.perf_counter()
    out = jax.block_until_ready(fn())
    first = time.perf_counter() - t0
    best = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = jax.block_until_ready(fn())
        best = min(best, time.perf_counter() - t0)
    return out, first, best


def memory_per_set(K: int, dtype: str) -> float | None:
    """Bytes per parameter set of the program ``fold_pairs`` ran for K sets (the padded
    batch, called as ``fold_pairs`` calls it: the same program, already compiled)."""
    inputs = padded(parameter_sets(K))
    try:
        compiled = fold_pairs_program.lower(*inputs, n=12, dtype=dtype).compile()
        mem = compiled.memory_analysis()
        total = mem.temp_size_in_bytes + mem.argument_size_in_bytes + mem.output_size_in_bytes
        return total / inputs[0].shape[0]
    except Exception:  # memory analysis is not available on every backend
        return None


_baseline = jit(jax.vmap(lambda G, M, D: jr.fold_angles(G, M, D, n=12)))


def run(ks, quick: bool) -> dict:
    rows = []
    reference = {}
    for dtype in ("float64", "float32"):
        for K in ks:
            G, M, D = parameter_sets(K)
            repeat = 3 if K <= 10_000 else 1
            res, first, best = timed(lambda: jr.fold_pairs(G, M, D, dtype=dtype), repeat)
            deg, conv, iters = res.alpha_deg, res.bistable, res.iterations
            row = {"dtype": dtype, "K": K, "compile_plus_first_s": first, "warm_s": best,
                   "pairs_per_s": K / best, "converged_fraction": float(np.mean(conv)),
                   "max_newton_iterations": int(np.max(iters)),
                   "bytes_per_set": memory_per_set(K, dtype)}
            if dtype == "float64":
                reference[K] = deg
            else:
                ok = np.asarray(conv)
                row["max_error_vs_float64_deg"] = float(np.max(np.abs(deg - reference[K])[ok]))
            rows.append(row)
            print(json.dumps(row), flush=True)
    # float64 against the continuation-based path, and the baseline's throughput (the quick
    # form at a K it has run already: its fold_pairs program is compiled)
    Kb = 10 if quick else 256
    G, M, D = parameter_sets(Kb)
    (alphas, conv), first, best = timed(lambda: _baseline(G, M, D), 2)
    err = float(np.max(np.abs(np.degrees(np.asarray(alphas)) - reference_for(Kb))))
    baseline = {"K": Kb, "warm_s": best, "pairs_per_s": Kb / best,
                "compile_plus_first_s": first, "converged_fraction": float(np.mean(conv)),
                "max_difference_fold_pairs_vs_fold_angles_deg": err}
    print(json.dumps(baseline), flush=True)
    return {"device": device(), "rows": rows, "baseline_fold_angles": baseline}


def reference_for(K: int) -> np.ndarray:
    G, M, D = parameter_sets(K)
    return jr.fold_pairs(G, M, D).alpha_deg


def markdown(res: dict) -> str:
    lines = [f"# Fold-pair throughput on {res['device']}", "",
             "E uniform in 80-250 GPa (paper's wire, D = 11.25/9.2), N = 12; "
             "`jaxrod.magnet.batch.fold_pairs` (one-mode bracketing + Moore-Spence, vmapped).",
             "", "| dtype | K | pairs/s | warm s | compile + first s | converged | "
             "max error vs float64 (deg) | bytes per set |", "|---|---|---|---|---|---|---|---|"]
    for r in res["rows"]:
        err = r.get("max_error_vs_float64_deg")
        mem = r["bytes_per_set"]
        lines.append(f"| {r['dtype']} | {r['K']} | {r['pairs_per_s']:.4g} | {r['warm_s']:.4g} | "
                     f"{r['compile_plus_first_s']:.3g} | {r['converged_fraction']:.4f} | "
                     f"{'-' if err is None else f'{err:.1e}'} | "
                     f"{'-' if mem is None else f'{mem:.3g}'} |")
    b = res["baseline_fold_angles"]
    lines += ["", f"Baseline `fold_angles` vmapped (continuation + Moore-Spence), K = {b['K']}: "
              f"{b['pairs_per_s']:.4g} pairs/s; largest difference to `fold_pairs`: "
              f"{b['max_difference_fold_pairs_vs_fold_angles_deg']:.1e} deg."]
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="K = 1 and 10 only")
    parser.add_argument("--max-k", type=int, default=100_000)
    parser.add_argument("--out", default=str(HERE / "results"))
    args = parser.parse_args(argv)
    top = 10 if args.quick else args.max_k
    ks = [k for k in (1, 10, 100, 1000, 10_000, 100_000, 1_000_000) if k <= top]
    res = run(ks, args.quick)
    backend = jax.devices()[0].platform
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    name = "throughput" if args.quick else f"throughput_{backend}"
    (out / f"{name}.json").write_text(json.dumps(res, indent=1))
    (out / f"{name}.md").write_text(markdown(res))
    print(markdown(res))
    return 0


if __name__ == "__main__":
    sys.exit(main())
