"""The snap against PyElastica: the paper's wire snapping off its magnet, explicit Cosserat
time stepping at its stability limit against jaxrod's implicit BDF2.

The rig of the paper's permanent-magnet experiment (G = 2.2, M = 0.0236, D = 11.25 / 9.2;
the 50 um nickel wire, slenderness r / L = 25 um / 92 mm), nondimensional: lengths in L,
time in T = L^2 sqrt(rho A / (E I)) (0.144 s for the paper's wire), a linear drag c per unit
length (air at the snap's speed: c ~ 1.1). The magnet is moved ``PAST`` degrees beyond the
upper fold and the wire starts at rest in the fold's shape.

PyElastica (a Cosserat rod: shear, extension and rotary inertia; position Verlet) takes the
same rig with E and rho chosen so that E I = rho A = 1 at the rod's radius r; gravity as its
GravityForces, the drag as AnalyticalLinearDamper (uniform constant c), and the magnet as a
forcing class written here: the force -M grad Phi(X) on the tip node (the paper's endpoint
potential, the exact derivative of the tangent magnetisation's Zeeman energy). The fold's
shape is laid on its elements (each of length dl along the fold's tangent at its middle).
Its explicit step is limited by the axial waves, dt < dl sqrt(rho / E) = dl r / 2 (its issue
#246), and, for a rod thinner than its elements, by the shear-rotation mode of each element,
dt < ~r^2: each run takes the largest stable step of a scan. The whole snap is run on a rod
of r / L = 0.01 (its shear and rotary inertia change the motion by ~(r/L)^2 = 1e-4) at
n = 25, 50, 100 elements; on the paper's wire (r / L = 2.7e-4) the stable step and the
cost per step are measured and the snap's wall time extrapolated.

jaxrod: ``jr.simulate`` (BDF2) at two steps, to show its own convergence. Both record the
tip's angle (its position's, from +z toward +x, as ``Trajectory.tip_angle_deg``); the run
prints the snap's times (leave: the tip 0.5 degrees from its start; arrive: first within 0.5
degrees of the resting angle; settle: the last time outside), the largest difference of the
tip's angle over the snap, wall time and steps, side by side.

PyElastica is installed (pip) into ``benchmarks/.peers/pyelastica`` if the running Python
lacks it (as for benchmarks/pyelastica_peer.py).

Run:  python benchmarks/pyelastica_snap.py [--quick]    (quick: 20 elements, 6 T)
Writes benchmarks/results/pyelastica_snap.{json,md}.
"""

from __future__ import annotations

import argparse
import json
import math
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from pyelastica_peer import peer_python  # noqa: E402

HERE = Path(__file__).resolve().parent
G, M, D = 2.2, 0.0236, 11.25 / 9.2
RADIUS = 25e-6 / 0.092  # the paper's wire, r / L
PAST = 0.5  # degrees past the fold
THICK = 0.01  # r / L of the rod whose whole snap PyElastica runs
BAND = 0.5

