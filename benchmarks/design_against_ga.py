"""A design for a target shape by jaxrod's exact gradients, against what users do: a genetic
algorithm (scipy's differential_evolution) and least squares with finite-difference gradients
(scipy's least_squares, 2-point), on the same problem and the same forward model.

The problem: a hard-magnetic cantilever (load 2, field at 90 degrees) whose remanence
strength along s is mu(s) = sum_k d_k T_k(2 s - 1), K coefficients free; the target is the
tangent angle at 21 points of the shape of a known profile d* (computed by jaxrod at the same
N). The peers call one compiled forward model (Newton from the uniform rod's equilibrium, the
equilibrium of the scene at d: one program, warm), so the columns compare the searches, not
the models. Each row: evaluations of the forward model (jaxrod: its least-squares
iterations, each one equilibrium solve and its implicit tangents), wall time (warm, best of
the repeats) and the final largest shape error.

Run:  python benchmarks/design_against_ga.py [--quick]
Writes benchmarks/results/design_against_ga.json and .md.
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
from common import benchmark_main, write_results
from scipy.optimize import differential_evolution, least_squares

import jaxrod as jr
from jaxrod import spectral
from jaxrod.equilibria.equilibrium import MODEL, discretise
from jaxrod.scenes.path import along

N = 16
TRUE = np.array([1.0, 0.3, -0.1, 0.05, 0.02, -0.01, 0.005, -0.003, 0.002, -0.001])
RIG = """units = "nondimensional"
geometry = "planar"
[rod]
support = "clamped"
[magnetisation]
kind = "hard"
strength_profile = {profile}
[[field]]
kind = "uniform"
load = 2.0
angle_deg = 90.0
"""


def _problem(folder: Path, K: int):
    path = folder / "rig.toml"
    path.write_text(RIG.format(profile=[1.0] + [0.0] * (K - 1)))
    rig = jr.load_scene(str(path))
    keys = [f"magnetisation.strength_profile.{k}" for k in range(K)]
    p = along(rig, ("load_scale", *keys))
    disc = discretise(p.template, N)
    s = np.linspace(0.0, 1.0, 21)
    rows = jnp.asarray(spectral.interpolation_matrix(N, s) @ np.asarray(disc.to_full))
    x0 = jnp.asarray(jr.equilibrium(rig, n=N).state)

    @jax.jit
    def shape_deg(d):
        args = (p, disc, 1.0, 1.0, d)
        res = jr.newton(lambda x, a: MODEL.gradient(x, 0.0, a), x0, args, tol=1e-12,
                     jacobian=lambda x, a: MODEL.hessian(x, 0.0, a))
        return jnp.degrees(rows @ res.x), res.converged

    target, ok = shape_deg(jnp.asarray(TRUE[:K]))
    assert bool(ok)
    return rig, keys, s, np.asarray(target), shape_deg


def _timed(run, repeats: int):
    best, out = np.inf, None
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = run()
        best = min(best, time.perf_counter() - t0)
    return best, out


def run(quick: bool) -> dict:
    repeats = 1 if quick else 3
    return {"N": N, "quick": quick,
            "problems": [_compare(K, repeats, quick) for K in ((4,) if quick else (4, 10))]}


def _compare(K: int, repeats: int, quick: bool) -> dict:
    with tempfile.TemporaryDirectory() as tmp:
        rig, keys, s, target, shape_deg = _problem(Path(tmp), K)
        t0 = time.perf_counter()
        first = jr.design_shape(rig, keys, s, target, n=N)
        first_call = time.perf_counter() - t0
        t_jr, d = _timed(lambda: jr.design_shape(rig, keys, s, target, n=N), repeats)
        rows = [{"method": "jaxrod design_shape (exact gradients)", "evaluations":
                 d.iterations, "wall_s": t_jr, "shape_error_deg": d.shape_error_deg,
                 "converged": d.converged, "first_call_s": first_call}]
        count = {"n": 0}

        def residual(dv):
            count["n"] += 1
            theta, ok = shape_deg(jnp.asarray(dv))
            return np.asarray(theta) - target if bool(ok) else np.full(target.size, 1e3)

        def fd():
            count["n"] = 0
            return least_squares(residual, np.r_[1.0, np.zeros(K - 1)], jac="2-point",
                                 xtol=1e-15, ftol=1e-15, gtol=1e-15), count["n"]

        t_fd, (sol, n_fd) = _timed(fd, repeats)
        rows.append({"method": "scipy least_squares, finite differences", "evaluations": n_fd,
                     "wall_s": t_fd, "shape_error_deg": float(np.max(np.abs(
                         residual(sol.x)))), "converged": bool(sol.success)})

        def ga():
            count["n"] = 0
            out = differential_evolution(lambda dv: float(np.sum(residual(dv) ** 2)),
                                         [(0.0, 2.0)] + [(-1.0, 1.0)] * (K - 1), seed=0,
                                         maxiter=60 if quick else 400, tol=1e-14, polish=False)
            return out, count["n"]

        t_ga, (out, n_ga) = _timed(ga, 1)
        rows.append({"method": "scipy differential_evolution (a genetic algorithm)",
                     "evaluations": n_ga, "wall_s": t_ga, "shape_error_deg": float(np.max(
                         np.abs(residual(out.x)))), "converged": bool(out.success)})
    assert first.converged and d.converged
    return {"K": K, "points": int(s.size), "true": TRUE[:K].tolist(), "rows": rows}


def markdown(res: dict) -> str:
    lines = ["# A design for a target shape against a genetic algorithm and finite differences",
             "", f"A remanence strength profile of K Chebyshev coefficients for the shape (at "
             f"21 points) of a known profile, N = {res['N']}; the same compiled forward model "
             "for the peers (Newton from the uniform rod's equilibrium). Wall times warm; "
             "jaxrod's include its start and its checks (the ramped equilibria, the "
             "continued ramp and its eigenvalues).", ""]
    for pr in res["problems"]:
        jr_row = pr["rows"][0]
        lines += [f"K = {pr['K']} (jaxrod's first call, with compilation: "
                  f"{jr_row['first_call_s']:.2f} s)", "",
                  "| method | evaluations | wall time, s | largest shape error, deg | "
                  "x jaxrod's time |", "|---|---|---|---|---|"]
        for r in pr["rows"]:
            lines.append(f"| {r['method']} | {r['evaluations']} | {r['wall_s']:.3g} | "
                         f"{r['shape_error_deg']:.2e} | {r['wall_s'] / jr_row['wall_s']:.1f} |")
        lines.append("")
    return "\n".join(lines)


def write(res: dict, out: Path) -> None:
    write_results(out, "design_against_ga", res, markdown(res))


if __name__ == "__main__":
    raise SystemExit(benchmark_main(__doc__, run, write))
