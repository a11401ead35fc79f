"""Cost of 3D solves against planar ones at equal accuracy (permanent-magnet scene, E = 200 and
100 GPa, magnet in the experiment's plane).

For each Chebyshev degree N the same two solves run on the planar discretisation (theta) and
on the director discretisation (d3 on the sphere, twice the unknowns), from the same start:
  equilibrium  Newton at alpha = 35 deg from the equilibrium at 33 deg;
  fold         Moore-Spence for the upper fold from the nearest traced branch point.
Errors are against a planar N = 48 reference (tip angle at 35 deg; upper fold angle); the 3D
solution restricted to the plane is the planar one, so the two errors agree to round-off and
the comparison is of time at equal accuracy. Times are warm (compiled) medians; compile time
is the first call minus the warm time.

Run:  python benchmarks/three_d_cost.py [--quick]
Writes benchmarks/results/three_d_cost.{json,md,png}.
"""

from __future__ import annotations

import math
import platform
import time
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
from common import benchmark_main, write_results

import jaxrod as jr
from jaxrod.magnet import diagram as magnet
from jaxrod.programs import jit  # as jaxrod compiles its own programs

D_EXP = 11.25 / 9.2
CASES = {"200": (2.2, 0.0236), "100": (4.4, 0.0472)}
ALPHA, ALPHA_START = math.radians(35.0), math.radians(33.0)


def energy_3d(x, alpha, args):
    scene, disc = args
    return jr.DipoleMagnet3D(scene.G, scene.M, scene.D, jr.magnet_position(alpha)).energy(x, disc)


def _residual(energy):
    return lambda x, a: jax.grad(energy)(x, a[0], a[1:])


@jit
def equilibrium_planar(x0, scene, disc):
    return jr.newton(_residual(magnet.alpha_energy), x0, (ALPHA, scene, disc), tol=1e-13)


@jit
def equilibrium_3d(x0, scene, disc):
    return jr.newton(_residual(energy_3d), x0, (ALPHA, scene, disc), tol=1e-13)


@jit
def fold_planar(x0, a0, phi0, scene, disc):
    return jr.moore_spence_solve(magnet.alpha_energy, x0, a0, phi0, (scene, disc))


@jit
def fold_3d(x0, a0, phi0, scene, disc):
    return jr.moore_spence_solve(energy_3d, x0, a0, phi0, (scene, disc))


def _timed(fn, *args, repeats=5):
    t0 = time.perf_counter()
    out = jax.block_until_ready(fn(*args))
    first = time.perf_counter() - t0
    warm = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        jax.block_until_ready(fn(*args))
        warm.append(time.perf_counter() - t0)
    w = float(np.median(warm))
    return out, w, max(first - w, 0.0)


def _tip_3d(x, ddisc):
    d3, _ = ddisc.at_quadrature(x)
    X = ddisc.integrate(d3.T)
    return float(jnp.arctan2(jnp.hypot(X[0], X[1]), X[2]))


def _start_states(scene, n):
    """(theta at 33 deg, fold guess theta, alpha, null vector) on the planar grid of degree n."""
    disc = jr.planar_discretisation(n)
    branch = jr.diagram(scene, n)
    engaged = np.arange(len(branch))[branch.engaged]
    i = int(engaged[np.argmin(np.abs(branch.alpha[engaged] - ALPHA_START))])
    start = magnet._equilibrium(jnp.asarray(branch.theta[i]), ALPHA_START, scene, disc)
    f = [j for j in branch.fold_indices if branch.alpha[j] > 0]
    j = max(f, key=lambda k: branch.alpha[k])  # the upper fold
    H = jax.hessian(magnet.alpha_energy)(jnp.asarray(branch.theta[j]), branch.alpha[j],
                                         (scene, disc))
    return start.x, branch.theta[j], branch.alpha[j], np.linalg.eigh(np.asarray(H))[1][:, 0]