CASE = r'''
import json, sys, time
import numpy as np
from elastica import (AnalyticalLinearDamper, BaseSystemCollection, CallBacks, Constraints,
                      CosseratRod, Damping, Forcing, GravityForces, OneEndFixedBC,
                      PositionVerlet, integrate)
from elastica.callback_functions import CallBackBaseClass
from elastica.external_forces import NoForces


class Sim(BaseSystemCollection, Constraints, Forcing, Damping, CallBacks):
    pass


class TipMagnet(NoForces):
    """-M grad Phi(X) on the tip node, Phi(x) = p . r / |r|^3, r = x - D p."""

    def __init__(self, M, D, alpha):
        super().__init__()
        self.M, self.D = M, D
        self.p = np.array([np.sin(alpha), 0.0, np.cos(alpha)])

    def apply_forces(self, system, time=0.0):
        r = system.position_collection[:, -1] - self.D * self.p
        r2 = r @ r
        grad = self.p / r2**1.5 - 3.0 * (self.p @ r) * r / r2**2.5
        system.external_forces[:, -1] -= self.M * grad


class Tip(CallBackBaseClass):
    def __init__(self, every, out):
        super().__init__()
        self.every, self.out = every, out

    def make_callback(self, system, time, current_step):
        if current_step % self.every == 0:  # the tip's angle: its position's from +z
            X = system.position_collection[:, -1]
            self.out.append((float(time), float(np.degrees(np.arctan2(X[0], X[2])))))


def run(theta_mid, G, M, D, alpha, c, radius, final_time, dt):
    n = len(theta_mid)
    dl = 1.0 / n
    E, rho = 4.0 / (np.pi * radius**4), 1.0 / (np.pi * radius**2)  # E I = rho A = 1
    rod = CosseratRod.straight_rod(n, np.zeros(3), np.array([0.0, 0.0, 1.0]),
                                   np.array([1.0, 0.0, 0.0]), 1.0, radius, rho,
                                   youngs_modulus=E, shear_modulus=E / 3.0)
    t = np.asarray(theta_mid)
    d3 = np.stack([np.sin(t), np.zeros(n), np.cos(t)])
    rod.position_collection[:] = np.concatenate([np.zeros((3, 1)),
                                                 np.cumsum(dl * d3, axis=1)], axis=1)
    rod.director_collection[0] = np.stack([np.cos(t), np.zeros(n), -np.sin(t)])
    rod.director_collection[1] = np.stack([np.zeros(n), np.ones(n), np.zeros(n)])
    rod.director_collection[2] = d3
    sim = Sim()
    sim.append(rod)
    sim.constrain(rod).using(OneEndFixedBC, constrained_position_idx=(0,),
                             constrained_director_idx=(0,))
    sim.add_forcing_to(rod).using(GravityForces, acc_gravity=np.array([0.0, 0.0, -G]))
    sim.add_forcing_to(rod).using(TipMagnet, M=M, D=D, alpha=alpha)
    if c > 0:
        sim.dampen(rod).using(AnalyticalLinearDamper, uniform_damping_constant=c,
                              time_step=dt)
    record = []
    steps = int(final_time / dt)
    sim.collect_diagnostics(rod).using(Tip, every=max(1, int(0.005 / dt)), out=record)
    sim.finalize()
    t0 = time.perf_counter()
    integrate(PositionVerlet(), sim, final_time, steps, progress_bar=False)
    wall = time.perf_counter() - t0
    tip = np.asarray([r[1] for r in record])
    return {"time": [r[0] for r in record], "tip_deg": tip.tolist(),
            "wall_s": wall, "steps": steps, "dt": dt,
            "stable": bool(np.all(np.isfinite(rod.position_collection))
                           and np.all(np.isfinite(tip)) and np.ptp(tip) < 45.0)}


jobs = json.loads(open(sys.argv[1]).read())
print("RESULT " + json.dumps([run(**job) for job in jobs]))
'''


def times(time, tip, start, band=BAND):
    """leave, arrive, settle (jaxrod's definitions, ``band_times``: interpolated between the
    samples; None where undefined) and the resting angle = the last one."""
    from jaxrod.dynamics.snap import band_times

    tip = np.asarray(tip)
    found = [float(t) for t in band_times(np.asarray(time), tip, start, tip[-1], band)]
    return (*(None if math.isnan(t) else t for t in found), float(tip[-1]))


def jaxrod_runs(final_time, c, dts):
    import jaxrod as jr
    from jaxrod.equilibria.equilibrium import discretise

    scene = jr.Scene({"bending": jr.Bending(), "gravity": jr.Gravity(G),
                      "magnet": jr.Dipole(M, D, 0.0)})
    fold = max(jr.folds(scene, "magnet.alpha", 0.0, math.pi / 2, n=24),
               key=lambda f: f.value)
    at = scene.replace("magnet.alpha", fold.value + math.radians(PAST))
    runs = []
    for dt in dts:
        t0 = time.perf_counter()
        tr = jr.simulate(at, fold.state, final_time, dt, damping=c, n=24, scheme="bdf2")
        first = time.perf_counter() - t0
        t0 = time.perf_counter()
        tr = jr.simulate(at, fold.state, final_time, dt, damping=c, n=24, scheme="bdf2")
        runs.append({"dt": dt, "steps": len(tr.time), "wall_s": time.perf_counter() - t0,
                     "first_call_s": first, "time": tr.time.tolist(),
                     "tip_deg": tr.tip_angle_deg.tolist(), "converged": tr.converged})
    disc = discretise(scene, 24)
    d3 = np.asarray(scene.directors(fold.state, disc))
    s = np.asarray(disc.quad_nodes)
    return fold, runs, (s, np.arctan2(d3[:, 0], d3[:, 2]))


