"""jaxrod against PyElastica on MagnetoPyElastica's own validation case: a hard-magnetic
cantilever in a uniform field (L = 6 m, radius 0.15 m, E = 1 MPa, remanence 144 kA/m along
the tangent; field angles 30-179.5 degrees from the rod; loads lambda = A M_r B L^2 / (E I)
up to 38.7, MagnetoPyElastica's B up to 42 mT).

MagnetoPyElastica itself installs only on Python < 3.11; PyElastica does, and the magnetic
torque it applies (m x B per element, m = M_r V d3 in the material frame: MagnetoPyElastica's
``MagneticForces`` for a uniform field) is written in this script. PyElastica reaches the
static state by damped time stepping (MagnetoPyElastica's settings: n_elem = 50, dt = 0.05 dl,
the field ramped over half of t = 1000 s, damping 1.0); jaxrod solves the static problem
(``jr.equilibrium``). Both are compared with shooting (scipy, an independent reference) on
the tip deflection y/L and the tip angle, and timed; the run prints the table side by side.

PyElastica is installed (pip) into ``benchmarks/.peers/pyelastica`` if the running Python
lacks it.

Run:  python benchmarks/pyelastica_peer.py [--quick]
Writes benchmarks/results/pyelastica_peer.{json,md}.
"""

from __future__ import annotations

import argparse
import json
import math
import subprocess
import sys
import tempfile
import time
import venv
from pathlib import Path

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

HERE = Path(__file__).resolve().parent
PEERS = HERE / ".peers" / "pyelastica"

CASE = r'''
import json, sys, time
import numpy as np
from elastica import (AnalyticalLinearDamper, BaseSystemCollection, Constraints, CosseratRod,
                      Damping, Forcing, OneEndFixedBC, PositionVerlet, integrate)
from elastica._linalg import _batch_cross, _batch_matvec
from elastica.external_forces import NoForces


class Sim(BaseSystemCollection, Constraints, Forcing, Damping):
    pass


class UniformFieldTorque(NoForces):
    """m x B on each element, m = M_r V d3 (material frame), B ramped over ramp_time."""

    def __init__(self, field, magnetisation, volume, ramp_time):
        super().__init__()
        self.field = np.asarray(field, float)
        self.m = magnetisation * volume * np.array([0.0, 0.0, 1.0]).reshape(3, 1)
        self.ramp = ramp_time

    def apply_torques(self, system, time=0.0):
        scale = min(float(time) / self.ramp, 1.0)
        B = scale * self.field.reshape(3, 1) * np.ones((system.n_elems,))
        system.external_torques += _batch_cross(
            self.m, _batch_matvec(system.director_collection, B))


def run(load, angle_deg, n_elem, final_time):
    L, r, E, M = 6.0, 0.15, 1e6, 144e3
    A, I = np.pi * r**2, np.pi / 4 * r**4
    B = load * E * I / (M * A * L**2)
    sim = Sim()
    rod = CosseratRod.straight_rod(n_elem, np.zeros(3), np.array([1.0, 0, 0]),
                                   np.array([0, 1.0, 0]), L, r, 5000.0, youngs_modulus=E,
                                   shear_modulus=E / 2.0)
    sim.append(rod)
    sim.constrain(rod).using(OneEndFixedBC, constrained_position_idx=(0,),
                             constrained_director_idx=(0,))
    a = np.radians(angle_deg)
    sim.add_forcing_to(rod).using(UniformFieldTorque,
                                  field=B * np.array([np.cos(a), np.sin(a), 0.0]),
                                  magnetisation=M, volume=rod.volume,
                                  ramp_time=0.5 * final_time)
    dt = 0.05 * L / n_elem
    sim.dampen(rod).using(AnalyticalLinearDamper, damping_constant=1.0, time_step=dt)
    sim.finalize()
    t0 = time.perf_counter()
    integrate(PositionVerlet(), sim, final_time, int(final_time / dt), progress_bar=False)
    wall = time.perf_counter() - t0
    tip = rod.position_collection[:, -1] / L
    t = rod.tangents[:, -1]
    return {"deflection": float(tip[1]), "tip_angle_deg": float(np.degrees(np.arctan2(t[1], t[0]))),
            "seconds": wall, "steps": int(final_time / dt),
            "velocity": float(np.linalg.norm(rod.velocity_collection))}


print("RESULT " + json.dumps(run(float(sys.argv[1]), float(sys.argv[2]), int(sys.argv[3]),
                                 float(sys.argv[4]))))
'''