def run(quick: bool) -> dict:
    # (quick: N = 8, where the error is far above round-off, so that 3D = planar means
    # something)
    degrees = [8] if quick else [6, 8, 10, 12, 16, 20, 24, 32]
    rows = []
    for e_gpa, (G, M) in CASES.items():
        scene = jr.magnet_scene(G, M, D_EXP)
        ref_disc = jr.planar_discretisation(48)
        x0, xf, af, phi = _start_states(scene, 48)
        ref_tip = float(jr.tip_angle(equilibrium_planar(jnp.asarray(x0), scene, ref_disc).x,
                                  ref_disc))
        ref_fold = math.degrees(float(fold_planar(jnp.asarray(xf), af, jnp.asarray(phi), scene,
                                                  ref_disc).lam))
        for n in degrees:
            disc, ddisc = jr.planar_discretisation(n), jr.director_discretisation(n)
            x0, xf, af, phi = (jnp.asarray(v) for v in _start_states(scene, n))
            eq_p, t_eq_p, c_eq_p = _timed(equilibrium_planar, x0, scene, disc)
            eq_3, t_eq_3, c_eq_3 = _timed(equilibrium_3d, ddisc.from_planar(x0), scene, ddisc)
            fo_p, t_fo_p, c_fo_p = _timed(fold_planar, xf, af, phi, scene, disc)
            fo_3, t_fo_3, c_fo_3 = _timed(fold_3d, ddisc.from_planar(xf), af,
                                          ddisc.from_planar(phi), scene, ddisc)
            row = {
                "E_GPa": int(e_gpa), "N": n, "unknowns_planar": disc.size,
                "unknowns_3d": ddisc.size,
                "equilibrium_error_planar_deg": abs(math.degrees(
                    float(jr.tip_angle(eq_p.x, disc)) - ref_tip)),
                "equilibrium_error_3d_deg": abs(math.degrees(_tip_3d(eq_3.x, ddisc) - ref_tip)),
                "equilibrium_warm_s": {"planar": t_eq_p, "3d": t_eq_3},
                "equilibrium_compile_s": {"planar": c_eq_p, "3d": c_eq_3},
                "fold_error_planar_deg": abs(math.degrees(float(fo_p.lam)) - ref_fold),
                "fold_error_3d_deg": abs(math.degrees(float(fo_3.lam)) - ref_fold),
                "fold_warm_s": {"planar": t_fo_p, "3d": t_fo_3},
                "fold_compile_s": {"planar": c_fo_p, "3d": c_fo_3},
                "converged": bool(eq_p.converged & eq_3.converged & fo_p.newton.converged
                                  & fo_3.newton.converged),
            }
            rows.append(row)
            print(f"E={e_gpa} N={n}: eq {t_eq_p * 1e3:.2f} / {t_eq_3 * 1e3:.2f} ms, fold "
                  f"{t_fo_p * 1e3:.2f} / {t_fo_3 * 1e3:.2f} ms, fold error "
                  f"{row['fold_error_planar_deg']:.1e} / {row['fold_error_3d_deg']:.1e} deg",
                  flush=True)
    return {"machine": f"{platform.machine()} {platform.processor() or ''}".strip(),
            "device": str(jax.devices()[0]), "rows": rows}


def markdown(result: dict) -> str:
    lines = ["# Cost of 3D against planar solves (same start, same N)", "",
             f"Machine: {result['machine']}, JAX device {result['device']}. Warm medians; "
             "errors against a planar N = 48 reference.", "",
             "Compile times are measured at the first E (the second reuses the programs).", "",
             "| E GPa | N | unknowns 2D/3D | eq. error 2D / 3D deg | eq. ms 2D / 3D | ratio | "
             "fold error 2D / 3D deg | fold ms 2D / 3D | ratio | compile s 2D / 3D (fold) |",
             "|" + "---|" * 10]
    for r in result["rows"]:
        e, f, c = r["equilibrium_warm_s"], r["fold_warm_s"], r["fold_compile_s"]
        lines.append(
            f"| {r['E_GPa']} | {r['N']} | {r['unknowns_planar']}/{r['unknowns_3d']} | "
            f"{r['equilibrium_error_planar_deg']:.1e} / {r['equilibrium_error_3d_deg']:.1e} | "
            f"{e['planar'] * 1e3:.2f} / {e['3d'] * 1e3:.2f} | {e['3d'] / e['planar']:.1f} | "
            f"{r['fold_error_planar_deg']:.1e} / {r['fold_error_3d_deg']:.1e} | "
            f"{f['planar'] * 1e3:.2f} / {f['3d'] * 1e3:.2f} | {f['3d'] / f['planar']:.1f} | "
            f"{c['planar']:.1f} / {c['3d']:.1f} |")
    return "\n".join(lines) + "\n"


def figure(result: dict):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(1, 2, figsize=(10, 4))
    for e_gpa, color in (("200", "C0"), ("100", "C1")):
        rows = [r for r in result["rows"] if str(r["E_GPa"]) == e_gpa]
        for kind, marker in (("equilibrium", "o"), ("fold", "s")):
            for dim, style in (("planar", "-"), ("3d", "--")):
                err = [max(r[f"{kind}_error_{dim}_deg"], 1e-16) for r in rows]
                t = [r[f"{kind}_warm_s"][dim] for r in rows]
                label = f"E={e_gpa} {kind} {'2D' if dim == 'planar' else '3D'}"
                ax[0].semilogy([r["N"] for r in rows], err, style + marker, color=color,
                               label=label, ms=4)
                ax[1].loglog(t, err, style + marker, color=color, label=label, ms=4)
    ax[0].set_xlabel("N (Chebyshev degree)")
    ax[0].set_ylabel("error (deg)")
    ax[1].set_xlabel("warm time per solve (s)")
    ax[1].set_ylabel("error (deg)")
    ax[1].legend(fontsize=7)
    ax[0].set_title("same error in 2D and 3D")
    ax[1].set_title("3D costs more per digit")
    fig.tight_layout()
    return fig


def write(result: dict, out: Path) -> None:
    write_results(out, "three_d_cost", result, markdown(result), figure(result))


def main(argv=None) -> int:
    return benchmark_main(__doc__, run, write, argv, quick_help="N = 8 only")


if __name__ == "__main__":
    raise SystemExit(main())
