"""Stiff and extreme permanent-magnet cases: converge, or fail with a message.

For each case: the fold angles at N = 8 ... 64, the smallest N whose folds agree with N = 64
to 1e-10 degrees, the Moore-Spence iterations, and the status of the continuation. Cases:
small clearance D - 1 (0.1, 0.05, 0.02), a strong magnet, tip angles above 60 degrees, the
E = 100 GPa upper fold, and parameters next to the cusp where the two folds merge (located
here by bisection on M); the last row shows the clear report when no fold exists.

Run:  python benchmarks/magnet_extreme.py [--quick]
Writes benchmarks/results/magnet_extreme.{json,md}.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import jaxrod  # noqa: F401
from jaxrod.analysis import magnet

HERE = Path(__file__).resolve().parent
D_EXP = 11.25 / 9.2


def fold_count(G, M, D, n=16):
    return len(magnet.locate_folds(magnet.make_scene(G, M, D), n=n).folds)


def cusp_magnet_group(G, D, lo=0.002, hi=0.0236, steps=30):
    """Smallest M (bisection) with two folds on the branch: the cusp at (G, D)."""
    for _ in range(steps):
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if fold_count(G, mid, D) == 2 else (mid, hi)
    return hi


def run(quick: bool) -> dict:
    degrees = [8, 16, 32] if quick else [8, 12, 16, 24, 32, 48]
    cases = [
        ("paper E=200", 2.2, 0.0236, D_EXP),
        ("E=100 (upper fold tip ~50 deg)", 4.4, 0.0472, D_EXP),
        ("clearance D-1=0.1 (tip ~60 deg)", 2.2, 0.0236, 1.1),
        ("clearance D-1=0.05 (tip ~74 deg)", 2.2, 0.0236, 1.05),
        ("clearance D-1=0.02, M scaled by (0.02/0.2228)^3", 2.2, 0.0236 * (0.02 / 0.2228) ** 3,
         1.02),
        ("strong magnet M=0.2", 2.2, 0.2, D_EXP),
    ]
    if not quick:
        m_cusp = cusp_magnet_group(2.2, D_EXP)
        print(f"cusp at G=2.2, D=11.25/9.2: M = {m_cusp:.10f}", flush=True)
        cases += [("cusp: M = 1.001 M_cusp", 2.2, 1.001 * m_cusp, D_EXP),
                  ("cusp: M = 0.999 M_cusp (no fold)", 2.2, 0.999 * m_cusp, D_EXP)]
    cases.append(("clearance D-1=0.02, M=0.0236 (engaged to 90 deg: no fold)", 2.2, 0.0236,
                  1.02))
    rows = []
    for name, G, M, D in cases:
        scene = magnet.make_scene(G, M, D)
        t0 = time.perf_counter()
        ref = magnet.locate_folds(scene, n=64)
        per_n = {}
        for n in degrees:
            rep = magnet.locate_folds(scene, n=n)
            per_n[n] = [f.alpha_deg for f in rep.folds]
        ok = [n for n, a in per_n.items() if len(a) == len(ref.folds)
              and all(abs(x - f.alpha_deg) <= 1e-10 for x, f in zip(a, ref.folds))]
        row = {
            "case": name, "G": G, "M": M, "D": D,
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
    return {"rows": rows}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--out", default=str(HERE / "results"))
    args = parser.parse_args(argv)
    result = run(args.quick)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "magnet_extreme.json").write_text(json.dumps(result, indent=2))
    lines = ["| case | folds (alpha deg, tip deg) | N for 1e-10 deg | Moore-Spence iterations | "
             "converged |", "|---|---|---|---|---|"]
    for r in result["rows"]:
        folds = "; ".join(f"{f['kind']} {f['alpha_deg']:.8f} ({f['tip_deg']:.2f})"
                          for f in r["folds"]) or r.get("message", "")
        lines.append(f"| {r['case']} | {folds} | {r['N_for_1e-10_deg']} | "
                     f"{r['moore_spence_iterations']} | {r['converged']} |")
    (out / "magnet_extreme.md").write_text("\n".join(lines) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