def peer_python() -> str:
    """A Python with PyElastica: this one, or a venv of its own (created once)."""
    try:
        import elastica  # noqa: F401

        return sys.executable
    except ImportError:
        pass
    python = PEERS / "bin" / "python"
    if not python.exists():
        print(f"installing PyElastica into {PEERS} ...", flush=True)
        venv.create(PEERS, with_pip=True)
        subprocess.run([str(python), "-m", "pip", "install", "-q", "pyelastica"], check=True)
    return str(python)


def pyelastica_case(python: str, script: Path, load, angle_deg, n_elem, final_time=1000.0):
    proc = subprocess.run([python, str(script), str(load), str(angle_deg), str(n_elem),
                           str(final_time)], capture_output=True, text=True, timeout=3600)
    line = [x for x in proc.stdout.splitlines() if x.startswith("RESULT ")]
    if proc.returncode or not line:
        raise RuntimeError(proc.stderr[-800:])
    return json.loads(line[0][7:])


def shooting(load, angle_deg, k_max=14.0, count=281):
    """Every equilibrium with |theta'(0)| <= k_max of theta'' + lam sin(a - theta) = 0,
    theta(0) = 0, theta'(1) = 0: (tip angle deg, deflection X_perp, X_along) per root."""
    a = math.radians(angle_deg)

    def end(k):
        f = lambda s, y: [y[1], -load * math.sin(a - y[0]), math.sin(y[0]), math.cos(y[0])]
        return solve_ivp(f, (0.0, 1.0), [0.0, k, 0.0, 0.0], method="DOP853", rtol=1e-13,
                         atol=1e-14).y[:, -1]

    ks = np.linspace(-k_max, k_max, count)
    ends = [end(k)[1] for k in ks]
    roots = []
    for k0, k1, f0, f1 in zip(ks[:-1], ks[1:], ends[:-1], ends[1:]):
        if f0 * f1 < 0:
            y = end(brentq(lambda k: end(k)[1], k0, k1, xtol=1e-15, rtol=1e-15))
            roots.append((math.degrees(y[0]), y[2], y[3]))
    return roots


def jaxrod_case(load, angle_deg, n, repeats=5):
    import jaxrod as jr

    scene = jr.Scene({"bending": jr.Bending(), "field": jr.Zeeman(load, math.radians(angle_deg))})
    t0 = time.perf_counter()
    eq = jr.equilibrium(scene, n=n)
    first = time.perf_counter() - t0
    warm = math.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        jr.equilibrium(scene, n=n)
        warm = min(warm, time.perf_counter() - t0)
    return {"deflection": float(eq.tip_position[0]), "tip_angle_deg": eq.tip_tangent_deg,
            "stable": eq.stable, "first_call_s": first, "seconds": warm}


