"""Accuracy against wall time for the snap: diffrax's implicit Runge-Kutta solvers against
jaxrod's own integrators (the variational midpoint rule, the energy-conserving discrete
gradient, BDF2 at fixed steps and BDF2 with adaptive steps), to choose the integrator
(docs/dynamics.md).

The problem: the paper's rig (G = 2.2, M = 0.0236, D = 11.25 / 9.2, N = 16) released at
rest from its upper fold with the magnet 0.1 degrees past it, drag c = 1.1 (air), over
6 time units T (the snap and its first ringing). For diffrax the rod's Lagrange equations
are a first-order system in y = (q, v),

    M(q) v' = dT/dq - (dp/dq) v - grad E(q) - c M(q) v,   p = M(q) v,

(M the mass matrix of the kinetic energy, ``jaxrod.dynamics.modes``), solved by Cholesky at
each evaluation; its stiff solvers (Kvaerno3/5, ESDIRK with embedded error estimates,
Newton on the whole vector field's Jacobian, and KenCarp4, the additive IMEX pair run with
the whole field in its implicit part) with a PID step controller at rtol = atol = tol.
The error is the largest difference of the tip's angle (degrees) on 601 times from a
reference: the variational midpoint rule at dt = 0.0005 and 0.001 extrapolated by Richardson
(fourth order; its own error estimated from dt = 0.001 and 0.002, and Kvaerno5's rows
converge to it independently). (scipy's Radau on the same system, with its Jacobian by
autodiff, took 130 s at tol 1e-6: its per-call overhead on a 32-unknown system.) Each
method is timed warm (the second call of its compiled program); its first call,
compilation included, is printed too. A method whose run takes over 30 s is not run
at tighter tolerances.

diffrax is installed (pip, without its own jax) into ``benchmarks/.peers/diffrax`` if the
running Python lacks it.

Run:  python benchmarks/diffrax_peer.py [--quick]
Writes benchmarks/results/diffrax_peer.{json,md,png}.
"""

from __future__ import annotations

import argparse
import json
import math
import subprocess
import sys
import time
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np

import jaxrod as jr
from jaxrod.dynamics.lagrangian import kinetic
from jaxrod.dynamics.modes import mass_matrix
from jaxrod.equilibria.equilibrium import FIXED, discretise, tip

HERE = Path(__file__).resolve().parent
PEER = HERE / ".peers" / "diffrax"
N, C, T_END, PAST = 16, 1.1, 6.0, math.radians(0.1)
GRID = np.linspace(0.0, T_END, 601)


def import_diffrax():
    try:
        import diffrax
    except ImportError:
        if not PEER.exists():
            print(f"installing diffrax into {PEER} ...", flush=True)
            subprocess.run([sys.executable, "-m", "pip", "install", "-q", "--target", str(PEER),
                            "diffrax"], check=True)
            for extra in ("jax", "jaxlib", "numpy", "scipy", "ml_dtypes", "opt_einsum"):
                for p in PEER.glob(f"{extra}*"):  # the running Python's own are used
                    subprocess.run(["rm", "-rf", str(p)], check=True)
        sys.path.append(str(PEER))
        import diffrax
    return diffrax


def problem():
    scene = jr.Scene({"bending": jr.Bending(), "gravity": jr.Gravity(2.2),
                      "magnet": jr.Dipole(0.0236, 11.25 / 9.2, 0.0)})
    fold = max(jr.folds(scene, "magnet.alpha", 0.0, math.pi / 2, n=N),
               key=lambda f: f.value)
    return scene.replace("magnet.alpha", fold.value + PAST), fold


def vector_field(scene, disc):
    def f(t, y, args):
        q, v = jnp.split(y, 2)
        M = mass_matrix(scene, q, disc)
        p_of_q = lambda x: jax.grad(lambda w: kinetic(scene, disc, x, w))(v)  # noqa: E731
        dpdq_v = jax.jvp(p_of_q, (q,), (v,))[1]
        dTdq = jax.grad(lambda x: kinetic(scene, disc, x, v))(q)
        rhs = dTdq - dpdq_v - FIXED.gradient(q, 0.0, (scene, disc)) - C * (M @ v)
        return jnp.concatenate([v, jax.scipy.linalg.cho_solve(jax.scipy.linalg.cho_factor(M),
                                                              rhs)])
    return f


def diffrax_run(diffrax, scene, disc, q0, solver, tol):
    term = diffrax.ODETerm(vector_field(scene, disc))
    if isinstance(solver, diffrax.AbstractImplicitSolver) and \
            type(solver).__name__.startswith("KenCarp"):  # IMEX: the whole field implicit
        term = diffrax.MultiTerm(diffrax.ODETerm(lambda t, y, args: jnp.zeros_like(y)), term)

    @jax.jit
    def go(y0):
        sol = diffrax.diffeqsolve(term, solver, 0.0, T_END, 1e-3, y0,
                                  stepsize_controller=diffrax.PIDController(rtol=tol, atol=tol),
                                  saveat=diffrax.SaveAt(ts=jnp.asarray(GRID)),
                                  max_steps=200000)
        q = sol.ys[:, : q0.shape[0]]
        angle = jax.vmap(lambda x: tip(scene, x, disc)[0])(q)
        return jnp.degrees(angle), sol.stats["num_accepted_steps"], sol.result == \
            diffrax.RESULTS.successful

    y0 = jnp.concatenate([q0, jnp.zeros_like(q0)])
    t0 = time.perf_counter()
    jax.block_until_ready(go(y0))
    first = time.perf_counter() - t0
    t0 = time.perf_counter()
    angle, steps, ok = jax.block_until_ready(go(y0))
    return np.asarray(angle), int(steps), bool(ok), time.perf_counter() - t0, first


