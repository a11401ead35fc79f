"""Batched small dense solves: LAPACK's LU (``jnp.linalg.solve``, one call per matrix under
vmap on a CPU) against Gaussian elimination with partial pivoting written in jnp (one
vectorised rank-1 update over the whole batch per column), for the 13-50 unknowns of the
fold systems (m + 1 for the minimally augmented system, 2m + 1 for Moore-Spence).

The solver the package uses is the faster one on each backend measured here; on the CPU
that is LAPACK (benchmarks/results/dense_solve.md).

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

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import benchmark_main, write_results  # noqa: E402


def eliminate(A, b):
    """x = A^-1 b by Gaussian elimination with partial pivoting, batched over the leading
    axes of A (..., n, n) and b (..., n) with jnp operations only."""
    n = A.shape[-1]
    M = jnp.concatenate([A, b[..., None]], axis=-1)
    rows = jnp.arange(n)

    def column(k, M):
        size = jnp.where(rows >= k, jnp.abs(M[..., :, k]), -1.0)
        pivot = jnp.argmax(size, axis=-1)
        row_p = jnp.take_along_axis(M, pivot[..., None, None] * jnp.ones((1, n + 1), int),
                                    axis=-2)
        row_k = jax.lax.dynamic_slice_in_dim(M, k, 1, axis=-2)
        is_p = (rows == pivot[..., None])[..., None]
        M = jnp.where((rows == k)[:, None], row_p, jnp.where(is_p, row_k, M))
        factor = jnp.where(rows > k, M[..., :, k] / M[..., k, k][..., None], 0.0)
        return M - factor[..., :, None] * jax.lax.dynamic_slice_in_dim(M, k, 1, axis=-2)

    M = jax.lax.fori_loop(0, n, column, M)
    U, y = M[..., :n], M[..., n]

    def back(i, x):
        k = n - 1 - i
        return x.at[..., k].set((y[..., k] - jnp.sum(U[..., k, :] * x, axis=-1)) / U[..., k, k])

    return jax.lax.fori_loop(0, n, back, jnp.zeros_like(y))


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
    lapack = jax.jit(lambda A, b: jnp.linalg.solve(A, b[..., None])[..., 0])
    vectorised = jax.jit(eliminate)
    rows = []
    for n in (13, 25) if quick else (13, 25, 33, 50):
        for batch in (1000,) if quick else (1, 1000, 10000):
            for dtype in ("float64", "float32"):
                A = rng.standard_normal((batch, n, n)) + n * np.eye(n)
                b = rng.standard_normal((batch, n))
                A, b = jnp.asarray(A, dtype), jnp.asarray(b, dtype)
                t_lapack, t_vec = _best(lapack, A, b), _best(vectorised, A, b)
                diff = float(jnp.max(jnp.abs(lapack(A, b) - vectorised(A, b))))
                rows.append({"n": n, "batch": batch, "dtype": dtype, "lapack_s": t_lapack,
                             "vectorised_s": t_vec, "max_difference": diff})
                print(rows[-1], flush=True)
    return {"device": f"{jax.devices()[0].device_kind} ({jax.default_backend()})",
            "rows": rows}


def write(res: dict, out: Path) -> None:
    lines = ["# Batched small dense solves", "", f"Device: {res['device']}", "",
             "| n | batch | dtype | LAPACK LU ms | jnp elimination ms | faster |",
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
