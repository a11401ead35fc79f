"""This tree against the last release, side by side in one run: the first-call compile time
of every entry point, the fold pairs per second of the paper's scene, and the command line's
whole process against a bare ``import jax``.

The last release is taken from git (``--release REV``, default the commit that closed the
fast-path issue) into a temporary directory; each measurement runs in a fresh Python process
whose ``PYTHONPATH`` selects one of the two trees, the two trees alternating, so that a
change of the machine's load hits both. No persistent compilation cache anywhere (the
compile times are what a first run pays; the command line's warm-cache process is measured
separately, with a cache of its own per tree).

Run:  python benchmarks/against_last_release.py [--release REV] [--repeats 3] [--name NAME]
Writes benchmarks/results/NAME.{json,md} (default against_last_release; the every-rig work
against the tree that closed the one-engine work: --release 5a545fa --name
against_one_engine).
"""

from __future__ import annotations

import argparse
import io
import json
import os
import subprocess
import sys
import tarfile
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(HERE))
from compile_time import _own_caches_only  # noqa: E402

#: The last landed state before the one-engine work.
LAST_RELEASE = "47adaa8"
D_EXP = 11.25 / 9.2
SCENE = f"jr.magnet_scene(2.2, 0.0236, {D_EXP!r})"
POINT = f"jr.DesignPoint.from_groups(2.2, 0.0236, {D_EXP!r})"
PAIRS = ("np.full(1000, 2.2), np.linspace(0.022, 0.03, 1000), np.full(1000, 1.2)")
#: name -> the call whose first run is timed (the same public call in both trees)
ENTRY_POINTS = {
    "greenhill": "jr.greenhill(10.0, 'clamped', A=5.0)",
    "folds": f"jr.folds({SCENE})",
    "fold_pair": f"jr.fold_pair({SCENE})",
    "fold_angles": f"jr.fold_angles(2.2, 0.0236, {D_EXP!r})",
    "fold_pairs (K = 1000)": f"jr.fold_pairs({PAIRS})",
    "diagram": f"jr.diagram({SCENE})",
    "sweep": f"jr.sweep({SCENE}, step_deg=1.0)",
    "fold_curves": f"jr.fold_curves({POINT}, 'D', 1.3)",
    "cusp": f"jr.cusp({POINT}, 'D')",
    "fit (E alone)": "jr.fit_youngs_modulus([-25.0, 38.0, 24.0, -42.0], 1.0, True)",
    "fit (E, offset)": "jr.fit([-25.0, 38.0, 24.0, -42.0])",
    "reduced_folds": f"jr.reduced_folds({SCENE})",
    # any scene (the generic folds were jr.scene_folds before the one-vocabulary change)
    "folds of a scene (magnet.alpha)": f"(getattr(jr, 'scene_folds', None) or jr.folds)("
                                       f"{SCENE}.scene, 'magnet.alpha', 0.0, 1.5707963267948966)",
    "branch of a scene (gravity.G)": f"jr.branch({SCENE}.scene, 'gravity.G', 2.2, 4.0)",
}

CHILD = """
import json, time, warnings
warnings.simplefilter("ignore")
import jax, numpy as np
import jaxrod as jr
t1 = time.perf_counter()
jax.block_until_ready({call})
t2 = time.perf_counter()
warm = float("inf")
for _ in range({warm_runs}):
    t = time.perf_counter()
    jax.block_until_ready({call})
    warm = min(warm, time.perf_counter() - t)
print("RESULT " + json.dumps({{"first_call_s": t2 - t1, "warm_s": warm,
                               "where": jr.__file__}}))
"""


def export(rev: str, into: Path, paths: tuple[str, ...] = ("jaxrod",)) -> Path:
    """The ``paths`` of git revision ``rev`` (default the package; () the whole tree),
    unpacked under ``into``."""
    data = subprocess.run(["git", "-C", str(ROOT), "archive", rev, *paths], check=True,
                          capture_output=True).stdout
    with tarfile.open(fileobj=io.BytesIO(data)) as tar:
        tar.extractall(into, filter="data")
    return into


def child(call: str, path: Path, warm_runs: int = 3) -> dict:
    code = CHILD.format(call=call, warm_runs=warm_runs)
    env = _own_caches_only(os.environ) | {"PYTHONPATH": str(path), "JAXROD_NO_CACHE": "1"}
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          env=env, timeout=1800, cwd=tempfile.gettempdir())
    line = [x for x in proc.stdout.splitlines() if x.startswith("RESULT ")]
    if proc.returncode or not line:
        return {"error": proc.stderr[-400:]}
    out = json.loads(line[0][7:])
    if not out.pop("where").startswith(str(path)):
        raise RuntimeError(f"the child did not import jaxrod from {path}")
    out["compile_s"] = max(out["first_call_s"] - out["warm_s"], 0.0)
    return out


