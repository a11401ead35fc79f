"""Conditioning of the full, bordered, Moore-Spence, mean-zero and reduced systems as the
folds of the paper's two experiments are approached (jaxrod.magnet.conditioning).

The paper claims the full Newton solve is ill-conditioned near a fold and the reduced one is
not; this measures both, and where Moore-Spence and the pseudo-arclength corrector stand.

Run:  python benchmarks/conditioning.py [--quick]
Writes benchmarks/results/conditioning.{json,md,png}.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from common import benchmark_main, write_results

import jaxrod as jr
from jaxrod.plotting import CONDITIONING_LABELS

D_EXP = 11.25 / 9.2
CASES = {"E = 200 GPa": (2.2, 0.0236), "E = 100 GPa": (4.4, 0.0472)}


def run(quick: bool) -> dict:
    offsets = np.logspace(-6, -1, 6 if quick else 16)
    studies = {}
    for case, (G, M) in CASES.items():
        scene = jr.magnet_scene(G, M, D_EXP)
        for fold in jr.reduced_folds(scene):
            if quick and fold.kind == "lower":
                continue
            # the side of the fold towards the straight rod (engaged branch for the upper fold)
            side = -1.0 if fold.kind == "upper" else 1.0
            title = f"{case}, {fold.kind} fold (alpha* = {fold.alpha_deg:.4f} deg)"
            studies[title] = jr.conditioning_near_fold(scene, fold, offsets=offsets, side=side)
            print(title, flush=True)
    return studies


def markdown(studies: dict) -> str:
    lines = ["# Condition numbers approaching the folds", "",
             "2-norm condition numbers at branch points q = q* -+ dq (N = 16); the distance is "
             "|alpha - alpha*|.", ""]
    keys = list(CONDITIONING_LABELS)
    for title, c in studies.items():
        lines += [f"## {title}", "",
                  "| |alpha - alpha*| (deg) | " + " | ".join(CONDITIONING_LABELS[k] for k in keys)
                  + " |", "|" + "---|" * (len(keys) + 1)]
        for i, d in enumerate(c["distance_deg"]):
            lines.append(f"| {d:.2e} | " + " | ".join(f"{c[k][i]:.3g}" for k in keys) + " |")
        grow = np.log(c["full"][0] / c["full"][-1]) / np.log(c["distance_deg"][0]
                                                              / c["distance_deg"][-1])
        lines += ["", f"full Newton: cond ~ distance^{grow:.2f}; reduced: "
                  f"{min(c['reduced']):.3g} .. {max(c['reduced']):.3g}; Moore-Spence: "
                  f"{min(c['moore_spence']):.3g} .. {max(c['moore_spence']):.3g}", ""]
    return "\n".join(lines)


def write(studies: dict, out: Path) -> None:
    write_results(out, "conditioning", studies, markdown(studies),
                  jr.conditioning_figure(studies))


def main(argv=None) -> int:
    return benchmark_main(__doc__, run, write, argv, quick_help="one fold per case, 6 offsets")


if __name__ == "__main__":
    sys.exit(main())
