"""Fold curves in D and the cusps: jaxrod against AUTO-07p (ISW=2) and JaxCont, side by side.

From the paper's point (G, M, D) = (2.2, 0.0236, 1.2228) the lower fold's curve in D rises to
the cusp at D = 1.3064 (where the hysteresis closes), turns back as the upper fold and runs
down to a second cusp at D = 1.0212 (alpha = 87 deg, where the upper fold meets a third fold
of the small-clearance diagram). Every method follows that curve from the same limit point:

- jaxrod: ``fold_curves`` to D = 1.5 (both folds, first cusp) and to D = 1.015 (upper fold to
  the second cusp), N = 16 Chebyshev; warm (programs compiled) and the first call in the
  process (compilation included).
- AUTO-07p: the one-parameter run from the straight rod locates the LPs (as in
  error_vs_time.py), then ISW=2 from the lower LP generates the fold system's starting data
  and continues it in (D, alpha) (``--auto``; the tip enters as two constant state variables
  so that alpha alone is free in the one-parameter run). AUTO flags the second cusp as an LP
  in D; the first it steps over, and its D is read off the curve's maximum (a parabola
  through the three points around it).
- JaxCont (``--jaxcont``, installed into a temporary folder): ``fold_curve_problem`` on the
  same discretised residual (jaxrod's gradient of the N = 16 energy, p = (alpha, D)) and
  ``continuation`` with its ``Cusp`` event, float64.

The reference is jaxrod at N = 24 (the cusp converges spectrally: the table of error vs N).
The conditioning table compares the Moore-Spence corrector's Jacobian (2m + 2 unknowns) with
the minimally augmented fold system (m + 2 unknowns, g from a bordered solve) along the curve
up to the cusp: the choice of Moore-Spence in ``jaxrod.solvers.fold_curve``.

Run:  python benchmarks/fold_curves.py [--quick] [--auto] [--jaxcont]
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402
from common import RESULTS, write_results  # noqa: E402

import jaxrod as jr  # noqa: E402
from jaxrod.bistability import fold_curves as fc  # noqa: E402

G0, M0, D0 = 2.2, 0.0236, 11.25 / 9.2
LOW_END = 1.015


def _point():
    return jr.DesignPoint.from_groups(G0, M0, D0)


def _jaxrod_pair(n=fc.DEFAULT_N):
    """(first cusp, second cusp) from the two fold_curves runs."""
    up = jr.fold_curves(_point(), "D", 1.5, n=n)
    down = jr.fold_curves(_point(), "D", LOW_END, n=n)
    cusp = lambda curves: next(p for c in curves for p in c.cusps)
    return cusp(up), cusp(down), up, down


def _one_curve(max_cusps: int, repeat: int):
    """(best warm time, result) of the lower fold's curve in D from the limit point through
    up to ``max_cusps`` cusps (``trace_fold_curve``)."""
    run = lambda: fc.trace_fold_curve(_point(), "D", (LOW_END, 1.5), max_cusps=max_cusps)
    out, best = run(), math.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = run()
        best = min(best, time.perf_counter() - t0)
    return best, out


def jaxrod_timing(repeat: int = 3) -> dict:
    t0 = time.perf_counter()
    first_cusp, second, up, down = _jaxrod_pair()
    cold = time.perf_counter() - t0
    warm, warm_up = [], []
    for _ in range(repeat):
        t0 = time.perf_counter()
        jr.fold_curves(_point(), "D", 1.5)
        t1 = time.perf_counter()
        jr.fold_curves(_point(), "D", LOW_END)
        warm.append(time.perf_counter() - t0)
        warm_up.append(t1 - t0)
    # AUTO's route: one curve from the lower fold through the first cusp to the second;
    # and the work of an AUTO run that stops at the first cusp: that curve to the first cusp
    one, curve = _one_curve(2, repeat)
    to_cusp, first = _one_curve(1, repeat)
    return {"first_call_s": cold, "warm_s": min(warm), "warm_to_first_cusp_s": min(warm_up),
            "one_curve_to_first_cusp_s": to_cusp,
            "one_curve_first_cusp_D": first.cusps[0].along_value,
            "one_curve_s": one, "one_curve_cusps_D": [c.along_value for c in curve.cusps],
            "cusp_D": first_cusp.along_value,
            "second_cusp_D": second.along_value, "second_cusp_alpha_deg": second.value,
            "points": sum(len(c.values) for c in up + down)}


def convergence(ns, n_ref) -> dict:
    ref = _jaxrod_pair(n_ref)[:2]
    rows = []
    for n in ns:
        c1, c2 = _jaxrod_pair(n)[:2]
        rows.append({"N": n, "cusp_D_error": abs(c1.along_value - ref[0].along_value),
                     "cusp_alpha_error_deg": abs(c1.value - ref[0].value),
                     "second_cusp_D_error": abs(c2.along_value - ref[1].along_value)})
        print(f"N = {n}: cusp D error {rows[-1]['cusp_D_error']:.1e}, second cusp "
              f"{rows[-1]['second_cusp_D_error']:.1e}", flush=True)
    return {"N_ref": n_ref, "reference": {"cusp_D": ref[0].along_value,
                                          "cusp_alpha_deg": ref[0].value,
                                          "second_cusp_D": ref[1].along_value,
                                          "second_cusp_alpha_deg": ref[1].value},
            "rows": rows}


def conditioning(samples: int = 8) -> list[dict]:
    """2-norm condition numbers of the two fold formulations' corrector Jacobians at points
    of the lower fold's curve approaching the cusp."""
    from jaxrod.bistability.fold_curve import SHIFT
    from jaxrod.equilibria.equilibrium import MODEL
    from jaxrod.solvers.fold_curve import fold_linearisation

    point = _point()
    up = jr.fold_curves(point, "D", 1.5)
    lower = up[0]
    # states along the curve: re-run to get them (the FoldCurve keeps observables only)
    w0 = fc._start(point, fc.DEFAULT_N)
    runs, _, args = fc._run(point, "D", 0.0 - 1e-3, 0.3, w0, [1.0, 1.0], fc.DEFAULT_N, 1.0)
    m = args[1].size
    k = len(lower.values) - 1
    W = np.concatenate([np.full(2 * m, 1.0 / m), [1.0, 1.0]])
    rows = []
    for j in np.unique(np.linspace(0, k - 1, samples).astype(int)):
        w = jnp.asarray(runs.w[0][j])
        t = np.asarray(runs.tangent[0][j])
        ell = w[m:2 * m] / jnp.dot(w[m:2 * m], w[m:2 * m])
        _, J = fold_linearisation(w, ell, MODEL, SHIFT, args)
        ms = np.vstack([np.asarray(J), W * t])
        # minimally augmented: unknowns y = (x, alpha, u); g from [H b; c^T 0][v; g] = [0; 1]
        b = c = np.asarray(w[m:2 * m]) / np.linalg.norm(np.asarray(w[m:2 * m]))

        def minimal(y):
            at = SHIFT(y[m + 1], args)
            H = MODEL.hessian(y[:m], y[m], at)
            bordered = jnp.block([[H, jnp.asarray(b)[:, None]],
                                  [jnp.asarray(c)[None, :], jnp.zeros((1, 1))]])
            g = jnp.linalg.solve(bordered, jnp.zeros(m + 1).at[m].set(1.0))[m]
            return jnp.append(MODEL.gradient(y[:m], y[m], at), g)

        y = jnp.concatenate([w[:m], w[2 * m:]])
        Jm = np.asarray(jax.jacfwd(minimal)(y))
        ty = np.concatenate([t[:m], t[2 * m:]])
        Wy = np.concatenate([np.full(m, 1.0 / m), [1.0, 1.0]])
        mini = np.vstack([Jm, Wy * ty])
        rows.append({"D": float(lower.along_values[j]), "distance_to_cusp":
                     lower.cusps[0].along_value - float(lower.along_values[j]),
                     "moore_spence_cond": float(np.linalg.cond(ms)),
                     "minimally_augmented_cond": float(np.linalg.cond(mini))})
    return rows