def errors(result, ref):
    return (abs(result["deflection"] - ref[1]), abs(result["tip_angle_deg"] - ref[0]))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true", help="one case, n_elem = 25 (a smoke run)")
    ap.add_argument("--out", default=str(HERE / "results"))
    args = ap.parse_args(argv)
    python = peer_python()
    angles = (90.0,) if args.quick else (30.0, 90.0, 150.0, 179.5)
    loads = (20.0,) if args.quick else (5.0, 20.0, 38.7)
    n_elem = 25 if args.quick else 50
    with tempfile.TemporaryDirectory() as tmp:
        script = Path(tmp) / "case.py"
        script.write_text(CASE)
        pyelastica_case(python, script, 1.0, 90.0, 10, 10.0)  # numba compiles once
        rows = []
        for angle in angles:
            for load in loads:
                jx = jaxrod_case(load, angle, 24)
                ref = min(shooting(load, angle), key=lambda r: abs(r[0] - jx["tip_angle_deg"]))
                pe = pyelastica_case(python, script, load, angle, n_elem)
                row = {"angle_deg": angle, "load": load, "reference": ref, "jaxrod": jx,
                       "pyelastica": pe, "jaxrod_errors": errors(jx, ref),
                       "pyelastica_errors": errors(pe, ref),
                       "time_ratio": pe["seconds"] / jx["seconds"]}
                rows.append(row)
                print(json.dumps({k: row[k] for k in ("angle_deg", "load", "jaxrod_errors",
                                                       "pyelastica_errors", "time_ratio")}),
                      flush=True)
        # convergence on one case: PyElastica's error against n_elem, jaxrod's against N
        load, angle = 20.0, 90.0
        ref = min(shooting(load, angle), key=lambda r: abs(r[0] - 87.8))
        pe_conv = [{"n_elem": n, **pyelastica_case(python, script, load, angle, n)}
                   for n in ((10, 25) if args.quick else (25, 50, 100))]
        for r in pe_conv:
            r["errors"] = errors(r, ref)
        jx_conv = []
        for n in (4, 6, 8, 10, 12, 16, 20, 24):
            r = jaxrod_case(load, angle, n)
            jx_conv.append({"N": n, **r, "errors": errors(r, ref)})
    best = pe_conv[-1]
    match = next(r for r in jx_conv if r["errors"][0] <= best["errors"][0])
    out = {"rows": rows, "pyelastica_convergence": pe_conv, "jaxrod_convergence": jx_conv,
           "same_accuracy": {"pyelastica": best, "jaxrod": match,
                             "time_ratio": best["seconds"] / match["seconds"]},
           "machine": _machine()}
    dest = Path(args.out)
    dest.mkdir(parents=True, exist_ok=True)
    name = "pyelastica_peer_quick" if args.quick else "pyelastica_peer"
    (dest / f"{name}.json").write_text(json.dumps(out, indent=1))
    (dest / f"{name}.md").write_text(_table(out, n_elem))
    print(_table(out, n_elem))
    return 0


def _machine() -> str:
    import os
    import platform

    return f"{platform.machine()}, {os.cpu_count()} cores"


def _table(out, n_elem) -> str:
    lines = ["# jaxrod against PyElastica (MagnetoPyElastica's validation case)", "",
             f"Machine: {out['machine']}. Errors against shooting (scipy); PyElastica with "
             f"n_elem = {n_elem}, damped to rest (t = 1000 s, dt = 0.05 dl); jaxrod N = 24, "
             "warm.", "",
             "| field angle deg | load | deflection err jaxrod | PyElastica | tip angle err "
             "deg jaxrod | PyElastica | time jaxrod s | PyElastica s | ratio |",
             "|---|---|---|---|---|---|---|---|---|"]
    for r in out["rows"]:
        lines.append(f"| {r['angle_deg']:g} | {r['load']:g} | {r['jaxrod_errors'][0]:.1e} | "
                     f"{r['pyelastica_errors'][0]:.1e} | {r['jaxrod_errors'][1]:.1e} | "
                     f"{r['pyelastica_errors'][1]:.1e} | {r['jaxrod']['seconds']:.2g} | "
                     f"{r['pyelastica']['seconds']:.3g} | {r['time_ratio']:.3g} |")
    lines += ["", "Convergence (load 20, field at 90 degrees): PyElastica's deflection error "
              "against n_elem: " + ", ".join(f"{r['n_elem']}: {r['errors'][0]:.2e} "
                                              f"({r['seconds']:.3g} s)"
                                              for r in out["pyelastica_convergence"]),
              "jaxrod's against N: " + ", ".join(f"{r['N']}: {r['errors'][0]:.1e}"
                                                 for r in out["jaxrod_convergence"]), ""]
    s = out["same_accuracy"]
    lines.append(f"To PyElastica's best accuracy here (deflection error "
                 f"{s['pyelastica']['errors'][0]:.1e}, n_elem = {s['pyelastica']['n_elem']}, "
                 f"{s['pyelastica']['seconds']:.3g} s) jaxrod needs N = {s['jaxrod']['N']} "
                 f"({s['jaxrod']['seconds'] * 1e3:.3g} ms): {s['time_ratio']:.3g}x faster.")
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    sys.exit(main())
