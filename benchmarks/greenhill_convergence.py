"""Spectral convergence of the Greenhill eigenvalues and pitchfork coefficients against N.

For each support and G, and each Chebyshev degree N, prints the relative error of
beta0 (= -A_crit) and the error of A2, relative to max(|A2|, 1), against closed-form
references (the Airy characteristic equation solved by scipy's brentq; A2 by adaptive
quadrature of the Airy eigenfunction), the warm run
time per evaluation and the compile time, and the smallest N reaching 1e-10. (The clamped A2
has a zero at G = 9.9998, next to the case G = 10 where A2 = 4e-5: a relative error there
measures round-off amplified 2.5e4 times, so, as in tests/test_greenhill.py, A2's error is
taken relative to max(|A2|, 1).) The stiff cases
are G = 1e3, 1e4 (Airy boundary layer of width G^(-1/3) at the support) and the stability
margin A + beta0(G) at A = G = 1e4, where two numbers of size 1e4 nearly cancel.

Run:  python benchmarks/greenhill_convergence.py [--quick]
Writes benchmarks/results/greenhill_convergence.{json,md,png}.

Typical output (2-core CPU, excerpt):

    clamped G=10000  N=32  beta0 err 2.0e-16  A2 err 4.3e-12  warm 0.3 ms  compile 0.4 s
    N for 1e-10: clamped G=1e4 -> 32, pinned G=1e4 -> 32
"""

from __future__ import annotations

import json
import os
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "tests"))  # the Airy reference shared with the tests

import airy_reference as airy  # noqa: E402
import jax  # noqa: E402
import numpy as np  # noqa: E402
from common import benchmark_main  # noqa: E402

import jaxrod as jr  # noqa: E402
from jaxrod.programs import jit  # noqa: E402  (as jaxrod compiles its own programs)
from jaxrod.uniform.greenhill import pitchfork_coefficients  # noqa: E402


def _time(fn, *args, repeat=20):
    t0 = time.perf_counter()
    jax.block_until_ready(fn(*args))
    compile_s = time.perf_counter() - t0
    best = np.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        jax.block_until_ready(fn(*args))
        best = min(best, time.perf_counter() - t0)
    return compile_s, best


def run(quick: bool) -> dict:
    degrees = [8, 12, 16, 24, 32, 48] if quick else [8, 12, 16, 20, 24, 32, 40, 48, 64, 96, 128]
    cases = ([("clamped", 10.0), ("pinned", 1e4)] if quick else
             [(s, G) for s in ("clamped", "pinned") for G in (1.0, 10.0, 100.0, 1e3, 1e4)])
    rows, needed = [], {}
    for support, G in cases:
        beta_ref = airy.principal_eigenvalue(G, support)
        a2_ref = airy.pitchfork_coefficient(G, support)
        for n in degrees:
            disc = jr.planar_discretisation(n, support)
            fn = jit(pitchfork_coefficients)
            compile_s, warm_s = _time(fn, G, disc)
            beta, a2, _ = (float(v) for v in fn(G, disc))
            row = {
                "support": support, "G": G, "N": n,
                "beta0_rel_err": abs(beta - beta_ref) / abs(beta_ref),
                "A2_err": abs(a2 - a2_ref) / max(abs(a2_ref), 1.0),
                "warm_ms": 1e3 * warm_s, "first_call_s": compile_s,
            }
            if G == 1e4:  # stiff margin A + beta0 at A = 1e4: cancellation of two ~1e4 numbers
                margin_ref = 1e4 + beta_ref
                row["margin_A1e4_rel_err"] = abs((1e4 + beta) - margin_ref) / abs(margin_ref)
            rows.append(row)
            print(f"{support:8s} G={G:<7g} N={n:<4d} beta0 err {row['beta0_rel_err']:.1e}  "
                  f"A2 err {row['A2_err']:.1e}  warm {row['warm_ms']:.2f} ms  "
                  f"first call {compile_s:.2f} s", flush=True)
        for key in ("beta0_rel_err", "A2_err", "margin_A1e4_rel_err"):
            ok = [r["N"] for r in rows if r["support"] == support and r["G"] == G
                  and key in r and r[key] <= 1e-10]
            if any(key in r for r in rows if r["G"] == G):
                needed[f"{support} G={G:g} {key}"] = min(ok) if ok else None
    print("\nN needed for 1e-10:")
    for k, v in needed.items():
        print(f"  {k}: {v}")
    return {"rows": rows, "N_for_1e-10": needed, "machine": _machine()}


def _machine() -> str:
    import platform

    return f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores, " \
           f"jax {jax.__version__} on {jax.devices()[0].platform}"


def write(result: dict, out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    (out / "greenhill_convergence.json").write_text(json.dumps(result, indent=2))
    lines = ["First call = compile + run; ~0 where this N was compiled for an earlier G.", "",
             "| support | G | N | beta0 rel err | A2 err / max(A2, 1) | warm ms | first call s |",
             "|---|---|---|---|---|---|---|"]
    for r in result["rows"]:
        lines.append(f"| {r['support']} | {r['G']:g} | {r['N']} | {r['beta0_rel_err']:.1e} | "
                     f"{r['A2_err']:.1e} | {r['warm_ms']:.2f} | {r['first_call_s']:.2f} |")
    lines += ["", "N needed for 1e-10:", ""]
    lines += [f"- {k}: {v}" for k, v in result["N_for_1e-10"].items()]
    lines += ["", f"Machine: {result['machine']}"]
    (out / "greenhill_convergence.md").write_text("\n".join(lines) + "\n")

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(11, 4), sharey=True)
    for ax, key, title in ((axes[0], "beta0_rel_err", "beta0 (= -A_crit)"),
                           (axes[1], "A2_err", "A2 (error / max(|A2|, 1))")):
        for support, G in sorted({(r["support"], r["G"]) for r in result["rows"]}):
            sel = [r for r in result["rows"] if r["support"] == support and r["G"] == G]
            ax.semilogy([r["N"] for r in sel], [max(r[key], 1e-17) for r in sel], marker="o",
                        ls="-" if support == "clamped" else "--", label=f"{support} G={G:g}")
        ax.axhline(1e-10, color="0.5", lw=0.8)
        ax.set_xlabel("Chebyshev degree N")
        ax.set_title(f"error of {title} vs Airy reference")
    axes[0].set_ylabel("error")
    axes[1].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(out / "greenhill_convergence.png", dpi=110)


def main(argv=None) -> int:
    return benchmark_main(__doc__, run, write, argv, quick_help="two cases, N <= 48")


if __name__ == "__main__":
    sys.exit(main())
