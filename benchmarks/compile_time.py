"""Cold start, JIT compile and warm time of each entry point, with and without JAX's
persistent compilation cache; the CLI's whole-process time for one fold pair against
AUTO-07p's whole-process time.

Each measurement runs in a fresh Python process: ``import`` time (cold start), the first
call (compile + run) and the best warm call. "cache: off" uses no persistent cache; "cache:
cold" fills an empty cache directory; "cache: warm" is a new process reading it (what a user
sees from the second run on). The CLI keeps its cache under ~/.cache/jaxrod (JAXROD_CACHE_DIR
moves it, JAXROD_NO_CACHE=1 switches it off).

Run:  python benchmarks/compile_time.py [--quick] [--auto]
Writes benchmarks/results/compile_time.{json,md}.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
D_EXP = 11.25 / 9.2
MAGNET = ["--G", "2.2", "--M", "0.0236", "--D", repr(D_EXP)]

SCENE = f"jr.magnet_scene(2.2, 0.0236, {D_EXP!r})"
ENTRY_POINTS = {  # (the names to load before timing, the call)
    "greenhill": ("jr.greenhill", "jr.greenhill(10.0, 'clamped', A=5.0)"),
    "folds (locate_folds)": ("jr.folds, jr.magnet_scene", f"jr.folds({SCENE})"),
    "fold_pair": ("jr.fold_pair, jr.magnet_scene", f"jr.fold_pair({SCENE})"),
    "folds --method reduced": ("jr.reduced_folds, jr.magnet_scene",
                               f"jr.reduced_folds({SCENE})"),
    "branch (trace_diagram)": ("jr.diagram, jr.magnet_scene", f"jr.diagram({SCENE})"),
    "sweep": ("jr.sweep, jr.magnet_scene", f"jr.sweep({SCENE})"),
    "fit": ("jr.fit_youngs_modulus",
            "jr.fit_youngs_modulus([-25.0, 38.0, 24.0, -42.0], 1.0, True)"),
}

CHILD = """
import json, time
t0 = time.perf_counter()
import jax
import jaxrod as jr
{cache}
{imports}
t1 = time.perf_counter()
jax.block_until_ready({call})
t2 = time.perf_counter()
warm = float("inf")
for _ in range(3):
    t = time.perf_counter()
    jax.block_until_ready({call})
    warm = min(warm, time.perf_counter() - t)
