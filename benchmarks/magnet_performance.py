"""Permanent-magnet scene: accuracy of the fold angles against N, and what it costs.

Prints, for the paper's two cases (E = 200 and 100 GPa; G, M as in tab:parameters_radial,
D = 11.25/9.2):

1. the error of alpha_lower and alpha_upper against an independent shooting reference
   (scipy DOP853 + Brent on alpha(kappa), tests/shooting_reference.py) for N = 4..32, and the
   smallest N reaching 1e-10 degrees;
2. compile time (first call) and warm time (best of repeats) of: the Moore-Spence fold pair
   (both folds refined in one vmapped call from the detected fold points), the whole
   diagram (two pseudo-arclength runs over alpha in [-90, 90] degrees), and the end-to-end
   ``locate_folds`` (diagram + folds), each with the accuracy reached;
3. with ``--auto``, the same fold pair by AUTO-07p (Debian package ``auto-07p``, installed by
   ``benchmarks/auto07p.py`` if missing) at several NTST/NCOL, and the ratio of warm times
   at equal accuracy.

Run:  python benchmarks/magnet_performance.py [--quick] [--auto]
Writes benchmarks/results/magnet_performance.{json,md,png}.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "tests"))  # the shooting reference shared with the tests
sys.path.insert(0, str(HERE))

import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402
import shooting_reference as shooting  # noqa: E402

import jaxrod as jr  # noqa: E402
from jaxrod import spectral  # noqa: E402
from jaxrod.magnet import diagram as magnet  # noqa: E402
from jaxrod.magnet import folds as magnet_folds  # noqa: E402

D_EXP = 11.25 / 9.2
CASES = {200: (2.2, 0.0236), 100: (4.4, 0.0472)}


def machine() -> str:
    return (f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
            f"jax {jax.__version__} on {jax.devices()[0].platform}")


def timed(fn, repeat: int):
    t0 = time.perf_counter()
    out = jax.block_until_ready(fn())
    first = time.perf_counter() - t0
    best = math.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        jax.block_until_ready(fn())
        best = min(best, time.perf_counter() - t0)
    return out, first, best


def shooting_folds(G, M, folds, n):
    disc = jr.planar_discretisation(n, "clamped")
    ref = []
    for f in folds:
        kappa = (spectral.differentiation_matrix(n) @ np.asarray(disc.full_values(f.theta)))[0]
        X = np.asarray(jr.tip_position(jnp.asarray(f.theta), disc))
        ref.append(math.degrees(shooting.fold_alpha(
            G, M, D_EXP, (kappa - 0.02, kappa + 0.02), [math.radians(f.alpha_deg), *X],
            f.kind)))
    return ref


def convergence(quick: bool) -> dict:
    degrees = [8, 12, 16] if quick else [4, 5, 6, 7, 8, 10, 12, 14, 16, 20, 24, 32]
    out = {}
    for E, (G, M) in CASES.items():
        scene = jr.magnet_scene(G, M, D_EXP)
        ref = shooting_folds(G, M, jr.folds(scene, n=24, throw=False).folds, 24)
        rows = []
        for n in degrees:
            folds = jr.folds(scene, n=n, throw=False).folds
            errs = [abs(f.alpha_deg - r) for f, r in zip(folds, ref)] if len(folds) == 2 \
                else [math.nan, math.nan]
            rows.append({"N": n, "err_lower_deg": errs[0], "err_upper_deg": errs[1]})
            print(f"E={E} N={n:3d}  |alpha_lower err| {errs[0]:.1e} deg  "
                  f"|alpha_upper err| {errs[1]:.1e} deg", flush=True)
        ok = [r["N"] for r in rows if max(r["err_lower_deg"], r["err_upper_deg"]) <= 1e-10]
        out[E] = {"reference_deg": ref, "rows": rows, "N_for_1e-10_deg": min(ok) if ok else None}
    return out


def timings(n: int, repeat: int) -> dict:
    out = {}
    for E, (G, M) in CASES.items():
        scene = jr.magnet_scene(G, M, D_EXP)
        disc = jr.planar_discretisation(n, "clamped")
        opts = magnet.default_options()
        capacity = opts.max_points
        opts0 = opts._replace(max_points=0)
        _, diag_first, diag_warm = timed(lambda: magnet._diagram(scene, disc, opts0, capacity),
                                         repeat)
        branch = jr.diagram(scene, n)
        starts = [j for j in branch.fold_indices if branch.alpha[j] > 0]
        th0 = jnp.asarray(branch.theta[starts])
        al0 = jnp.asarray(branch.alpha[starts])
        (fp, _), pair_first, pair_warm = timed(
            lambda: magnet_folds._refine_batch(th0, al0, scene, disc, 1e-13), repeat)
        pair = sorted(np.degrees(np.asarray(fp.lam)))
        ref = shooting_folds(G, M, jr.folds(scene, n=n).folds, n)
        err = max(abs(a - r) for a, r in zip(pair, ref))
        _, _, e2e_warm = timed(lambda: jr.folds(scene, n=n), max(3, repeat // 10))
        (fast, fast_ok), fast_first, fast_warm = timed(
            lambda: jr.fold_pair(scene, n=12, throw=False), repeat)
        fast_err = max(abs(a - r) for a, r in zip(fast, ref)) if fast_ok else math.nan
        out[E] = {
            "N": n, "fold_pair_warm_ms": 1e3 * pair_warm, "fold_pair_compile_s": pair_first,
            "diagram_warm_ms": 1e3 * diag_warm, "diagram_compile_s": diag_first,
            "locate_folds_warm_ms": 1e3 * e2e_warm, "fold_pair_error_deg": err,
            "compile_note": "first call of the process; 0 where the program was already "
                            "compiled for the other case (parameters are traced)",
            "diagram_points": len(branch),
            "fold_pair_from_scratch_ms": 1e3 * fast_warm, "fold_pair_from_scratch_N": 12,
            "fold_pair_from_scratch_compile_s": fast_first,
            "fold_pair_from_scratch_error_deg": fast_err,
        }
        print(f"E={E}: fold pair {1e3 * pair_warm:.2f} ms warm (compile {pair_first:.2f} s), "
              f"error {err:.1e} deg; diagram {1e3 * diag_warm:.1f} ms warm "
              f"({len(branch)} points, compile {diag_first:.2f} s); locate_folds end to end "
              f"{1e3 * e2e_warm:.1f} ms; fold pair from scratch (N=12) {1e3 * fast_warm:.2f} ms, "
              f"error {fast_err:.1e} deg (compile {fast_first:.2f} s)", flush=True)
    return out


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--auto", action="store_true", help="compare with AUTO-07p")
    parser.add_argument("--out", default=str(HERE / "results"))
    args = parser.parse_args(argv)
    result = {"machine": machine(), "timings": timings(magnet.DEFAULT_N, 20 if args.quick else 200),
              "convergence": convergence(args.quick)}
    if args.auto:
        import auto07p

        result["auto07p"] = auto07p.compare(CASES, D_EXP, result["convergence"],
                                            result["timings"], quick=args.quick)
    write(result, Path(args.out))
    return 0


def write(result: dict, out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    (out / "magnet_performance.json").write_text(json.dumps(result, indent=2))
    lines = [f"Machine: {result['machine']}", "",
             "Fold pair = both Moore-Spence solves from the detected fold points; from scratch "
             "= `fold_pair` (continuation from alpha = 0 to the second fold, then both "
             "Moore-Spence solves, N = 12); compile = first call in the process (0 where the "
             "program was compiled for the other case: parameters are traced).", "",
             "| E GPa | N | fold pair warm ms | fold pair compile s | error deg | "
             "diagram warm ms | diagram compile s | points | locate_folds warm ms | "
             "from scratch warm ms | from scratch error deg | from scratch compile s |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for E, t in result["timings"].items():
        lines.append(f"| {E} | {t['N']} | {t['fold_pair_warm_ms']:.2f} | "
                     f"{t['fold_pair_compile_s']:.2f} | {t['fold_pair_error_deg']:.1e} | "
                     f"{t['diagram_warm_ms']:.1f} | {t['diagram_compile_s']:.2f} | "
                     f"{t['diagram_points']} | {t['locate_folds_warm_ms']:.1f} | "
                     f"{t['fold_pair_from_scratch_ms']:.2f} | "
                     f"{t['fold_pair_from_scratch_error_deg']:.1e} | "
                     f"{t['fold_pair_from_scratch_compile_s']:.2f} |")
    lines += ["", "Fold-angle error against shooting (deg):", "",
              "| E GPa | N | lower | upper |", "|---|---|---|---|"]
    for E, c in result["convergence"].items():
        for r in c["rows"]:
            lines.append(f"| {E} | {r['N']} | {r['err_lower_deg']:.1e} | "
                         f"{r['err_upper_deg']:.1e} |")
        lines.append(f"| {E} | N for 1e-10 deg: {c['N_for_1e-10_deg']} | | |")
    if "auto07p" in result:
        lines += ["", result["auto07p"]["markdown"]]
    (out / "magnet_performance.md").write_text("\n".join(lines) + "\n")

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.5, 4.5))
    for E, c in result["convergence"].items():
        n = [r["N"] for r in c["rows"]]
        for key, style in (("err_lower_deg", "o-"), ("err_upper_deg", "s--")):
            ax.semilogy(n, [max(r[key], 1e-16) for r in c["rows"]], style,
                        label=f"E={E} GPa {key.split('_')[1]} fold")
    ax.axhline(1e-10, color="0.5", lw=0.8)
    ax.set_xlabel("Chebyshev degree N")
    ax.set_ylabel("|alpha* - shooting| (deg)")
    ax.set_title("spectral convergence of the fold angles")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out / "magnet_performance.png", dpi=110)


if __name__ == "__main__":
    sys.exit(main())
