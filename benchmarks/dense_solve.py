"""Batched small dense solves: LAPACK's LU (``jnp.linalg.solve``, one call per matrix under
vmap on a CPU) against the package's LU with partial pivoting written in jnp
(``jaxrod.solvers.dense``, columns unrolled, rows left in place), for the 2-50 unknowns of
the fold systems (2 for the one-mode fold, m + 1 = 13 for the bordered Moore-Spence step and
the mode's KKT system, 2m + 1 for the assembled Moore-Spence Jacobian).

The batched fold-pair path uses the jnp LU although LAPACK is faster on a CPU at most sizes:
LAPACK's batched LU blocks on XLA's intra-op thread pool, and two programs running at once
(two CPU devices, or two dispatches) hang there (``jaxrod/solvers/dense.py``).

Run:  python benchmarks/dense_solve.py [--quick]
Writes benchmarks/results/dense_solve.{json,md}.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np

import jaxrod  # noqa: F401  (float64)
from jaxrod.programs import jit
from jaxrod.solvers import dense

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import benchmark_main, write_results  # noqa: E402


def _best(f, *args, repeat=7) -> float:
    jax.block_until_ready(f(*args))
    best = float("inf")
    for _ in range(repeat):
        t = time.perf_counter()
        jax.block_until_ready(f(*args))
        best = min(best, time.perf_counter() - t)
    return best


def run(quick: bool) -> dict:
    rng = np.random.default_rng(0)
    lapack = jit(lambda A, b: jnp.linalg.solve(A, b[..., None])[..., 0])
    vectorised = jit(jax.vmap(dense.solve))
    rows = []
    for n in (2, 13, 25) if quick else (2, 13, 25, 33, 50):
        for batch in (1000,) if quick else (1, 1000, 10000):
            for dtype in ("float64", "float32"):
                A = rng.standard_normal((batch, n, n)) + (n + 4) * np.eye(n)  # well conditioned
                b = rng.standard_normal((batch, n))
                A, b = jnp.asarray(A, dtype), jnp.asarray(b, dtype)
                t_lapack, t_vec = _best(lapack, A, b), _best(vectorised, A, b)
                x = lapack(A, b)  # difference relative to the solution's size
                diff = float(jnp.max(jnp.abs(x - vectorised(A, b))) / jnp.max(jnp.abs(x)))
                rows.append({"n": n, "batch": batch, "dtype": dtype, "lapack_s": t_lapack,
                             "vectorised_s": t_vec, "max_difference": diff})
                print(rows[-1], flush=True)
    return {"device": f"{jax.devices()[0].device_kind} ({jax.default_backend()})",
            "rows": rows}


def write(res: dict, out: Path) -> None:
    lines = ["# Batched small dense solves", "", f"Device: {res['device']}", "",
             "| n | batch | dtype | LAPACK LU ms | jnp LU (jaxrod.solvers.dense) ms | faster |",
             "|---|---|---|---|---|---|"]
    for r in res["rows"]:
        faster = "LAPACK" if r["lapack_s"] <= r["vectorised_s"] else "jnp"
        lines.append(f"| {r['n']} | {r['batch']} | {r['dtype']} | {1e3 * r['lapack_s']:.3f} | "
                     f"{1e3 * r['vectorised_s']:.3f} | {faster} |")
    write_results(out, "dense_solve", res, "\n".join(lines))


def main(argv=None) -> int:
    return benchmark_main(__doc__, run, write, argv, quick_help="n = 13, 25; batch 1000")


if __name__ == "__main__":
    sys.exit(main())