def peer(python, jobs):
    """Run PyElastica jobs (``run``'s arguments) in one process of the peer's Python."""
    with tempfile.TemporaryDirectory() as tmp:
        script, data = Path(tmp) / "case.py", Path(tmp) / "jobs.json"
        script.write_text(CASE)
        data.write_text(json.dumps(jobs))
        proc = subprocess.run([python, str(script), str(data)], capture_output=True,
                              text=True, timeout=7200)
    line = [x for x in proc.stdout.splitlines() if x.startswith("RESULT ")]
    if proc.returncode or not line:
        raise RuntimeError(proc.stderr[-1500:])
    return json.loads(line[0][7:])


def stability_limit(python, job, n_elem, radius, probe_steps=20000):
    """The largest step that stays stable for ``probe_steps`` steps, of a geometric scan
    from 1.5 dl r / 2 down to a quarter of min(dl r / 2, sqrt(3) r^2 / 2): the limits of the
    axial waves (dl sqrt(rho / E)) and of the shear-rotation mode of a rod thinner than its
    elements (frequency ~ sqrt(G A / (rho I)))."""
    axial = radius / (2.0 * n_elem)
    ref = min(axial, math.sqrt(3.0) * radius**2 / 2.0)
    steps = np.geomspace(1.5 * axial, 0.25 * ref, 14)
    probes = peer(python, [job | {"dt": dt, "final_time": probe_steps * dt} for dt in steps])
    stable = [p["dt"] for p in probes if p["stable"]]
    if not stable:
        raise RuntimeError("PyElastica: no stable step in the scan")
    return max(stable), ref, probes[0]["wall_s"] / probe_steps