# --- AUTO-07p ----------------------------------------------------------------------------

AUTO_EQUATIONS = """\
! Planar clamped rod pulled by a dipole magnet on a circle (written by jaxrod's benchmark);
! the tip X = (U6, U7) as two constant states, so that alpha alone is free on a branch
SUBROUTINE FUNC(NDIM,U,ICP,PAR,IJAC,F,DFDU,DFDP)
  IMPLICIT NONE
  INTEGER, INTENT(IN) :: NDIM, ICP(*), IJAC
  DOUBLE PRECISION, INTENT(IN) :: U(NDIM), PAR(*)
  DOUBLE PRECISION, INTENT(OUT) :: F(NDIM)
  DOUBLE PRECISION, INTENT(INOUT) :: DFDU(NDIM,NDIM), DFDP(NDIM,*)
  DOUBLE PRECISION p1, p3, r1, r3, r2, pr, g1, g3
  p1 = SIN(PAR(1)); p3 = COS(PAR(1))
  r1 = U(6) - PAR(4)*p1; r3 = U(7) - PAR(4)*p3
  r2 = r1*r1 + r3*r3; pr = p1*r1 + p3*r3
  g1 = p1/r2**1.5d0 - 3.d0*pr*r1/r2**2.5d0
  g3 = p3/r2**1.5d0 - 3.d0*pr*r3/r2**2.5d0
  F(1) = U(2)
  F(2) = -PAR(2)*(1.d0 - U(5))*SIN(U(1)) + PAR(3)*(g1*COS(U(1)) - g3*SIN(U(1)))
  F(3) = SIN(U(1))
  F(4) = COS(U(1))
  F(5) = 1.d0
  F(6) = 0.d0
  F(7) = 0.d0
END SUBROUTINE FUNC

SUBROUTINE STPNT(NDIM,U,PAR,T)
  IMPLICIT NONE
  INTEGER, INTENT(IN) :: NDIM
  DOUBLE PRECISION, INTENT(INOUT) :: U(NDIM), PAR(*)
  DOUBLE PRECISION, INTENT(IN) :: T
  PAR(1) = 0.d0; PAR(2) = {G}; PAR(3) = {M}; PAR(4) = {D}
  U(1) = 0.d0; U(2) = 0.d0; U(3) = 0.d0; U(4) = T; U(5) = T; U(6) = 0.d0; U(7) = 1.d0
END SUBROUTINE STPNT

SUBROUTINE BCND(NDIM,PAR,ICP,NBC,U0,U1,FB,IJAC,DBC)
  IMPLICIT NONE
  INTEGER, INTENT(IN) :: NDIM, ICP(*), NBC, IJAC
  DOUBLE PRECISION, INTENT(IN) :: PAR(*), U0(NDIM), U1(NDIM)
  DOUBLE PRECISION, INTENT(OUT) :: FB(NBC)
  DOUBLE PRECISION, INTENT(INOUT) :: DBC(NBC,*)
  FB(1) = U0(1); FB(2) = U0(3); FB(3) = U0(4); FB(4) = U0(5)
  FB(5) = U1(2); FB(6) = U1(3) - U1(6); FB(7) = U1(4) - U1(7)
END SUBROUTINE BCND

SUBROUTINE ICND
END SUBROUTINE ICND
SUBROUTINE FOPT
END SUBROUTINE FOPT
SUBROUTINE PVLS
END SUBROUTINE PVLS
"""

