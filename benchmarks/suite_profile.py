"""Where the test suite's time goes: JAX's tracing, lowering and XLA compilation against the
rest, per kind of process and per program, for the suite as the README runs it.

The suite runs once (``python -m pytest``, one xdist worker per core) on this tree's last
commit, taken from git into a temporary directory with a fresh compilation cache, as
``suite_against_release.py`` runs it. Every Python process it starts (the test workers, the
benchmark scripts their quick tests run, notebook kernels, command lines) records JAX's own
compile-time events (``jax.monitoring``: ``/jax/core/compile/jaxpr_trace_duration``,
``jaxpr_to_mlir_module_duration``, ``backend_compile_duration``, and the persistent cache's
retrievals) with the name of the program, and writes them out when it exits. The recorder
is a ``sitecustomize`` module on the suite's ``PYTHONPATH`` (it shadows any other one for
this run); it registers its listener once JAX has been imported, so that a process's own
start-up (and its Ctrl-C handling while JAX is imported) is unchanged.

Programs are counted by name: "small" programs (under 0.15 s of compilation on average)
are the single operations that eager code compiles for each new shape; the others are jitted
programs. Processes that start others (a test worker waiting for a benchmark script) count
their own work only: the times add up across processes as work, not wall time.

Run:  python benchmarks/suite_profile.py [--name NAME]
Writes benchmarks/results/NAME.{json,md} (default suite_profile). About the suite's time.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from common import write_results  # noqa: E402
from suite_against_release import _by_module, _short, export_tree, run_suite  # noqa: E402

#: pytest's own process: it waits for the xdist workers (not counted in the totals).
CONTROLLER = "pytest's controller (waits for the workers)"
#: The xdist workers: they run the tests, and wait for the processes that tests start.
WORKERS = "test workers"

#: Compilations shorter than this (seconds) are counted as eager single operations.
SMALL = 0.15

RECORDER = '''\
import atexit, importlib.abc, importlib.machinery, json, os, sys, time

_out = os.environ.get("JAXROD_SUITE_PROFILE")
_t0 = time.time()
_events, _programs = {}, {}


def _listen(event, duration, **kw):
    total = _events.setdefault(event, [0.0, 0])
    total[0] += duration
    total[1] += 1
    name = kw.get("fun_name", "?")
    name = name[4:-1] if name.startswith("jit(") else name
    kind = event.rsplit("/", 1)[-1]
    if kind in ("backend_compile_duration", "jaxpr_trace_duration"):
        rec = _programs.setdefault(name, {"compile_s": 0.0, "compiles": 0,
                                          "trace_s": 0.0, "traces": 0})
        if kind == "backend_compile_duration":
            rec["compile_s"] += duration
            rec["compiles"] += 1
        else:
            rec["trace_s"] += duration
            rec["traces"] += 1


def _write():
    record = {"argv": [os.path.basename(a) for a in sys.argv[:2]], "wall_s": time.time() - _t0,
              "worker": "PYTEST_XDIST_WORKER" in os.environ and "xdist" in sys.modules,
              "events": _events, "programs": _programs}
    with open(_out, "a") as f:
        f.write(json.dumps(record) + "\\n")


class _AfterJax(importlib.abc.MetaPathFinder):
    """Registers the listener once JAX's monitoring module has been imported (by JAX's own
    import)."""

    def find_spec(self, name, path, target=None):
        if name != "jax._src.monitoring":
            return None
        sys.meta_path.remove(self)
        spec = importlib.machinery.PathFinder.find_spec(name, path)
        if spec is None or spec.loader is None:
            return spec
        run = spec.loader.exec_module

        def exec_module(module):
            run(module)
            module.register_event_duration_secs_listener(_listen)

        spec.loader.exec_module = exec_module
        return spec


if _out:
    sys.meta_path.insert(0, _AfterJax())
    atexit.register(_write)
'''


def _kind(record: dict) -> str:
    if record.get("worker"):
        return WORKERS
    argv = record["argv"]
    first = argv[0] if argv else ""
    if first.endswith(".py") and first not in ("__main__.py", "ipykernel_launcher.py"):
        return "benchmark scripts"
    if first == "ipykernel_launcher.py":
        return "notebook kernels"
    if first == "jaxrod" or first == "__main__.py" and argv[1:2] and argv[1] not in ("-q",
                                                                                  "-p"):
        return "command lines"
    if first == "-c":
        return "python -c snippets"
    if first == "__main__.py":
        return CONTROLLER
    return "other"


def summarise(records: list[dict]) -> dict:
    kinds: dict[str, dict] = {}
    programs: dict[str, dict] = {}
    for r in records:
        ev = r["events"]
        get = lambda k: ev.get(f"/jax/core/compile/{k}", [0.0, 0])[0]  # noqa: E731
        k = kinds.setdefault(_kind(r), {"processes": 0, "wall_s": 0.0, "trace_s": 0.0,
                                                "lower_s": 0.0, "compile_s": 0.0,
                                                "cache_load_s": 0.0})
        k["processes"] += 1
        k["wall_s"] += r["wall_s"]
        k["trace_s"] += get("jaxpr_trace_duration")
        k["lower_s"] += get("jaxpr_to_mlir_module_duration")
        k["compile_s"] += get("backend_compile_duration")
        k["cache_load_s"] += ev.get("/jax/compilation_cache/cache_retrieval_time_sec",
                                    [0.0, 0])[0]
        for name, p in r["programs"].items():
            q = programs.setdefault(name, {"compile_s": 0.0, "compiles": 0,
                                           "trace_s": 0.0, "traces": 0})
            for key in q:
                q[key] += p[key]
    small = [p for p in programs.values()
             if p["compiles"] and p["compile_s"] / p["compiles"] < SMALL]
    small = {"compiles": sum(p["compiles"] for p in small),
             "compile_s": sum(p["compile_s"] for p in small)}
    big = [dict(name=n, **p) for n, p in programs.items()
           if p["compiles"] and p["compile_s"] / p["compiles"] >= SMALL]
    total = {key: sum(k[key] for name, k in kinds.items() if name != CONTROLLER)
             for key in ("trace_s", "lower_s", "compile_s", "cache_load_s")}
    # the workers wait for the processes their tests start: their time is counted there
    total["work_s"] = sum(k["wall_s"] for name, k in kinds.items() if name != CONTROLLER) \
        - sum(k["wall_s"] for name, k in kinds.items() if name not in (CONTROLLER, WORKERS))
    return {"kinds": kinds, "total": total, "small_programs": small,
            "jitted_programs": {"compiles": sum(p["compiles"] for p in big),
                                "compile_s": sum(p["compile_s"] for p in big),
                                "trace_s": sum(p["trace_s"] for p in big)},
            "top_programs": sorted(big, key=lambda p: -(p["compile_s"] + p["trace_s"]))[:20]}


def run() -> dict:
    rev = _short("HEAD")  # now: the working tree's commits may move on while the suite runs
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        tree = export_tree(rev, work / "tree")
        recorder = work / "recorder"
        recorder.mkdir()
        (recorder / "sitecustomize.py").write_text(RECORDER)
        events = work / "events.jsonl"
        suite = run_suite(tree, work, "this", path=(recorder,),
                          env_extra={"JAXROD_SUITE_PROFILE": str(events)})
        records = [json.loads(x) for x in events.read_text().splitlines()] \
            if events.exists() else []
    times = suite.pop("times")
    return {"tree": rev, **suite,
            "test_s": sum(t["s"] for t in times.values()), "by_module": _by_module(times),
            **summarise(records)}


def markdown(res: dict, machine: str) -> str:
    t = res["total"]
    jax_s = t["trace_s"] + t["lower_s"] + t["compile_s"] + t["cache_load_s"]
    lines = [f"# Where the test suite's time goes ({res['tree']})", "",
             f"Machine: {machine}. One run of the suite as the README runs it "
             "(`benchmarks/suite_profile.py`); times are summed over processes (work, not "
             "wall time); a test worker's own time includes its waiting for the processes "
             "its tests start.", "",
             f"- wall time: {res['wall_s'] / 60:.1f} min, tests: "
             + ", ".join(f"{v} {k}" for k, v in sorted(res["counts"].items())),
             f"- work (the processes' time, less the workers' waiting for the processes "
             f"their tests start): {t['work_s']:.0f} s, of which JAX's tracing "
             f"{t['trace_s']:.0f} s, lowering {t['lower_s']:.0f} s, XLA compilation "
             f"{t['compile_s']:.0f} s and loads from the compilation cache "
             f"{t['cache_load_s']:.0f} s: {jax_s:.0f} s ({100 * jax_s / t['work_s']:.0f}%)",
             f"- jitted programs: {res['jitted_programs']['compiles']} compilations "
             f"({res['jitted_programs']['compile_s']:.0f} s) and their tracing "
             f"({res['jitted_programs']['trace_s']:.0f} s); eager single operations: "
             f"{res['small_programs']['compiles']} compilations "
             f"({res['small_programs']['compile_s']:.0f} s)", "",
             "| processes | count | own time s | tracing s | lowering s | compilation s | "
             "cache loads s |", "|---|---|---|---|---|---|---|"]
    for name, k in sorted(res["kinds"].items(), key=lambda kv: -kv[1]["wall_s"]):
        lines.append(f"| {name} | {k['processes']} | {k['wall_s']:.0f} | {k['trace_s']:.0f} | "
                     f"{k['lower_s']:.0f} | {k['compile_s']:.0f} | {k['cache_load_s']:.0f} |")
    lines += ["", "The programs that cost most (compilation and tracing, summed over "
              "processes; `call` is a program of the command line's store, ``jax.export``'s "
              "call compiled):", "", "| program | compilations | compilation s | traces | "
              "tracing s |", "|---|---|---|---|---|"]
    for p in res["top_programs"]:
        lines.append(f"| `{p['name']}` | {p['compiles']} | {p['compile_s']:.0f} | "
                     f"{p['traces']} | {p['trace_s']:.0f} |")
    lines += ["", "Summed test time per module (pytest's, over the workers):", "",
              "| module | s |", "|---|---|"]
    lines += [f"| `{m}` | {s:.0f} |" for m, s in list(res["by_module"].items())[:15]]
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--name", default="suite_profile")
    args = parser.parse_args()
    res = run()
    write_results(HERE / "results", args.name, res,
                  markdown(res, f"{platform.machine()}, {os.cpu_count()} cores"))


if __name__ == "__main__":
    main()