def process_s(argv: list[str], path: Path, env: dict) -> float:
    t0 = time.perf_counter()
    subprocess.run([sys.executable, *argv], check=True, capture_output=True, timeout=1800,
                   env=_own_caches_only(os.environ) | {"PYTHONPATH": str(path)} | env,
                   cwd=tempfile.gettempdir())
    return time.perf_counter() - t0


def run(release: str, repeats: int) -> dict:
    with tempfile.TemporaryDirectory() as tmp:
        trees = {"this tree": ROOT, f"release {release}": export(release, Path(tmp) / "old")}
        rows = []
        for name, call in ENTRY_POINTS.items():
            row = {"entry": name}
            for label, path in trees.items():
                got = [child(call, path) for _ in range(repeats)]
                ok = [g for g in got if "error" not in g]
                row[label] = (min((g["compile_s"] for g in ok), default=None),
                              min((g["warm_s"] for g in ok), default=None))
                if len(ok) < len(got):
                    row[label + " error"] = next(g["error"] for g in got if "error" in g)
            rows.append(row)
            print(json.dumps(row), flush=True)
        # the trees alternating, ``repeats`` fresh processes each: the best warm time of each
        best = {label: float("inf") for label in trees}
        for _ in range(repeats):
            for label, path in trees.items():
                r = child(f"jr.fold_pairs({PAIRS})", path, warm_runs=15)
                best[label] = min(best[label], r.get("warm_s", float("inf")))
        throughput = {label: 1000.0 / t if t < float("inf") else None
                      for label, t in best.items()}
        print(json.dumps({"fold pairs per s": throughput}), flush=True)
        cli = {}
        argv = ["-m", "jaxrod.cli", "folds", "--G", "2.2", "--M", "0.0236", "--D",
                repr(D_EXP), "--json"]
        for label, path in trees.items():
            bare = min(process_s(["-c", "import jax"], path, {}) for _ in range(repeats))
            off = min(process_s(argv, path, {"JAXROD_NO_CACHE": "1"}) for _ in range(repeats))
            with tempfile.TemporaryDirectory() as cache:
                process_s(argv, path, {"JAXROD_CACHE_DIR": cache})
                warm = min(process_s(argv, path, {"JAXROD_CACHE_DIR": cache})
                           for _ in range(repeats))
            cli[label] = {"import_jax_s": bare, "folds_no_cache_s": off,
                          "folds_warm_cache_s": warm, "warm_over_import_jax": warm / bare}
        print(json.dumps({"cli": cli}), flush=True)
        return {"release": release, "labels": list(trees), "rows": rows,
                "fold_pairs_per_s": throughput, "cli": cli, "repeats": repeats}


def markdown(res: dict, machine: str) -> str:
    new, old = res["labels"]
    lines = [f"# This tree against {old}", "", f"Machine: {machine}. Each number the "
             f"best of {res['repeats']} fresh processes; no persistent compilation cache.", "",
             f"| entry point | compile s ({new}) | compile s ({old}) | ratio | warm s ({new}) "
             f"| warm s ({old}) |", "|---|---|---|---|---|---|"]
    for r in res["rows"]:
        (cn, wn), (co, wo) = r[new], r[old]
        ratio = f"{cn / co:.2f}" if cn and co else "-"
        fmt = lambda v: "-" if v is None else f"{v:.3g}"
        lines.append(f"| {r['entry']} | {fmt(cn)} | {fmt(co)} | {ratio} | {fmt(wn)} | "
                     f"{fmt(wo)} |")
    tp = res["fold_pairs_per_s"]
    lines += ["", f"Fold pairs per second, the paper's scene at K = 1000 (warm, best of 15 "
              f"calls in each of {res['repeats']} fresh processes, the trees alternating): "
              f"{tp[new]:.4g} ({new}) against {tp[old]:.4g} ({old}), ratio "
              f"{tp[new] / tp[old]:.3f}.", "",
              "| command line (`jaxrod folds`, one process) | " + new + " | " + old + " |",
              "|---|---|---|"]
    for key, label in (("import_jax_s", "bare `import jax`, s"),
                       ("folds_no_cache_s", "no cache, s"),
                       ("folds_warm_cache_s", "warm cache, s"),
                       ("warm_over_import_jax", "warm cache / bare import jax")):
        lines.append(f"| {label} | {res['cli'][new][key]:.3g} | {res['cli'][old][key]:.3g} |")
    return "\n".join(lines) + "\n"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--release", default=LAST_RELEASE)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--name", default="against_last_release",
                    help="the results' file name (another for another --release: "
                    "against_one_engine for the tree that closed the one-engine work)")
    args = ap.parse_args()
    res = run(args.release, args.repeats)
    import platform

    machine = f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores"
    out = HERE / "results"
    (out / f"{args.name}.json").write_text(json.dumps(res, indent=1))
    (out / f"{args.name}.md").write_text(markdown(res, machine))
    print(markdown(res, machine))


if __name__ == "__main__":
    main()