def compare(rows, runs, fine, start, grid, name, r):
    """The snap's times, and the largest difference of the tip's angle from ``fine`` with
    both aligned at their leave (how long the rod lingers at the fold depends on how far
    past its own fold the magnet is, which differs by each discretisation's error)."""
    leave, arrive, settle, rest = times(r["time"], r["tip_deg"], start)
    leave_fine = times(fine["time"], fine["tip_deg"], start)[0]
    after = grid[grid <= grid[-1] - max(leave, leave_fine)]
    diff = np.max(np.abs(np.interp(after + leave, r["time"], r["tip_deg"])
                         - np.interp(after + leave_fine, fine["time"], fine["tip_deg"])))
    rows.append({"method": name, "steps": r["steps"], "wall_s": r["wall_s"], "dt": r["dt"],
                 "leave": leave, "arrive": arrive, "settle": settle,
                 "duration": None if settle is None or leave is None else settle - leave,
                 "rest_tip_deg": rest, "max_tip_difference_deg": float(diff)})


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--drag", type=float, default=1.1)
    args = ap.parse_args()
    final_time = 6.0 if args.quick else 12.0
    elements = (25,) if args.quick else (25, 50, 100)
    fold, runs, (s, theta) = jaxrod_runs(final_time, args.drag, (0.01, 0.005))
    from scipy.interpolate import CubicSpline

    order = np.argsort(s)
    spline = CubicSpline(s[order], theta[order])
    python = peer_python()

    def job(n_elem, radius):
        return {"theta_mid": spline((np.arange(n_elem) + 0.5) / n_elem).tolist(), "G": G,
                "M": M, "D": D, "alpha": fold.value + math.radians(PAST), "c": args.drag,
                "radius": radius}

    # the snap of a thicker rod (r / L = 0.01: its shear and rotary inertia 1e-4 of bending)
    limits = {n: stability_limit(python, job(n, THICK), n, THICK) for n in elements}
    full = peer(python, [job(n, THICK) | {"dt": limits[n][0], "final_time": final_time}
                         for n in elements])
    # the paper's wire: the stability limit and the cost per step, measured
    wire_n = elements[-1]
    wire_dt, wire_ref, per_step = stability_limit(python, job(wire_n, RADIUS), wire_n, RADIUS)
    start = fold.tip_angle_deg
    rows = []
    fine = runs[-1]
    grid = np.linspace(0.0, final_time, 2001)[1:]
    for q in runs:
        compare(rows, runs, fine, start, grid, f"jaxrod BDF2 dt = {q['dt']:g}", q)
    for n, r in zip(elements, full):
        compare(rows, runs, fine, start, grid, f"PyElastica r/L = {THICK:g}, n = {n}", r)
    fmt = lambda v: "   -   " if v is None else f"{v:7.4f}"  # noqa: E731
    print(f"{'method':32s} {'dt (T)':>9s} {'steps':>9s} {'wall s':>8s} {'leave':>7s} "
          f"{'arrive':>7s} {'settle':>7s} {'duration':>8s} {'max |dtip| deg':>14s}")
    for r in rows:
        print(f"{r['method']:32s} {r['dt']:9.3g} {r['steps']:9d} {r['wall_s']:8.3f} "
              f"{fmt(r['leave'])} {fmt(r['arrive'])} {fmt(r['settle'])} {fmt(r['duration'])} "
              f"{r['max_tip_difference_deg']:14.4g}")
    extrapolated = None
    if len(elements) >= 2:  # PyElastica converges at first order in dl: Richardson
        d = [r["duration"] for r in rows[len(runs):]]
        extrapolated = 2.0 * d[-1] - d[-2]
        print(f"PyElastica's duration, n = {elements[-2]}, {elements[-1]} -> infinity (first "
              f"order): {extrapolated:.4f}; jaxrod (dt = 0.005): {rows[1]['duration']:.4f}")
    wire_steps = final_time / wire_dt
    wire_wall = wire_steps * per_step
    ratio_thick = full[-1]["wall_s"] / runs[0]["wall_s"]
    ratio_wire = wire_wall / runs[0]["wall_s"]
    print(f"PyElastica on the paper's wire (r/L = {RADIUS:.3g}, n = {wire_n}): stable step "
          f"{wire_dt:.3g} T ({wire_dt / wire_ref:.2g} of min(dl r/2, sqrt(3) r^2/2)), "
          f"{wire_steps:.3g} steps for {final_time:g} T at {per_step * 1e6:.1f} us each: "
          f"~{wire_wall:.3g} s")
    print(f"wall time / jaxrod's (BDF2 dt = 0.01, warm): PyElastica r/L = {THICK:g}, "
          f"n = {elements[-1]}: {ratio_thick:.3g}; on the paper's wire (extrapolated): "
          f"{ratio_wire:.3g}")
    out = HERE / "results"
    (out / "pyelastica_snap.json").write_text(json.dumps(
        {"rows": rows, "fold_deg": math.degrees(fold.value), "past_deg": PAST,
         "drag": args.drag, "final_time": final_time, "thick_radius": THICK,
         "wire": {"radius": RADIUS, "n_elem": wire_n, "stable_dt": wire_dt,
                  "seconds_per_step": per_step, "steps": wire_steps,
                  "extrapolated_wall_s": wire_wall},
         "wall_ratio_thick": ratio_thick, "wall_ratio_wire": ratio_wire,
         "peer_duration_extrapolated": extrapolated,
         "quick": args.quick}, indent=1))
    lines = ["# The snap: jaxrod against PyElastica", "",
             f"The paper's rig, magnet {PAST} deg past the upper fold "
             f"({math.degrees(fold.value):.6f} deg), drag c = {args.drag:g}, {final_time:g} T; "
             f"tip angle within {BAND} deg for arrive/settle. Max dtip: the largest "
             "difference of the tip's angle from jaxrod at dt = 0.005 over the run, both "
             "aligned at their leave. "
             f"PyElastica at the largest stable step of a scan (r/L = {THICK:g}: the paper's "
             "wire is too slender for a whole snap, below).", "",
             "| method | dt (T) | steps | wall (s) | leave | arrive | settle | duration | "
             "max dtip (deg) |", "|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['method']} | {r['dt']:.3g} | {r['steps']} | {r['wall_s']:.3f} | "
                     f"{fmt(r['leave'])} | {fmt(r['arrive'])} | {fmt(r['settle'])} | "
                     f"{fmt(r['duration'])} | {r['max_tip_difference_deg']:.4g} |")
    if extrapolated is not None:
        lines += ["", f"PyElastica's duration extrapolated from n = {elements[-2]}, "
                  f"{elements[-1]} to infinity (it converges at first order in dl): "
                  f"{extrapolated:.4f}; jaxrod's (dt = 0.005): {rows[1]['duration']:.4f}."]
    lines += ["", f"The paper's wire (r/L = {RADIUS:.3g}) in PyElastica, n = {wire_n}: stable "
              f"step {wire_dt:.3g} T, {wire_steps:.3g} steps for the snap at "
              f"{per_step * 1e6:.1f} us each: ~{wire_wall:.3g} s (extrapolated from the "
              "measured cost per step).", "",
              f"Wall time over jaxrod's (BDF2, dt = 0.01, warm, {runs[0]['wall_s']:.3f} s): "
              f"PyElastica r/L = {THICK:g}, n = {elements[-1]}: {ratio_thick:.3g}; the paper's "
              f"wire: {ratio_wire:.3g}."]
    (out / "pyelastica_snap.md").write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
