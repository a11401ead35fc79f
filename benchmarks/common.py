"""What the benchmark scripts share: their command line (``--quick``, ``--out``) and how
they write results (JSON, markdown, PNG under ``benchmarks/results/`` by default)."""

from __future__ import annotations

import argparse
import json
from collections.abc import Callable
from pathlib import Path

RESULTS = Path(__file__).resolve().parent / "results"


def write_results(out: Path, name: str, result: dict, markdown: str, figure=None) -> None:
    """out/name.json, out/name.md and (when given) out/name.png; prints the markdown."""
    out.mkdir(parents=True, exist_ok=True)
    (out / f"{name}.json").write_text(json.dumps(result, indent=1))
    (out / f"{name}.md").write_text(markdown)
    if figure is not None:
        figure.savefig(out / f"{name}.png", dpi=110)
    print(markdown)


def benchmark_main(doc: str, run: Callable[[bool], dict], write: Callable[[dict, Path], None],
                   argv=None, quick_help: str = "the short form the tests run") -> int:
    """Parse ``--quick`` and ``--out``, then ``write(run(quick), out)``."""
    parser = argparse.ArgumentParser(description=doc.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help=quick_help)
    parser.add_argument("--out", default=str(RESULTS), help="results folder")
    args = parser.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    write(run(args.quick), out)
    return 0