print("RESULT " + json.dumps({{"import_s": t1 - t0, "first_call_s": t2 - t1, "warm_s": warm}}))
"""

CACHE = """
jax.config.update("jax_compilation_cache_dir", {path!r})
jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.0)
"""


def child(imports: str, call: str, cache_dir: str | None) -> dict:
    code = CHILD.format(cache=CACHE.format(path=cache_dir) if cache_dir else "",
                        imports=imports, call=call)
    t0 = time.perf_counter()
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          env=_own_caches_only(os.environ), timeout=1800)
    process = time.perf_counter() - t0
    line = [x for x in proc.stdout.splitlines() if x.startswith("RESULT ")]
    if proc.returncode or not line:
        return {"error": proc.stderr[-500:]}
    out = json.loads(line[0][7:])
    out["compile_s"] = max(out["first_call_s"] - out["warm_s"], 0.0)
    out["process_s"] = process
    return out


#: Variables that would give a measured process a compilation cache it did not ask for (the
#: test suite sets them).
_CACHE_VARIABLES = ("JAXROD_NO_CACHE", "JAXROD_CACHE_DIR", "JAX_COMPILATION_CACHE_DIR",
                    "JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS")


def _own_caches_only(environ) -> dict:
    """The environment less every cache setting, so that each run here gets exactly the
    cache it asks for."""
    return {k: v for k, v in environ.items() if k not in _CACHE_VARIABLES}


def cli_process(argv: list[str], env: dict) -> float:
    t0 = time.perf_counter()
    proc = subprocess.run([sys.executable, "-m", "jaxrod.cli", *argv], capture_output=True,
                          text=True, env=_own_caches_only(os.environ) | env, timeout=1800)
    if proc.returncode:
        raise RuntimeError(proc.stderr[-500:])
    return time.perf_counter() - t0


def run(quick: bool, auto: bool) -> dict:
    names = ["greenhill"] if quick else list(ENTRY_POINTS)
    rows = []
    for name in names:
        imports, call = ENTRY_POINTS[name]
        with tempfile.TemporaryDirectory() as cache:
            for mode, cache_dir in (("off", None), ("cold", cache), ("warm", cache)):
                r = child(imports, call, cache_dir) | {"entry": name, "cache": mode}
                rows.append(r)
                print(json.dumps(r), flush=True)
    cli = {}
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-c", "import jax"], check=True, timeout=300,
                   env=_own_caches_only(os.environ))
    cli["import_jax_process_s"] = time.perf_counter() - t0
    with tempfile.TemporaryDirectory() as cache:
        argv = ["folds", *MAGNET, "--json"]
        cli["folds_no_cache_s"] = cli_process(argv, {"JAXROD_NO_CACHE": "1"})
        cli["folds_cache_cold_s"] = cli_process(argv, {"JAXROD_CACHE_DIR": cache})
        cli["folds_cache_warm_s"] = cli_process(argv, {"JAXROD_CACHE_DIR": cache})
    print(json.dumps(cli), flush=True)
    if auto:
        sys.path.insert(0, str(HERE))
        import auto07p

        r = auto07p.run_auto(2.2, 0.0236, D_EXP, 10, 4)
        cli["auto07p_process_s"] = r.get("process_s")
        cli["auto07p_first_process_s"] = r.get("first_process_s")
        cli["auto07p_mesh"] = "NTST=10, NCOL=4"
    return {"rows": rows, "cli": cli}


def markdown(res: dict, device: str) -> str:
    lines = ["# Compile time and cold start", "", f"Machine: {device}", "",
             "| entry point | persistent cache | import s | compile s | warm s | whole process s |",
             "|---|---|---|---|---|---|"]
    for r in res["rows"]:
        if "error" in r:
            lines.append(f"| {r['entry']} | {r['cache']} | failed | | | |")
            continue
        lines.append(f"| {r['entry']} | {r['cache']} | {r['import_s']:.2f} | "
                     f"{r['compile_s']:.2f} | {r['warm_s']:.4f} | {r['process_s']:.2f} |")
    c = res["cli"]
    lines += ["", "Whole process, one fold pair (`jaxrod folds ... --json`, locate_folds with "
              "the diagram):", "",
              f"- no persistent cache: {c['folds_no_cache_s']:.2f} s",
              f"- empty cache (first run): {c['folds_cache_cold_s']:.2f} s",
              f"- cache filled (every later run): {c['folds_cache_warm_s']:.2f} s",
              f"- the floor, a bare `python -c \"import jax\"` in the same run: "
              f"{c['import_jax_process_s']:.2f} s (warm cache / floor: "
              f"{c['folds_cache_warm_s'] / c['import_jax_process_s']:.1f}x)"]
    if c.get("auto07p_process_s"):
        lines += [f"- AUTO-07p whole `python run.py` session ({c['auto07p_mesh']}): "
                  f"{c['auto07p_process_s']:.2f} s (first, compiling the equations: "
                  f"{c['auto07p_first_process_s']:.2f} s)"]
    return "\n".join(lines)


def main(argv=None) -> int:
    import platform

    import jax

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="one entry point")
    parser.add_argument("--auto", action="store_true", help="include AUTO-07p's process time")
    parser.add_argument("--out", default=str(HERE / "results"))
    args = parser.parse_args(argv)
    res = run(args.quick, args.auto)
    device = (f"{platform.machine()}, {os.cpu_count()} cores, jax {jax.__version__} on "
              f"{jax.devices()[0].platform}")
    res["device"] = device
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "compile_time.json").write_text(json.dumps(res, indent=1))
    (out / "compile_time.md").write_text(markdown(res, device))
    print(markdown(res, device))
    return 0


if __name__ == "__main__":
    sys.exit(main())
