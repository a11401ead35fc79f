"""Does the batch path ever miss a fold pair? ``jr.fold_pairs`` against ``locate_folds``
(continuation of the whole diagram, then Moore-Spence; same N = 12) on three sets:

1. the paper's G = 2.2, M = 0.0236 with 2501 clearances D in [1.05, 1.30] (the last release
   reported 78 of them "not converged": a window D = 1.1898-1.1922 and scattered sets);
2. a 100 x 100 map over D in [1.05, 1.35] and M in [0.015, 0.035] (both sides of the cusp);
3. 10,000 random sets of the design ranges: the paper's wire and magnet with E uniform in
   80-250 GPa, track radius in 0.095-0.14 m and remanence within +-10 %.

A set is bistable for ``locate_folds`` when it finds exactly a lower and an upper fold with
0 < alpha <= 90 degrees; it is unsure where it reports a problem (not converged: near a
cusp, two folds may hide within its finest step). Every set is counted as agreeing (both
bistable with the same folds to 1e-9 degrees, both sure there is no pair, or both unsure:
``fold_pairs`` NOT_CONVERGED), missed (locate_folds bistable, fold_pairs not), spurious
(fold_pairs bistable, locate_folds not), off (both bistable, folds further apart) or unknown
(fold_pairs NOT_CONVERGED where locate_folds is sure); the target is zero of each but the
first. Which tier of ``fold_pairs`` answered is counted too.

Throughput, side by side in one run: ``fold_pairs`` (all tiers), its tier 1 alone
(``fold_pairs_program``) and the previous release's batch path (its ``batch.py`` taken from
git, where the repository is there), on K = 1000 sets of the throughput benchmark's
(E uniform in 80-250 GPa at the paper's D), best of 5.

Run:  python benchmarks/fold_pair_coverage.py [--quick]
Writes benchmarks/results/fold_pair_coverage.{json,md}.
"""

from __future__ import annotations

import importlib.util
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import jax
import numpy as np
from common import benchmark_main, write_results

import jaxrod as jr
from jaxrod.design_point import groups_of
from jaxrod.magnet.batch import NOT_CONVERGED, fold_pairs_program
from jaxrod.params import NDFEB_MAGNET
from jaxrod.programs import padded

N = 12
TOL_DEG = 1e-9
#: The release before the fallback tiers, for the side-by-side throughput.
PREVIOUS = "b8c045f"
REPO = Path(__file__).resolve().parent.parent


def reference(G, M, D) -> tuple[np.ndarray, np.ndarray]:
    """(K, 2) folds of ``locate_folds`` in degrees, NaN where it finds no pair in (0, 90],
    and (K,) whether it is sure (converged, no problem reported)."""
    out, sure = np.full((len(G), 2), np.nan), np.ones(len(G), bool)
    for i, (g, m, d) in enumerate(zip(G, M, D)):
        rep = jr.folds(jr.magnet_scene(float(g), float(m), float(d)), n=N, throw=False)
        kinds = {f.kind: f.alpha_deg for f in rep.folds}
        sure[i] = rep.converged
        if rep.converged and {"lower", "upper"} <= kinds.keys() \
                and 0.0 < kinds["lower"] and kinds["upper"] <= 90.0:
            out[i] = kinds["lower"], kinds["upper"]
    return out, sure