def richardson_reference(scene, q0, dt):
    """The tip's angle on GRID, (4 A(dt / 2) - A(dt)) / 3 for the variational midpoint
    rule's A (symmetric: its error is even in dt, so this is fourth order)."""
    fine, coarse = (jaxrod_run(scene, q0, dt=h, scheme="midpoint")[0] for h in (dt / 2, dt))
    return (4.0 * fine - coarse) / 3.0


def jaxrod_run(scene, q0, **kw):
    t0 = time.perf_counter()
    jr.simulate(scene, q0, T_END, n=N, damping=C, **kw)
    first = time.perf_counter() - t0
    t0 = time.perf_counter()
    tr = jr.simulate(scene, q0, T_END, n=N, damping=C, **kw)
    wall = time.perf_counter() - t0
    angle = np.interp(GRID, np.r_[0.0, tr.time], np.r_[tr.tip_angle_deg[0], tr.tip_angle_deg])
    return angle, len(tr.time), tr.converged, wall, first


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args()
    diffrax = import_diffrax()
    scene, fold = problem()
    disc = discretise(scene, N)
    q0 = jnp.asarray(fold.state)
    ref = np.array(richardson_reference(scene, q0, 0.001))
    check = np.array(richardson_reference(scene, q0, 0.002))
    ref[0] = check[0] = fold.tip_angle_deg
    print(f"reference: the midpoint rule at dt = 0.0005, 0.001 extrapolated; against 0.001, "
          f"0.002: {np.max(np.abs(ref - check)):.2e} deg")
    tols = [1e-4, 1e-6] if args.quick else [1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8]
    dts = [0.04, 0.01, 0.0025] if args.quick else [0.04, 0.02, 0.01, 0.005, 0.0025]
    cases = []
    for name, solver in (("diffrax Kvaerno3", diffrax.Kvaerno3()),
                         ("diffrax Kvaerno5", diffrax.Kvaerno5()),
                         ("diffrax KenCarp4", diffrax.KenCarp4())):
        for tol in tols:
            cases.append((name, f"tol {tol:g}",
                          lambda s=solver, t=tol: diffrax_run(diffrax, scene, disc, q0, s, t)))
    for dt in dts:
        cases.append(("jaxrod midpoint", f"dt {dt:g}",
                      lambda d=dt: jaxrod_run(scene, q0, dt=d, scheme="midpoint")))
        cases.append(("jaxrod BDF2", f"dt {dt:g}",
                      lambda d=dt: jaxrod_run(scene, q0, dt=d, scheme="bdf2")))
        cases.append(("jaxrod discrete gradient", f"dt {dt:g}",
                      lambda d=dt: jaxrod_run(scene, q0, dt=d, scheme="discrete-gradient")))
    for tol in tols:
        cases.append(("jaxrod BDF2 adaptive", f"tol {tol:g}",
                      lambda t=tol: jaxrod_run(scene, q0, dt=1e-3, scheme="bdf2", tol=t,
                                               dt_max=0.5)))
    rows, slow = [], set()
    for method, setting, run in cases:
        if method in slow:  # its last run took over 30 s: no tighter runs
            continue
        angle, steps, ok, wall, first = run()
        if wall > 30.0:
            slow.add(method)
        angle = np.array(angle)
        angle[0] = fold.tip_angle_deg
        err = float(np.max(np.abs(angle - ref)))
        rows.append({"method": method, "setting": setting, "steps": steps, "ok": ok,
                     "error_deg": err, "wall_s": wall, "first_call_s": first})
        print(f"{method:22s} {setting:10s} steps {steps:6d}  error {err:9.2e} deg  warm "
              f"{wall:8.4f} s  first call {first:6.2f} s  {'ok' if ok else 'FAILED'}",
              flush=True)
    out = HERE / "results"
    (out / "diffrax_peer.json").write_text(json.dumps(
        {"rows": rows, "reference_check_deg": float(np.max(np.abs(ref - check))),
         "quick": args.quick, "N": N, "drag": C, "t_end": T_END}, indent=1))
    lines = ["# The snap's accuracy against wall time: diffrax against jaxrod's integrators",
             "", f"The paper's rig from its upper fold, 0.1 deg past it, drag {C}, {T_END} T, "
             f"N = {N}. Error: the largest difference of the tip's angle from the midpoint rule "
             "at dt = 0.0005, 0.001 extrapolated by Richardson (itself within "
             f"{np.max(np.abs(ref - check)):.1e} deg of dt = 0.001, 0.002). "
             "Warm: the second call of the compiled program.", "",
             "| method | setting | steps | error (deg) | warm (s) | first call (s) |",
             "|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['method']} | {r['setting']} | {r['steps']} | "
                     f"{r['error_deg']:.2e} | {r['wall_s']:.4f} | {r['first_call_s']:.2f} |")
    (out / "diffrax_peer.md").write_text("\n".join(lines) + "\n")
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 5))
    for k, method in enumerate(dict.fromkeys(r["method"] for r in rows)):
        rs = [r for r in rows if r["method"] == method and r["ok"]]
        ax.loglog([r["wall_s"] for r in rs], [r["error_deg"] for r in rs], "o-",
                  color=f"C{k}", label=method)
    ax.set_xlabel("wall time, warm (s)")
    ax.set_ylabel("max tip-angle error (deg)")
    ax.set_title(f"the snap, {T_END:g} T (N = {N})")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out / "diffrax_peer.png", dpi=130)


if __name__ == "__main__":
    main()
