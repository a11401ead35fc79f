"""Inverse fitting of Young's modulus: time of one fit (warm) and of a batch of fits.

One fit = L-BFGS (optax) on 0.5 chi^2 over (log E, offset), every loss evaluation computing
both fold angles from scratch (continuation + Moore-Spence) with implicit gradients. The
batch fits K synthetic wires (E uniform in 80-250 GPa, offsets in +-2 deg, noise 0.5 deg) in
one vmapped call, and one by one. Prints compile time, warm time per fit, and the recovery
error. (Under vmap every nested while loop runs until its slowest batch element is done, so
on a CPU the vmapped batch is not faster than the loop; it is the form that scales on a GPU.)

Run:  python benchmarks/fit_performance.py [--quick]    (quick: K = 4; full: K = 1000)
Writes benchmarks/results/fit_performance.json.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np

import jaxrod as jr
from jaxrod.inverse import youngs as fit_youngs
from jaxrod.programs import jit  # as jaxrod compiles its own programs

HERE = Path(__file__).resolve().parent


def synthetic(K: int, seed: int = 0):
    rng = np.random.default_rng(seed)
    E_true = rng.uniform(80e9, 250e9, K)
    offsets = rng.uniform(-2.0, 2.0, K)
    setup = fit_youngs.setup_from_preset()
    model = jit(jax.vmap(lambda p: fit_youngs.model_angles(p, setup)[0]))
    angles = np.asarray(model(jnp.stack([jnp.log(E_true), jnp.asarray(offsets)], axis=1)))
    return E_true, angles + 0.5 * rng.normal(size=angles.shape)


def vmap_only(K: int, out: Path) -> int:
    E_true, measured = synthetic(K)
    t0 = time.perf_counter()
    jr.fit_batch(measured, 0.5, True, method="vmap")
    first = time.perf_counter() - t0
    t0 = time.perf_counter()
    results = jr.fit_batch(measured, 0.5, True, method="vmap")
    warm = time.perf_counter() - t0
    z = np.array([(r["E_Pa"] - e) / r["E_std_Pa"] for r, e in zip(results, E_true)])
    conv = sum(r["converged"] for r in results)
    d = jax.devices()[0]
    summary = {"device": f"{d.device_kind} ({d.platform}), jax {jax.__version__}",
               "vmapped_batch_size": K, "vmapped_batch_s": warm,
               "vmapped_batch_compile_plus_first_s": first, "fits_per_s": K / warm,
               "converged": int(conv), "rms_normalised_error": float(np.sqrt(np.mean(z**2)))}
    print(json.dumps(summary), flush=True)
    out.mkdir(parents=True, exist_ok=True)
    (out / f"fit_performance_{d.platform}.json").write_text(json.dumps(summary, indent=2))
    return 0


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--out", default=str(HERE / "results"))
    parser.add_argument("--vmap-only", type=int, default=None, metavar="K",
                        help="only a vmapped batch of K fits (the GPU measurement); writes "
                        "fit_performance_<backend>.json")
    args = parser.parse_args(argv)
    if args.vmap_only:
        return vmap_only(args.vmap_only, Path(args.out))
    paper = [-25.0, 38.0, 24.0, -42.0]
    t0 = time.perf_counter()
    jr.fit_youngs_modulus(paper, 1.0, True)
    first = time.perf_counter() - t0
    warm = math.inf
    for _ in range(3 if args.quick else 10):
        t0 = time.perf_counter()
        r = jr.fit_youngs_modulus(paper, 1.0, True)
        warm = min(warm, time.perf_counter() - t0)
    print(f"one fit: compile+run {first:.1f} s, warm {1e3 * warm:.0f} ms "
          f"({r['iterations']} L-BFGS iterations), E = {r['E_Pa'] / 1e9:.3f} GPa", flush=True)

    K = 4 if args.quick else 1000
    E_true, measured = synthetic(K)
    Kv = K if args.quick else 16  # vmapped batches on the CPU are slow (see the docstring)
    t0 = time.perf_counter()
    results = jr.fit_batch(measured[:Kv], 0.5, True, method="vmap")
    batch_first = time.perf_counter() - t0  # compile (for this K) + run
    t0 = time.perf_counter()
    results = jr.fit_batch(measured[:Kv], 0.5, True, method="vmap")
    batch = time.perf_counter() - t0
    t0 = time.perf_counter()
    sequential = jr.fit_batch(measured, 0.5, True, method="loop", progress=not args.quick)
    loop = time.perf_counter() - t0
    z = np.array([(r["E_Pa"] - e) / r["E_std_Pa"] for r, e in zip(sequential, E_true)])
    conv = sum(r["converged"] for r in sequential)
    print(f"vmapped batch of {Kv} fits: {batch:.2f} s ({1e3 * batch / Kv:.1f} ms per fit; "
          f"compile {batch_first - batch:.1f} s); {K} fits one by one: {loop:.2f} s "
          f"({1e3 * loop / K:.1f} ms per fit); converged {conv}/{K}; rms of "
          f"(E_fit - E_true)/std = {np.sqrt(np.mean(z**2)):.2f}", flush=True)
    assert all(abs(a["E_Pa"] - b["E_Pa"]) <= 1e-6 * b["E_Pa"] for a, b in
               zip(results, sequential)), "vmapped and sequential fits disagree"
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "fit_performance.json").write_text(json.dumps({
        "one_fit_compile_s": first, "one_fit_warm_s": warm, "batch_size": K,
        "vmapped_batch_size": Kv, "vmapped_batch_s": batch,
        "vmapped_batch_compile_s": batch_first - batch, "sequential_s": loop,
        "converged": int(conv),
        "rms_normalised_error": float(np.sqrt(np.mean(z**2)))}, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
