"""The test suite of this tree against that of a release, side by side in one run: wall time,
number of tests, and the time of the tests both trees have (matched by their pytest node id),
so that new tests and a slower engine are told apart.

The release is taken from git (``--release REV``, default the tree that closed the one-engine
work) into a temporary directory, and this tree likewise (its last commit: edits that are not
committed are not measured, and the working tree may change while the suites run). Each
suite runs as the README says (``python -m pytest``, one xdist worker per core), in its own
tree, with that tree's package first on the path and a fresh compilation cache; the release
first, then this tree. Per-test times come from
pytest's JUnit XML (call time with its setup and teardown, summed over the workers: work, not
wall time).

Run:  python benchmarks/suite_against_release.py [--release REV] [--name NAME]
      [--this-junit FILE --this-wall-s S]  (this tree's suite from a run made just before)
Writes benchmarks/results/NAME.{json,md} (default suite_against_one_engine). About twice
the suite's time.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import tempfile
import time
import xml.etree.ElementTree as ET
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(HERE))
from against_last_release import export  # noqa: E402

#: The tree that closed the one-engine work.
ONE_ENGINE = "5a545fa"


def export_tree(rev: str, into: Path) -> Path:
    """The whole tree of git revision ``rev`` (package, tests, notebooks, benchmarks),
    unpacked under ``into``."""
    return export(rev, into, paths=())


def _short(rev: str) -> str:
    return subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short", rev], check=True,
                          capture_output=True, text=True).stdout.strip()


def per_test_times(junit: Path) -> dict[str, dict]:
    """node id -> {"s": seconds, "outcome": passed/failed/skipped/error}."""
    out = {}
    for case in ET.parse(junit).iter("testcase"):
        module = case.get("classname", "").replace(".", "/")
        key = f"{module}::{case.get('name')}"
        outcome = "passed"
        for tag in ("failure", "error", "skipped"):
            if case.find(tag) is not None:
                outcome = {"failure": "failed"}.get(tag, tag)
        out[key] = {"s": float(case.get("time", 0.0)), "outcome": outcome}
    return out


def run_suite(tree: Path, work: Path, label: str, path: tuple[Path, ...] = (),
              env_extra: dict | None = None) -> dict:
    """The suite of ``tree`` as the README runs it, that tree's package first on the path
    (then ``path``), a fresh cache folder, and ``env_extra`` in its environment."""
    junit = work / f"{label}.xml"
    cache = work / f"{label}-cache"
    env = os.environ | {"PYTHONPATH": os.pathsep.join(map(str, (tree, *path))),
                        "JAXROD_CACHE_DIR": str(cache)} | (env_extra or {})
    env.pop("JAX_COMPILATION_CACHE_DIR", None)
    t0 = time.perf_counter()
    proc = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider",
                           f"--junitxml={junit}"], cwd=tree, env=env, capture_output=True,
                          text=True)
    wall = time.perf_counter() - t0
    summary = [x for x in proc.stdout.splitlines() if " in " in x and ("passed" in x
                                                                       or "failed" in x)]
    times = per_test_times(junit) if junit.exists() else {}
    counts = {}
    for t in times.values():
        counts[t["outcome"]] = counts.get(t["outcome"], 0) + 1
    print(json.dumps({"tree": label, "wall_s": wall, "returncode": proc.returncode,
                      "counts": counts, "summary": summary[-1:]}), flush=True)
    if proc.returncode:
        print(proc.stdout[-3000:], flush=True)
    return {"wall_s": wall, "returncode": proc.returncode, "counts": counts,
            "summary": summary[-1] if summary else None, "times": times}


def run(release: str, this_junit: Path | None = None, this_wall_s: float | None = None) -> dict:
    """Both suites, the release first; with ``this_junit`` (and its wall time), this tree's
    suite is the run that wrote that file (made just before, on the same machine, at this
    tree's last commit) and only the release's runs here."""
    this = _short("HEAD")  # now: the working tree's commits may move on while the suites run
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        old = export_tree(release, work / "release")
        release_suite = run_suite(old, work, "release")
        if this_junit is None:
            this_suite = run_suite(export_tree(this, work / "this-tree"), work, "this")
        else:
            times = per_test_times(this_junit)
            counts = {}
            for t in times.values():
                counts[t["outcome"]] = counts.get(t["outcome"], 0) + 1
            this_suite = {"wall_s": this_wall_s, "returncode": int(
                counts.get("failed", 0) + counts.get("error", 0) > 0), "counts": counts,
                "summary": f"from {this_junit.name}", "times": times}
        res = {"release": release, "this": this, "release_suite": release_suite,
               "this_suite": this_suite, "order": "the release first" if this_junit is None
               else "this tree's just before the release's"}
    a, b = res["release_suite"]["times"], res["this_suite"]["times"]
    common = sorted(set(a) & set(b))
    res["common"] = {"tests": len(common),
                     "release_s": sum(a[k]["s"] for k in common),
                     "this_s": sum(b[k]["s"] for k in common)}
    res["only_this"] = {"tests": len(set(b) - set(a)),
                        "s": sum(b[k]["s"] for k in set(b) - set(a))}
    res["only_release"] = {"tests": len(set(a) - set(b)),
                           "s": sum(a[k]["s"] for k in set(a) - set(b))}
    res["slowest_common"] = sorted(
        ({"test": k, "release_s": a[k]["s"], "this_s": b[k]["s"]} for k in common),
        key=lambda r: -max(r["release_s"], r["this_s"]))[:15]
    res["slowest_this"] = sorted(({"test": k, "s": v["s"]} for k, v in b.items()),
                                 key=lambda r: -r["s"])[:25]
    res["by_module_this"] = _by_module(b)
    res["by_module_release"] = _by_module(a)
    return res


def _by_module(times: dict) -> dict[str, float]:
    """Summed test time per test module, largest first."""
    out: dict[str, float] = {}
    for k, v in times.items():
        module = k.split("::")[0]
        out[module] = out.get(module, 0.0) + v["s"]
    return dict(sorted(out.items(), key=lambda kv: -kv[1]))


def markdown(res: dict, machine: str) -> str:
    old, new = res["release_suite"], res["this_suite"]
    rel = res["release"]
    n = lambda s: sum(s["counts"].values())
    bad = lambda s: s["counts"].get("failed", 0) + s["counts"].get("error", 0)
    c, only = res["common"], res["only_this"]
    lines = [f"# The test suite: this tree ({res['this']}) against release {rel}", "",
             f"Machine: {machine}. One run of each suite (`python -m pytest`, one worker per "
             f"core), {res.get('order', 'the release first')}; per-test times are pytest's "
             "(setup, call and teardown), summed over the workers.", "",
             f"| | this tree | release {rel} |", "|---|---|---|",
             f"| tests | {n(new)} | {n(old)} |",
             f"| failed or errors | {bad(new)} | {bad(old)} |",
             f"| wall time, min | {new['wall_s'] / 60:.1f} | {old['wall_s'] / 60:.1f} |",
             f"| the {c['tests']} tests both have, summed s | {c['this_s']:.0f} | "
             f"{c['release_s']:.0f} |",
             f"| tests only this tree has | {only['tests']} ({only['s']:.0f} s) | - |",
             f"| tests only the release has | - | {res['only_release']['tests']} "
             f"({res['only_release']['s']:.0f} s) |", "",
             f"The tests both have take {c['this_s'] / c['release_s']:.2f}x their time in the "
             "release.", "", "The slowest tests both have:", "",
             f"| test | this tree, s | release {rel}, s |", "|---|---|---|"]
    for r in res["slowest_common"]:
        lines.append(f"| `{r['test']}` | {r['this_s']:.1f} | {r['release_s']:.1f} |")
    lines += ["", "Summed time per test module:", "",
              f"| module | this tree, s | release {rel}, s |", "|---|---|---|"]
    for module, t in res["by_module_this"].items():
        t_old = res["by_module_release"].get(module)
        lines.append(f"| `{module}` | {t:.0f} | {'-' if t_old is None else f'{t_old:.0f}'} |")
    lines += ["", "The slowest tests of this tree:", "", "| test | s |", "|---|---|"]
    for r in res["slowest_this"]:
        lines.append(f"| `{r['test']}` | {r['s']:.1f} |")
    return "\n".join(lines) + "\n"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--release", default=ONE_ENGINE)
    ap.add_argument("--name", default="suite_against_one_engine")
    ap.add_argument("--this-junit", type=Path, default=None,
                    help="JUnit XML of a run of this tree's suite made just before (with "
                    "--this-wall-s): only the release's suite runs")
    ap.add_argument("--this-wall-s", type=float, default=None)
    args = ap.parse_args()
    if (args.this_junit is None) != (args.this_wall_s is None):
        ap.error("--this-junit and --this-wall-s go together")
    res = run(args.release, args.this_junit, args.this_wall_s)
    machine = f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores"
    out = HERE / "results"
    slim = {k: v for k, v in res.items()}
    for key in ("release_suite", "this_suite"):
        slim[key] = {k: v for k, v in res[key].items() if k != "times"}
    (out / f"{args.name}.json").write_text(json.dumps(slim, indent=1))
    (out / f"{args.name}.md").write_text(markdown(res, machine))
    print(markdown(res, machine))


if __name__ == "__main__":
    main()
