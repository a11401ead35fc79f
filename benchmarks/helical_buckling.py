"""jaxrod against PyElastica on PyElastica's helical buckling case: a rod (L = 100, B = 1.345,
C = 0.789) clamped at both ends, the far end brought 3% closer and turned by 27 turns
(``examples/HelicalBucklingCase``: 100 elements, dt = 1e-3 dl, the ends turned and moved over
500 s, then held to t = 10,500 s: 1.05e7 PositionVerlet steps, damping 0.01).

The reference is the localised helix's long-rod closed form (van der Heijden, Neukirch, Goss
and Thompson 2003): with mu = m / sqrt(t), t = 16 (1 - mu^2 / 4) / d^2 and the end rotation
R = mu sqrt(t) / gamma + 4 arccos(mu / 2), solved here for mu by brentq; the helix's distance
from the axis is A / cosh(k (s - 1/2)). Both codes are compared on the end moment
m = M L / B, the tension t = T L^2 / B (PyElastica's from its internal couple and force at
the end elements; the moment's sign is the sense the example turns) and that envelope, and
timed: jaxrod from a fresh program (compilation included) and warm, PyElastica as it runs
its example. jaxrod then turns on to the helix's fold in the end rotation, against the long-rod
closed form of the fold (``fold_closed_form``).

PyElastica is installed (pip) into ``benchmarks/.peers/pyelastica`` if missing
(``pyelastica_peer.peer_python``).

Run:  python benchmarks/helical_buckling.py [--quick]   (quick: PyElastica to 1/20 of the
simulated time, a smoke run: not at rest)
Writes benchmarks/results/helical_buckling{,_quick}.{json,md}.
"""

from __future__ import annotations

import argparse
import json
import math
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np
from pyelastica_peer import _machine, peer_python
from scipy.optimize import brentq

HERE = Path(__file__).resolve().parent
B, C, LENGTH, SHORTENING, TURNS = 1.345, 0.789, 100.0, 0.03, 27.0

CASE = r'''
import json, sys, time
import numpy as np
import elastica as ea


class Sim(ea.BaseSystemCollection, ea.Constraints, ea.Forcing, ea.Damping):
    pass


n_elem, final_time = int(sys.argv[1]), float(sys.argv[2])
L, r = 100.0, 0.35
sim = Sim()
rod = ea.CosseratRod.straight_rod(n_elem, np.zeros(3), np.array([0.0, 0.0, 1.0]),
                                  np.array([0.0, 1.0, 0.0]), L, r, 1.0 / (np.pi * r * r),
                                  youngs_modulus=1e6, shear_modulus=1e6 / 200.0)
rod.shear_matrix[:] = np.repeat(1e5 * np.identity(3)[:, :, None], n_elem, axis=2)
bend = np.diag([1.345, 1.345, 0.789])
rod.bend_matrix[:] = np.repeat(bend[:, :, None], n_elem - 1, axis=2)
sim.append(rod)
dt = 1e-3 * L / n_elem
sim.constrain(rod).using(ea.HelicalBucklingBC, constrained_position_idx=(0, -1),
                         constrained_director_idx=(0, -1), twisting_time=500, slack=3,
                         number_of_rotations=27)
sim.dampen(rod).using(ea.AnalyticalLinearDamper, damping_constant=0.01, time_step=dt)
sim.finalize()
rod.velocity_collection[..., n_elem // 2] += np.array([0.0, 1e-6, 0.0])
steps = int(round(final_time / dt))
start = time.perf_counter()
ea.integrate(ea.PositionVerlet(), sim, final_time, steps, progress_bar=False)
seconds = time.perf_counter() - start
print(json.dumps({"seconds": seconds, "steps": steps,
                  "positions": rod.position_collection.tolist(),
                  "axial_force": rod.internal_stress[2, [0, -1]].tolist(),
                  "twist_couple": rod.internal_couple[2, [0, -1]].tolist()}))
'''


def closed_form(gamma: float, d: float, turns: float) -> dict:
    """The localised helix's long-rod limit (module docstring)."""
    def rotation(mu):
        t = 16.0 * (1.0 - mu * mu / 4.0) / d**2
        return mu * math.sqrt(t) / gamma + 4.0 * math.acos(mu / 2.0) - 2.0 * math.pi * turns

    mu = brentq(rotation, 1.0, 2.0 - 1e-12, xtol=1e-15)
    t = 16.0 * (1.0 - mu * mu / 4.0) / d**2
    m = mu * math.sqrt(t)
    tp, mp = t / (4 * math.pi**2), m / (2 * math.pi)
    root = math.sqrt(4 * tp - mp * mp)
    return {"twist_moment": m, "tension": t, "amplitude": root / (2 * math.pi * tp),
            "decay": math.pi * root}