def compare(name: str, G, M, D) -> dict:
    t0 = time.perf_counter()
    got = jr.fold_pairs(G, M, D, n=N)
    t_batch = time.perf_counter() - t0
    t0 = time.perf_counter()
    ref, sure = reference(G, M, D)
    t_ref = time.perf_counter() - t0
    ref_pair = np.isfinite(ref[:, 0])
    unsure = got.status == NOT_CONVERGED
    both = got.bistable & ref_pair
    diff = np.max(np.abs(got.alpha_deg - ref), axis=1)
    agree = (both & (diff <= TOL_DEG)) | (~got.bistable & ~unsure & ~ref_pair & sure) \
        | (unsure & ~sure)
    counts = {
        "sets": int(len(G)),
        "bistable_locate_folds": int(ref_pair.sum()),
        "bistable_fold_pairs": int(got.bistable.sum()),
        "locate_folds_unsure": int(np.sum(~sure)),
        "agree": int(agree.sum()),
        "missed": int(np.sum(ref_pair & ~got.bistable & ~unsure)),
        "spurious": int(np.sum(got.bistable & ~ref_pair)),
        "off": int(np.sum(both & (diff > TOL_DEG))),
        "unknown": int(np.sum(unsure & sure)),
    }
    bad = np.nonzero(~agree)[0]
    row = {"name": name, **counts,
           "max_difference_deg": float(np.nanmax(np.where(both, diff, np.nan)))
           if both.any() else None,
           "tiers": {str(t): int(np.sum(got.tier == t)) for t in (1, 2, 3, 4)},
           "status": {str(s): int(np.sum(got.status == s)) for s in range(5)},
           "fold_pairs_s": t_batch, "locate_folds_s": t_ref,
           "disagreements": [{"G": float(G[i]), "M": float(M[i]), "D": float(D[i]),
                              "fold_pairs": got.alpha_deg[i].tolist(),
                              "status": int(got.status[i]),
                              "locate_folds": ref[i].tolist()} for i in bad[:20]]}
    print({k: v for k, v in row.items() if k != "disagreements"}, flush=True)
    return row


def design_ranges(K: int, seed: int = 0):
    rng = np.random.default_rng(seed)
    values = np.tile(np.array(jr.default_point().values), (K, 1))
    values[:, 0] = rng.uniform(80e9, 250e9, K)  # E
    values[:, 6] = NDFEB_MAGNET.remanence * rng.uniform(0.9, 1.1, K)
    values[:, 8] = rng.uniform(0.095, 0.14, K)  # track radius
    return groups_of("physical", values.T)


