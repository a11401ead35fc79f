"""Bistability maps: points per second against the number of devices, and a large map's wall
time.

- Throughput: one map of the paper's wire over (track radius, E) inside the bistable region
  (nearly every point on the batched path), one chunk, in a fresh process per device count
  with ``--xla_force_host_platform_device_count`` (on a CPU the virtual devices share its cores,
  so this measures the sharding's overhead, not a speed-up; on a GPU node the same code
  spreads over the real devices). Timed after a warm-up map of the same chunk shape (a
  slightly shifted grid). A device count that gives no result in 15 minutes is reported as
  such (before the batched path solved its small systems in jnp, several virtual CPU devices
  hung inside LAPACK's batched LU: ``jaxrod/solvers/dense.py``).
- A large map over track radius 0.095-0.14 m and E 80-250 GPa (all three solver tiers: the
  region beyond the cusp goes to the batched continuation, the magnet-touching corner is
  refused), on all local devices: wall time and points per second, compilation excluded
  (a warm-up chunk first) and included.

Run:  python benchmarks/design_map.py [--quick] [--points 1000000]
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import RESULTS, write_results  # noqa: E402

WORKER = """\
import json, sys, tempfile, time
import jax
import jaxrod as jr
from jaxrod.params import NDFEB_MAGNET
rod, _ = jr.preset("permanent-magnet")
point = jr.DesignPoint.from_physical(rod, NDFEB_MAGNET)
x, y, chunk = {x!r}, {y!r}, {chunk}
def once(xs, ys):
    spec = jr.MapSpec(point, jr.MapAxis.parse(xs), jr.MapAxis.parse(ys), chunk=chunk)
    with tempfile.TemporaryDirectory() as out:
        t0 = time.perf_counter()
        counts = jr.bistability_map(spec, out, progress=False)
        return time.perf_counter() - t0, counts
warm, _ = once({warm_x!r}, {warm_y!r})
wall, counts = once(x, y)
print("JAXROD-BENCH " + json.dumps({{"devices": len(jax.local_devices()), "wall_s": wall,
                                    "warmup_s": warm, "chunks": counts["chunks"]}}))
"""


def _worker(x, y, chunk, warm_x, warm_y, devices=None, timeout=7200) -> dict:
    env = dict(os.environ)
    if devices:
        env["XLA_FLAGS"] = f"--xla_force_host_platform_device_count={devices}"
    with tempfile.TemporaryDirectory() as work:
        script = Path(work) / "w.py"
        script.write_text(WORKER.format(x=x, y=y, chunk=chunk, warm_x=warm_x, warm_y=warm_y))
        try:
            proc = subprocess.run([sys.executable, str(script)], env=env, capture_output=True,
                                  text=True, timeout=timeout)
        except subprocess.TimeoutExpired:  # a hang (module docstring)
            return {"devices": devices or 1, "timed_out_s": timeout}
    line = [s for s in proc.stdout.splitlines() if s.startswith("JAXROD-BENCH ")]
    if proc.returncode != 0 or not line:
        raise RuntimeError(proc.stderr[-2000:])
    return json.loads(line[0].split(" ", 1)[1])


def run(quick: bool, points: int) -> dict:
    side = 32 if quick else 64
    bistable = (f"track-radius:0.105:0.112:{side}", f"E:150e9:250e9:{side}")
    # the warm-up is a map of the same grid shifted a little (the same programs, other
    # values)
    warm = (f"track-radius:0.1051:0.1121:{side}", f"E:151e9:251e9:{side}")
    rows = []
    for d in ([1, 8] if quick else [1, 2, 4, 8]):
        r = _worker(*bistable, side, *warm, devices=d, timeout=900)
        r["points"] = side * side
        if "timed_out_s" in r:
            print(f"{d} devices: no result in {r['timed_out_s']} s", flush=True)
        else:
            r["points_per_s"] = r["points"] / r["wall_s"]
            print(f"{d} devices: {r['points_per_s']:.0f} points/s", flush=True)
        rows.append(r)
    n = int(round(math.sqrt(points)))
    big_axes = (f"track-radius:0.095:0.14:{n}", f"E:80e9:250e9:{n}")
    chunk = min(100, n)
    big = _worker(*big_axes, chunk, f"track-radius:0.095:0.14:{chunk}",
                  f"E:80e9:250e9:{chunk}")
    big |= {"points": n * n, "grid": [n, n], "chunk": chunk,
            "points_per_s": n * n / big["wall_s"]}
    print(f"{n * n} points: {big['wall_s']:.1f} s", flush=True)
    return {"throughput": rows, "large_map": big, "cpu_count": os.cpu_count()}


def markdown(res: dict) -> str:
    lines = ["# Bistability maps", "",
             f"Machine: {res['cpu_count']} CPU cores. Throughput on a bistable grid (nearly "
             "every point on the batched path), one chunk, warm:", "",
             "| devices | points | wall s | points/s |", "|---|---|---|---|"]
    for r in res["throughput"]:
        if "timed_out_s" in r:
            lines.append(f"| {r['devices']} | {r['points']} | no result in "
                         f"{r['timed_out_s']} s | - |")
        else:
            lines.append(f"| {r['devices']} | {r['points']} | {r['wall_s']:.2f} | "
                         f"{r['points_per_s']:.0f} |")
    b = res["large_map"]
    lines += ["", f"Large map over track radius 0.095-0.14 m and E 80-250 GPa ({b['grid'][0]} x "
              f"{b['grid'][1]} = {b['points']} points, chunks of {b['chunk']}^2, all solver "
              f"tiers): {b['wall_s']:.1f} s warm ({b['points_per_s']:.0f} points/s); the "
              f"warm-up chunk, which compiles the programs, took {b['warmup_s']:.1f} s."]
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="the short form the tests run")
    parser.add_argument("--points", type=float, default=None,
                        help="points of the large map (default 1e4 quick, 1e6 otherwise)")
    parser.add_argument("--out", default=str(RESULTS), help="results folder")
    args = parser.parse_args(argv)
    points = int(args.points or (1e4 if args.quick else 1e6))
    res = run(args.quick, points)
    write_results(Path(args.out), "design_map", res, markdown(res))
    return 0


if __name__ == "__main__":
    sys.exit(main())