def envelope_error(s, radius, ref) -> float:
    """max |radius - A / cosh(k (s - 1/2))| / A over the given points (lengths in L)."""
    expected = ref["amplitude"] / np.cosh(ref["decay"] * (np.asarray(s) - 0.5))
    return float(np.max(np.abs(np.asarray(radius) - expected)) / ref["amplitude"])


def _reached(target):
    """PyElastica's state on ``target`` (a TwistedRod): the Euler-buckled rod turned to 27
    turns at n = 48, then solved on the target's grid."""
    import jaxrod as jr

    rod = jr.TwistedRod(twist_ratio=C / B, shortening=SHORTENING, n=48)
    branch = jr.twist_branch(rod, TURNS, ds_max=2.0)
    state = jr.twisted_equilibrium(rod, TURNS, start=branch.points[-2])
    return jr.twisted_equilibrium(target, TURNS, start=state)


def _twice(run):
    """(run()'s result, the seconds of its first call (programs compiled) and of a second
    (warm))."""
    times = []
    for _ in range(2):
        start = time.perf_counter()
        result = run()
        times.append(time.perf_counter() - start)
    return result, times[0], times[1]


def jaxrod_case(ref: dict, n: int) -> dict:
    """Turn the Euler-buckled rod to 27 turns at n = 48, then solve at n, timed."""
    import jaxrod as jr
    from jaxrod import spectral

    state, first, warm = _twice(lambda: _reached(
        jr.TwistedRod(twist_ratio=C / B, shortening=SHORTENING, n=n)))
    s, r = state.centreline()
    fine = np.linspace(0.0, 1.0, 401)
    xy = spectral.interpolation_matrix(len(s) - 1, fine) @ r[:, :2]
    return {"n": n, "seconds_first": first, "seconds_warm": warm,
            "twist_moment": state.twist_moment, "tension": state.tension,
            "envelope_error": envelope_error(fine, np.hypot(xy[:, 0], xy[:, 1]), ref),
            "unstable": state.unstable, "converged": state.converged}


def fold_closed_form(gamma: float, d: float) -> dict:
    """The localised helix's fold in the end rotation at shortening d, long-rod limit: with
    u = d^2 t / 16, m = (8 / d) sqrt(u (1 - u)) and R = m / gamma + 4 arcsin(sqrt u), so
    dR/du = 0 at u = 1/2 + gamma d / 4."""
    u = 0.5 + gamma * d / 4.0
    m = 8.0 / d * math.sqrt(u * (1.0 - u))
    return {"turns": (m / gamma + 4.0 * math.asin(math.sqrt(u))) / (2.0 * math.pi),
            "twist_moment": m, "tension": 16.0 * u / d**2}


def jaxrod_fold(n: int) -> dict:
    """From 27 turns (reached as ``jaxrod_case`` does), turned on at n on the grid gathered
    into a layer of width 0.015 at the middle, the slide centred, to the fold, timed."""
    import jaxrod as jr

    rod = jr.TwistedRod(twist_ratio=C / B, shortening=SHORTENING, n=n, layer_width=0.015,
                        centred=True)
    branch, first, warm = _twice(lambda: jr.twist_branch(
        rod, 39.0, start=_reached(rod), ds_max=0.5, max_folds=1))
    fold, i = branch.fold_points[0], branch.folds[0]
    return {"n": n, "seconds_first": first, "seconds_warm": warm,
            "turns": fold.value, "twist_moment": fold.state.twist_moment,
            "tension": fold.state.tension, "converged": fold.converged,
            "unstable_before": branch.points[i - 1].unstable,
            "unstable_after": branch.points[i].unstable}