def previous_release():
    """The previous release's batch module (from git), or None where git or the commit is
    not there."""
    try:
        text = subprocess.run(["git", "-C", str(REPO), "show",
                               f"{PREVIOUS}:jaxrod/magnet/batch.py"], capture_output=True,
                              text=True, check=True, timeout=60).stdout
    except (OSError, subprocess.SubprocessError):
        return None
    path = Path(tempfile.mkdtemp()) / "previous_batch.py"
    path.write_text(text)
    spec = importlib.util.spec_from_file_location("previous_batch", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def best_of(paths: dict, repeat: int) -> dict:
    """The best time of each path over ``repeat`` rounds, the paths taking turns in each
    round (so that a slow spell of a shared machine falls on all of them)."""
    for fn in paths.values():
        jax.block_until_ready(fn())
    best = dict.fromkeys(paths, float("inf"))
    for _ in range(repeat):
        for name, fn in paths.items():
            t0 = time.perf_counter()
            jax.block_until_ready(fn())
            best[name] = min(best[name], time.perf_counter() - t0)
    return best


def throughput(K: int, repeat: int, previous: bool = True) -> dict:
    """One row of the throughput table: pairs/s of each path at batch size K."""
    E = np.random.default_rng(0).uniform(80.0, 250.0, K)
    G, M, D = 2.2 * 200.0 / E, 0.0236 * 200.0 / E, np.full(K, 11.25 / 9.2)
    # tier 1 alone on the padded batch that ``fold_pairs`` gives it, called as it calls it
    # (the same program: compiled once)
    batch = padded([G, M, D])
    paths = {"fold_pairs (all tiers)": lambda: jr.fold_pairs(G, M, D).alpha_deg,
             "tier 1 alone (fold_pairs_program)":
                 lambda: fold_pairs_program(*batch, n=N, dtype="float64")}
    old = previous_release() if previous else None
    if old is not None:
        paths[f"previous release ({PREVIOUS}) fold_pairs"] = lambda: old.fold_pairs(G, M, D)
    rows = best_of(paths, repeat)
    out = {"K": K, "repeat": repeat, "seconds": rows,
           "pairs_per_s": {k: K / v for k, v in rows.items()}}
    print(out, flush=True)
    return out


def run(quick: bool) -> dict:
    k_sweep, k_map, k_random = (41, 6, 60) if quick else (2501, 100, 10_000)
    rows = []
    D = np.linspace(1.05, 1.30, k_sweep)
    rows.append(compare(f"paper's G, M; {k_sweep} D in [1.05, 1.30]", np.full(k_sweep, 2.2),
                        np.full(k_sweep, 0.0236), D))
    Dm, Mm = np.meshgrid(np.linspace(1.05, 1.35, k_map), np.linspace(0.015, 0.035, k_map))
    rows.append(compare(f"{k_map} x {k_map} map, D in [1.05, 1.35], M in [0.015, 0.035]",
                        np.full(Dm.size, 2.2), Mm.ravel(), Dm.ravel()))
    G, M, Dr = design_ranges(k_random)
    rows.append(compare(f"{k_random} random sets of the design ranges", G, M, Dr))
    return {"device": f"{jax.devices()[0].platform}, jax {jax.__version__}", "n": N,
            "tolerance_deg": TOL_DEG, "rows": rows,
            "throughput": [throughput(K, 2 if quick else 15, previous=not quick)
                           for K in ((200,) if quick else (1000, 1024))]}


def markdown(res: dict) -> str:
    lines = ["# Fold-pair coverage: `fold_pairs` against `locate_folds`", "",
             f"N = {res['n']}; agreement to {res['tolerance_deg']:g} deg; {res['device']}.", "",
             "| sets | bistable (locate_folds / fold_pairs) | locate_folds unsure | agree | "
             "missed | spurious | off | unknown | max difference (deg) | tiers 1/2/3/4 | "
             "fold_pairs s | locate_folds s |", "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in res["rows"]:
        tiers = "/".join(str(r["tiers"][str(t)]) for t in (1, 2, 3, 4))
        diff = "-" if r["max_difference_deg"] is None else f"{r['max_difference_deg']:.1e}"
        lines.append(f"| {r['name']} | {r['bistable_locate_folds']} / "
                     f"{r['bistable_fold_pairs']} | {r['locate_folds_unsure']} | "
                     f"{r['agree']} | {r['missed']} | "
                     f"{r['spurious']} | {r['off']} | {r['unknown']} | {diff} | {tiers} | "
                     f"{r['fold_pairs_s']:.3g} | {r['locate_folds_s']:.3g} |")
    rows = res["throughput"]
    lines += ["", f"Throughput (pairs/s, best of {rows[0]['repeat']}, the paths taking turns; "
              "K = 1000 is padded to 1024 by the batch-size buckets):", "",
              "| path | " + " | ".join(f"K = {t['K']}" for t in rows) + " |",
              "|---|" + "---|" * len(rows)]
    lines += [f"| {k} | " + " | ".join(f"{t['pairs_per_s'][k]:.4g}" for t in rows) + " |"
              for k in rows[0]["pairs_per_s"]]
    bad = [d for r in res["rows"] for d in r["disagreements"]]
    if bad:
        lines += ["", "Disagreements (first 20 per set):", ""]
        lines += [f"- G = {d['G']:.6g}, M = {d['M']:.6g}, D = {d['D']:.6g}: fold_pairs "
                  f"{d['fold_pairs']} (status {d['status']}), locate_folds {d['locate_folds']}"
                  for d in bad]
    return "\n".join(lines) + "\n"


def write(res: dict, out: Path) -> None:
    write_results(out, "fold_pair_coverage", res, markdown(res))


def main(argv=None) -> int:
    return benchmark_main(__doc__, run, write, argv)


if __name__ == "__main__":
    sys.exit(main())
