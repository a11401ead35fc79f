"""Stiff and extreme cases: converge, or fail with a message.

Permanent magnet: for each case the fold angles at N = 8 ... 64, the smallest N whose folds
agree with N = 64 to 1e-10 degrees, the Moore-Spence iterations, the status of the
continuation, and whether the reduced route (Newton on F = dF/dq = 0) converges to the same
folds, with its contraction constant K. Cases: the clearance D - 1 from 0.3 down to 0.01
(with the paper's M, and with M scaled so that the field at the straight rod's tip,
~M/delta^3, stays the paper's), a strong magnet, tip angles up to ~90 degrees, the E = 100
GPa upper fold, and parameters next to the cusp where the two folds merge (located by
bisection on M); rows without folds show the clear report.

Greenhill (uniform field): beta0 and the margin A + beta0 for G up to 1e4 and A = 1e4, the
smallest N reaching 1e-10 relative against N = 160, for both supports.

Run:  python benchmarks/extreme.py [--quick]
Writes benchmarks/results/extreme.{json,md}.
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

from common import benchmark_main

import jaxrod as jr

D_EXP = 11.25 / 9.2


def fold_count(G, M, D, n=16):
    return len(jr.folds(jr.magnet_scene(G, M, D), n=n, throw=False).folds)


def cusp_magnet_group(G, D, lo=0.002, hi=0.0236, steps=30):
    """Smallest M (bisection) with two folds on the branch: the cusp at (G, D)."""
    for _ in range(steps):
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if fold_count(G, mid, D) == 2 else (mid, hi)
    return hi


def run(quick: bool) -> dict:
    degrees = [16, 32] if quick else [8, 12, 16, 24, 32, 48]
    delta = D_EXP - 1.0
    scaled = lambda d: 0.0236 * (d / delta) ** 3
    cases = [
        ("paper E=200", 2.2, 0.0236, D_EXP),
        ("E=100 (upper fold tip ~50 deg)", 4.4, 0.0472, D_EXP),
        ("clearance D-1=0.3", 2.2, 0.0236, 1.3),
        ("clearance D-1=0.1 (tip ~60 deg)", 2.2, 0.0236, 1.1),
        ("clearance D-1=0.05 (tip ~74 deg)", 2.2, 0.0236, 1.05),
        ("clearance D-1=0.02, M scaled by (0.02/0.2228)^3", 2.2, scaled(0.02), 1.02),
        ("clearance D-1=0.01, M scaled by (0.01/0.2228)^3", 2.2, scaled(0.01), 1.01),
        ("strong magnet M=0.2", 2.2, 0.2, D_EXP),
    ]
    if not quick:
        cases += [("clearance D-1=0.2", 2.2, 0.0236, 1.2),
                  ("clearance D-1=0.03 (tip near 90 deg)", 2.2, 0.0236, 1.03),
                  ("clearance D-1=0.05, M scaled", 2.2, scaled(0.05), 1.05)]
    if not quick:
        m_cusp = cusp_magnet_group(2.2, D_EXP)
        print(f"cusp at G=2.2, D=11.25/9.2: M = {m_cusp:.10f}", flush=True)
        cases += [("cusp: M = 1.001 M_cusp", 2.2, 1.001 * m_cusp, D_EXP),
                  ("cusp: M = 0.999 M_cusp (no fold)", 2.2, 0.999 * m_cusp, D_EXP)]
    cases += [("clearance D-1=0.02, M=0.0236 (engaged to 90 deg: no fold)", 2.2, 0.0236, 1.02),
              ("clearance D-1=0.01, M=0.0236 (engaged to 90 deg: no fold)", 2.2, 0.0236, 1.01)]
    if quick:  # the tests' form: one case of each kind
        keep = ("paper E=200", "clearance D-1=0.05 (tip ~74 deg)",
                "clearance D-1=0.01, M scaled by (0.01/0.2228)^3", "strong magnet M=0.2",
                "clearance D-1=0.01, M=0.0236 (engaged to 90 deg: no fold)")
        cases = [c for c in cases if c[0] in keep]
    rows = []
    for name, G, M, D in cases:
        scene = jr.magnet_scene(G, M, D)
        t0 = time.perf_counter()
        ref = jr.folds(scene, n=64, throw=False)
        per_n = {}
        for n in degrees:
            rep = jr.folds(scene, n=n, throw=False)
            per_n[n] = [f.alpha_deg for f in rep.folds]
        ok = [n for n, a in per_n.items() if len(a) == len(ref.folds)
              and all(abs(x - f.alpha_deg) <= 1e-10 for x, f in zip(a, ref.folds))]
        row = {
            "case": name, "G": G, "M": M, "D": D, "reduced": reduced_route(scene, ref.folds),
            "folds": [f.as_dict() | {"alpha_deg": f.alpha_deg} for f in ref.folds],
            "N_for_1e-10_deg": min(ok) if ok else None,
            "moore_spence_iterations": [f.iterations for f in ref.folds],
            "branch_status": list(ref.branch.status), "converged": ref.converged,
            "seconds": time.perf_counter() - t0,
        }
        if not ref.folds:
            row["message"] = ("no fold on the branch through the straight rod in "
                              "[-90, 90] degrees")
        rows.append(row)
        summary = ", ".join(f"{f.kind} {f.alpha_deg:.10f} deg (tip {f.tip_deg:.2f})"
                            for f in ref.folds) or row["message"]
        print(f"{name}: {summary}; N for 1e-10 deg: {row['N_for_1e-10_deg']}; "
              f"iterations {row['moore_spence_iterations']}; converged {ref.converged}",
              flush=True)
    return {"rows": rows, "greenhill": greenhill_cases(quick)}


def reduced_route(scene, folds) -> dict:
    """The reduced route at the same scene: agreement with Moore-Spence, K at each fold."""
    import numpy as np

    from jaxrod.magnet.contraction import contraction_constants

    try:
        red_folds = jr.reduced_folds(scene, n=32)
    except jr.ParameterError as err:
        return {"message": str(err)}
    if len(red_folds) != len(folds) or not folds:
        return {"message": f"{len(red_folds)} one-mode folds against {len(folds)} folds"}
    disc = jr.planar_discretisation(32)
    red = jr.reduction(scene, disc)
    K = [float(contraction_constants(f.q, np.radians(f.alpha_deg), red, scene, disc)["K"])
         for f in red_folds]
    return {"converged": all(f.converged for f in red_folds),
            "max_difference_deg": max(abs(a.alpha_deg - b.alpha_deg)
                                      for a, b in zip(red_folds, folds)),
            "iterations": [f.iterations for f in red_folds], "K": K}


def greenhill_cases(quick: bool) -> list[dict]:
    cases = [("clamped", 1e2, 1e4), ("clamped", 1e4, 1e4), ("pinned", 1e4, 1e4)]
    if not quick:
        cases += [("clamped", 1e3, 1e4), ("pinned", 1e3, 1e4), ("clamped", 1e4, 1e3)]
    out = []
    for support, G, A in cases:
        ref = jr.greenhill(G, support, A=A, n=160)
        per_n = {n: jr.greenhill(G, support, A=A, n=n) for n in (16, 24, 32, 40, 48, 64, 96)}
        ok = [n for n, r in per_n.items()
              if abs(r.beta0 - ref.beta0) <= 1e-10 * abs(ref.beta0)
              and abs((A + r.beta0) - (A + ref.beta0)) <= 1e-10 * abs(A + ref.beta0)]
        row = {"support": support, "G": G, "A": A, "beta0": ref.beta0,
               "margin": A + ref.beta0, "stable": ref.stable, "criticality": ref.criticality,
               "N_for_1e-10": min(ok) if ok else None,
               "default_N": jr.greenhill(G, support, A=A).n}
        out.append(row)
        print(f"Greenhill {support} G={G:g} A={A:g}: beta0 = {ref.beta0:.10g}, margin "
              f"{row['margin']:.6g}, N for 1e-10: {row['N_for_1e-10']}", flush=True)
    return out


def write(result: dict, out: Path) -> None:
    (out / "extreme.json").write_text(json.dumps(result, indent=2))
    lines = ["# Stiff and extreme cases", "", "Permanent magnet:", "",
             "| case | folds (alpha deg, tip deg) | N for 1e-10 deg | Moore-Spence iterations | "
             "converged | reduced route (max diff deg, K) |", "|---|---|---|---|---|---|"]
    for r in result["rows"]:
        folds = "; ".join(f"{f['kind']} {f['alpha_deg']:.8f} ({f['tip_deg']:.2f})"
                          for f in r["folds"]) or r.get("message", "")
        red = r["reduced"]
        red_text = red.get("message") or (
            f"{red['max_difference_deg']:.1e}, K = " + ", ".join(f"{k:.3g}" for k in red["K"])
            + ("" if red["converged"] else " (NOT converged)"))
        lines.append(f"| {r['case']} | {folds} | {r['N_for_1e-10_deg']} | "
                     f"{r['moore_spence_iterations']} | {r['converged']} | {red_text} |")
    lines += ["", "Greenhill:", "", "| support | G | A | beta0 | A + beta0 | N for 1e-10 rel | "
              "default N |", "|---|---|---|---|---|---|---|"]
    for g in result["greenhill"]:
        lines.append(f"| {g['support']} | {g['G']:g} | {g['A']:g} | {g['beta0']:.10g} | "
                     f"{g['margin']:.8g} | {g['N_for_1e-10']} | {g['default_N']} |")
    (out / "extreme.md").write_text("\n".join(lines) + "\n")


def main(argv=None) -> int:
    return benchmark_main(__doc__, run, write, argv)


if __name__ == "__main__":
    sys.exit(main())