def pyelastica_case(python: str, n_elem: int, final_time: float, ref: dict) -> dict:
    with tempfile.TemporaryDirectory() as tmp:
        script = Path(tmp) / "case.py"
        script.write_text(CASE)
        subprocess.run([python, str(script), "100", "1.0"], check=True, capture_output=True)
        proc = subprocess.run([python, str(script), str(n_elem), str(final_time)], check=True,
                              capture_output=True, text=True)
    raw = json.loads(proc.stdout.strip().splitlines()[-1])
    x = np.asarray(raw["positions"])
    s = np.linspace(0.0, 1.0, x.shape[1])
    return {"n_elem": n_elem, "steps": raw["steps"], "seconds": raw["seconds"],
            "twist_moment": abs(float(np.mean(raw["twist_couple"]))) * LENGTH / B,
            "tension": float(np.mean(raw["axial_force"])) * LENGTH**2 / B,
            "envelope_error": envelope_error(s, np.hypot(x[0], x[1]) / LENGTH, ref),
            "shortening": 1.0 - float(x[2, -1] - x[2, 0]) / LENGTH}


def _relative(value, ref):
    return abs(value / ref - 1.0)


def _table(out: dict) -> str:
    ref, jx, pe = out["reference"], out["jaxrod"], out["pyelastica"]
    rows = [("end moment M L / B", "twist_moment", ".7f"), ("tension T L^2 / B", "tension",
                                                             ".5f")]
    lines = ["# Helical buckling: jaxrod against PyElastica", "",
             f"Machine: {out['machine']}. PyElastica's example (n_elem = {pe['n_elem']}, "
             f"{pe['steps']:,} steps to t = {out['final_time']:g}); jaxrod n = {jx['n']}.", "",
             "| | closed form (long rod) | jaxrod | PyElastica |", "|---|---|---|---|"]
    for label, key, fmt in rows:
        lines.append(f"| {label} | {ref[key]:{fmt}} | {jx[key]:{fmt}} "
                     f"({_relative(jx[key], ref[key]):.1e}) | {pe[key]:{fmt}} "
                     f"({_relative(pe[key], ref[key]):.1e}) |")
    lines += [f"| envelope, max error / A | | {jx['envelope_error']:.1e} | "
              f"{pe['envelope_error']:.1e} |",
              f"| time | | {jx['seconds_first']:.1f} s first call, {jx['seconds_warm']:.1f} s "
              f"warm | {pe['seconds']:.0f} s |",
              f"| time ratio (PyElastica / jaxrod's first call) | | | "
              f"{pe['seconds'] / jx['seconds_first']:.0f}x |", ""]
    if "fold" in out:
        f, fr = out["fold"], out["fold_reference"]
        lines += ["The fold in the end rotation beyond 27 turns (3% shortening held): jaxrod "
                  f"at n = {f['n']}, the grid gathered into a layer of width 0.015, the slide "
                  "centred; an explicit simulation lands on one side of a fold and does not "
                  "locate it.", "", "| | closed form (long rod) | jaxrod |", "|---|---|---|"]
        for label, key, fmt in (("turns", "turns", ".10f"),
                                ("end moment M L / B", "twist_moment", ".9f"),
                                ("tension T L^2 / B", "tension", ".8f")):
            lines.append(f"| {label} | {fr[key]:{fmt}} | {f[key]:{fmt}} "
                         f"({_relative(f[key], fr[key]):.1e}) |")
        lines += [f"| unstable directions before / after | | {f['unstable_before']} / "
                  f"{f['unstable_after']} |",
                  f"| time (from the Euler-buckled rod) | | {f['seconds_first']:.1f} s first "
                  f"call, {f['seconds_warm']:.1f} s warm |", ""]
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true",
                    help="PyElastica to 525 s of simulated time, jaxrod at n = 96 (a smoke run)")
    ap.add_argument("--out", default=str(HERE / "results"))
    args = ap.parse_args(argv)
    ref = closed_form(C / B, SHORTENING, TURNS)
    final_time = 525.0 if args.quick else 10500.0
    jx = jaxrod_case(ref, 96 if args.quick else 160)
    print(json.dumps(jx), flush=True)
    fold = jaxrod_fold(96)
    print(json.dumps(fold), flush=True)
    pe = pyelastica_case(peer_python(), 100, final_time, ref)
    print(json.dumps(pe), flush=True)
    out = {"reference": ref, "jaxrod": jx, "pyelastica": pe, "final_time": final_time,
           "fold": fold, "fold_reference": fold_closed_form(C / B, SHORTENING),
           "machine": _machine()}
    dest = Path(args.out)
    dest.mkdir(parents=True, exist_ok=True)
    name = "helical_buckling_quick" if args.quick else "helical_buckling"
    (dest / f"{name}.json").write_text(json.dumps(out, indent=1))
    (dest / f"{name}.md").write_text(_table(out))
    print(_table(out))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