AUTO_CONSTANTS = """\
NDIM=7, IPS=4, IRS=0, ILP=1
ICP=[1]
NTST={ntst}, NCOL={ncol}, IAD=3, ISP=0, ISW=1, IPLT=0, NBC=7, NINT=0
NMX=600, NPR=1000, MXBF=0, IID=0, ITMX=12, ITNW=7, NWTN=3, JAC=0
EPSL=1e-10, EPSU=1e-10, EPSS=1e-10
DS=0.01, DSMIN=1e-7, DSMAX=0.05, IADS=1
THL={{}}, THU={{}}
UZSTOP={{1: 1.5}}
"""

AUTO_RUNNER = """\
import json, sys, time
sys.path.insert(0, {path!r})
import auto
t0 = time.perf_counter()
r1 = auto.run(e="magnet", c="magnet")
lower = min((p for p in r1("LP") if p["PAR(1)"] > 0), key=lambda p: p["PAR(1)"])
r2 = auto.run(lower, ICP=[4, 1], ISW=2)
r3 = auto.run(r2, UZSTOP={{4: 1.5}}, STOP=["LP1"], NMX=4000, DSMAX={dsmax}, DS=0.01)
wall = time.perf_counter() - t0
curve = [[float(p["PAR(4)"]), float(p["PAR(1)"])] for p in r3[0]]
lps = [[float(p["PAR(4)"]), float(p["PAR(1)"]), int(p["PT"])] for p in r3("LP")]
print("JAXROD-BENCH " + json.dumps({{"curve": curve, "lp": lps, "wall_s": wall}}))
"""


def _auto_max_D(curve) -> float:
    """D at the curve's maximum: the vertex of the parabola through the three points around
    it (D as a function of the step index)."""
    D = np.array([c[0] for c in curve])
    i = int(np.clip(np.argmax(D), 1, len(D) - 2))
    a, b, _ = np.polyfit([-1.0, 0.0, 1.0], D[i - 1:i + 2], 2)
    s = -b / (2 * a)
    return float(np.polyval([a, b, D[i]], s))


def run_auto(ntst: int, ncol: int, dsmax: float, repeat: int = 2) -> dict:
    import auto07p

    path = auto07p.ensure_installed()
    f = auto07p._fortran
    with tempfile.TemporaryDirectory() as work:
        w = Path(work)
        (w / "magnet.f90").write_text(AUTO_EQUATIONS.format(G=f(G0), M=f(M0), D=f(D0)))
        (w / "c.magnet").write_text(AUTO_CONSTANTS.format(ntst=ntst, ncol=ncol))
        (w / "run.py").write_text(AUTO_RUNNER.format(path=path, dsmax=dsmax))
        env = os.environ | {"AUTO_DIR": auto07p.AUTO_DIR}
        runs = []
        for _ in range(repeat + 1):  # the first also compiles the equations
            proc = subprocess.run([sys.executable, "run.py"], cwd=w, env=env,
                                  capture_output=True, text=True, timeout=900)
            line = [x for x in proc.stdout.splitlines() if x.startswith("JAXROD-BENCH ")]
            if proc.returncode != 0 or not line:
                return {"ntst": ntst, "ncol": ncol, "error": proc.stderr[-400:] or "no output"}
            runs.append(json.loads(line[0].split(" ", 1)[1]))
    last = runs[-1]
    second = [lp for lp in last["lp"] if lp[0] < 1.1 and lp[1] > 1.0]
    first = [lp for lp in last["lp"] if lp[0] > 1.2]
    return {"ntst": ntst, "ncol": ncol, "dsmax": dsmax,
            "run_s": min(r["wall_s"] for r in runs[1:]),
            "cusp_D": first[0][0] if first else _auto_max_D(last["curve"]),
            "cusp_located": "LP" if first else "curve maximum",
            "second_cusp_D": second[0][0] if second else None,
            "second_cusp_alpha_deg": math.degrees(second[0][1]) if second else None,
            "points": len(last["curve"])}


# --- JaxCont -------------------------------------------------------------------------------

JAXCONT_RUNNER = """\
import json, math, sys, time
import jax, jax.numpy as jnp
import jaxrod
import jaxcont as jc
from jaxrod.magnet.folds import locate_folds
from jaxrod.discretise.planar import planar_discretisation
from jaxrod.scenes.dipole import ALPHA_MODEL, DipoleMagnet
G, M, D0 = {G!r}, {M!r}, {D!r}
disc = planar_discretisation({n}, "clamped")

def f(u, p, args):
    return ALPHA_MODEL.gradient(u, p[0], (DipoleMagnet(G, M, p[1], 0.0), disc))

low = locate_folds(DipoleMagnet(G, M, D0, 0.0), n={n}).folds[0]
out = []
for _ in range(2):
    t0 = time.perf_counter()
    prob = jc.fold_curve_problem(f, jnp.asarray(low.theta),
                                 jnp.array([math.radians(low.alpha_deg), D0]), free=1,
                                 tol=1e-10)
    res = jc.continuation(prob, p_span=(D0, 1.5), settings=jc.ContinuationPar(
        ds=0.005, ds_max=0.02, max_steps=400, newton_tol=1e-10, compute_stability=False),
        events=[jc.Cusp(f)])
    wall = time.perf_counter() - t0
    cusps = sorted([float(e.info["p"][1]), float(e.info["p"][0])] for e in res.events
                   if e.kind == "cusp" and e.info.get("converged"))
    out.append({{"wall_s": wall, "cusps": cusps}})
print("JAXROD-BENCH " + json.dumps(out))
"""


def run_jaxcont(n: int) -> dict:
    with tempfile.TemporaryDirectory() as work:
        target = Path(work) / "site"
        pip = subprocess.run([sys.executable, "-m", "pip", "install", "-q", "--no-deps",
                              "--target", str(target), "jaxcont", "equinox", "jaxtyping",
                              "wadler-lindig"], capture_output=True, text=True)
        if pip.returncode != 0:
            return {"error": "could not install jaxcont: " + pip.stderr[-300:]}
        script = Path(work) / "run.py"
        script.write_text(JAXCONT_RUNNER.format(G=G0, M=M0, D=D0, n=n))
        env = os.environ | {"PYTHONPATH": os.pathsep.join(
            [str(target), os.environ.get("PYTHONPATH", "")])}
        proc = subprocess.run([sys.executable, str(script)], env=env, capture_output=True,
                              text=True, timeout=1800)
    line = [x for x in proc.stdout.splitlines() if x.startswith("JAXROD-BENCH ")]
    if proc.returncode != 0 or not line:
        return {"error": proc.stderr[-400:] or "no output"}
    runs = json.loads(line[0].split(" ", 1)[1])
    cusps = runs[-1]["cusps"]
    first = [c for c in cusps if c[0] > 1.2]
    second = [c for c in cusps if c[0] < 1.1]
    return {"first_call_s": runs[0]["wall_s"], "second_call_s": runs[1]["wall_s"],
            "cusp_D": first[0][0] if first else None,
            "second_cusp_D": second[0][0] if second else None}


# --- report --------------------------------------------------------------------------------


def run(quick: bool, auto: bool, jaxcont: bool) -> dict:
    timing = jaxrod_timing()
    print(f"jaxrod: first call {timing['first_call_s']:.1f} s, warm "
          f"{1e3 * timing['warm_s']:.0f} ms", flush=True)
    conv = convergence([12] if quick else [6, 8, 10, 12, 16, 20], 16 if quick else 24)
    ref = conv["reference"]
    result = {"jaxrod": timing | {
        "cusp_D_error": abs(timing["cusp_D"] - ref["cusp_D"]),
        "second_cusp_D_error": abs(timing["second_cusp_D"] - ref["second_cusp_D"])},
        "convergence": conv, "conditioning": conditioning(4 if quick else 8)}
    if auto:
        rows = []
        for ntst, ncol, dsmax in ((10, 4, 0.02), (20, 4, 0.02), (40, 4, 0.02), (40, 4, 0.005)):
            r = run_auto(ntst, ncol, dsmax)
            if "error" not in r:
                r["cusp_D_error"] = abs(r["cusp_D"] - ref["cusp_D"])
                r["second_cusp_D_error"] = (abs(r["second_cusp_D"] - ref["second_cusp_D"])
                                            if r["second_cusp_D"] is not None else None)
                # AUTO stopped at the first cusp: compare with jaxrod's run to it alone
                whole = r["second_cusp_D"] is not None
                r["reached"] = "both cusps" if whole else "first cusp"
                r["ratio_to_jaxrod_warm"] = r["run_s"] / (
                    timing["one_curve_s"] if whole else timing["one_curve_to_first_cusp_s"])
            print(f"AUTO {r}", flush=True)
            rows.append(r)
        result["auto"] = rows
    if jaxcont:
        r = run_jaxcont(fc.DEFAULT_N)
        if "error" not in r:
            r["cusp_D_error"] = abs(r["cusp_D"] - ref["cusp_D"]) if r["cusp_D"] else None
            r["second_cusp_D_error"] = (abs(r["second_cusp_D"] - ref["second_cusp_D"])
                                        if r["second_cusp_D"] else None)
            r["ratio_to_jaxrod_warm"] = r["second_call_s"] / timing["warm_s"]  # same work
        print(f"JaxCont {r}", flush=True)
        result["jaxcont"] = r
    return result


def _e(x):
    return "-" if x is None else f"{x:.1e}"


def markdown(res: dict) -> str:
    j, conv = res["jaxrod"], res["convergence"]
    ref = conv["reference"]
    lines = ["# Fold curves in D and the cusps", "",
             f"From (G, M, D) = ({G0}, {M0}, {D0:.10g}). Reference (jaxrod, N = "
             f"{conv['N_ref']}): cusp D = {ref['cusp_D']:.13f}, alpha = "
             f"{ref['cusp_alpha_deg']:.10f} deg; second cusp D = {ref['second_cusp_D']:.13f}, "
             f"alpha = {ref['second_cusp_alpha_deg']:.10f} deg.", "",
             "## Spectral convergence of the cusps (error against the reference)", "",
             "| N | cusp D | cusp alpha (deg) | second cusp D |", "|---|---|---|---|"]
    for r in conv["rows"]:
        lines.append(f"| {r['N']} | {_e(r['cusp_D_error'])} | {_e(r['cusp_alpha_error_deg'])} "
                     f"| {_e(r['second_cusp_D_error'])} |")
    lines += ["", "## Side by side (both cusps from the same limit point)", "",
              "Ratios: AUTO runs that reach both cusps against jaxrod's one-curve route, "
              "those that stop at the first cusp against jaxrod's one curve from the lower fold "
              "to the first cusp (the same work); JaxCont against "
              "jaxrod's `fold_curves` pair.", "",
              "| method | setting | cusp D error | second cusp D error | time | ratio to "
              "jaxrod warm |", "|---|---|---|---|---|---|",
              f"| jaxrod `fold_curves` (warm) | N = 16, {j['points']} points | "
              f"{_e(j['cusp_D_error'])} | {_e(j['second_cusp_D_error'])} | "
              f"{1e3 * j['warm_s']:.0f} ms | 1 |",
              f"| jaxrod, the run to D = 1.5 alone (both folds, first cusp) | N = 16 | | | "
              f"{1e3 * j['warm_to_first_cusp_s']:.0f} ms | |",
              f"| jaxrod `trace_fold_curve`: the lower fold's curve to the first cusp "
              f"(AUTO's work when it stops there) | N = 16 | "
              f"{_e(abs(j['one_curve_first_cusp_D'] - ref['cusp_D']))} | | "
              f"{1e3 * j['one_curve_to_first_cusp_s']:.0f} ms | |",
              f"| jaxrod `trace_fold_curve`: AUTO's route, one curve from the lower fold "
              f"round both cusps | N = 16 | {_e(abs(j['one_curve_cusps_D'][0] - ref['cusp_D']))}"
              f" | {_e(abs(j['one_curve_cusps_D'][1] - ref['second_cusp_D']))} | "
              f"{1e3 * j['one_curve_s']:.0f} ms | |",
              f"| jaxrod, first call in the process | compilation included | | | "
              f"{j['first_call_s']:.1f} s | {j['first_call_s'] / j['warm_s']:.0f} |"]
    for r in res.get("auto", []):
        if "error" in r:
            lines.append(f"| AUTO-07p ISW=2 | NTST={r['ntst']} | failed: {r['error'][:60]} | | | |")
            continue
        lines.append(f"| AUTO-07p ISW=2 | NTST={r['ntst']}, NCOL={r['ncol']}, DSMAX="
                     f"{r['dsmax']} ({r['points']} points, {r['reached']}) | "
                     f"{_e(r['cusp_D_error'])} "
                     f"({r['cusp_located']}) | {_e(r['second_cusp_D_error'])} (LP) | "
                     f"{1e3 * r['run_s']:.0f} ms | {r['ratio_to_jaxrod_warm']:.1f} |")
    jc = res.get("jaxcont")
    if jc is not None:
        if "error" in jc:
            lines.append(f"| JaxCont | | failed: {jc['error'][:60]} | | | |")
        else:
            lines.append(f"| JaxCont fold_curve_problem + Cusp | N = 16, float64 | "
                         f"{_e(jc['cusp_D_error'])} | {_e(jc['second_cusp_D_error'])} | "
                         f"{jc['second_call_s']:.1f} s (first call {jc['first_call_s']:.1f} s) "
                         f"| {jc['ratio_to_jaxrod_warm']:.0f} |")
    lines += ["", "## Conditioning along the lower fold's curve (2-norm condition numbers of "
              "the corrector Jacobians)", "",
              "| D | distance to cusp | Moore-Spence (2m + 2) | minimally augmented (m + 2) |",
              "|---|---|---|---|"]
    for r in res["conditioning"]:
        lines.append(f"| {r['D']:.6f} | {r['distance_to_cusp']:.2e} | "
                     f"{r['moore_spence_cond']:.2e} | {r['minimally_augmented_cond']:.2e} |")
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="the short form the tests run")
    parser.add_argument("--auto", action="store_true", help="include AUTO-07p (installs it)")
    parser.add_argument("--jaxcont", action="store_true", help="include JaxCont (installs it "
                        "into a temporary folder)")
    parser.add_argument("--out", default=str(RESULTS), help="results folder")
    args = parser.parse_args(argv)
    res = run(args.quick, args.auto, args.jaxcont)
    write_results(Path(args.out), "fold_curves", res, markdown(res))
    return 0


if __name__ == "__main__":
    sys.exit(main())
