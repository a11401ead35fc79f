"""``jaxrod reproduce``: the paper's numbers, recomputed."""

from __future__ import annotations

import json
import sys

from jaxrod.cli._output import _output_dir


def cmd_reproduce(args) -> int:
    from jaxrod.progress import progress_bar
    from jaxrod.reproduce import (
        format_permanent_magnet_report,
        format_uniform_field_report,
        format_youngs_modulus_report,
        permanent_magnet_report,
        uniform_field_report,
        youngs_modulus_report,
    )

    out = _output_dir(args.out) if args.out is not None else None
    sections = (("permanent_magnet", permanent_magnet_report),
                ("uniform_field", uniform_field_report),
                ("youngs_modulus_fit", youngs_modulus_report))
    report = {}
    bar = progress_bar(len(sections), "reproduce", "section", not args.quiet)
    try:
        for name, make in sections:
            report[name] = make()
            bar.update(1)
    except KeyboardInterrupt:
        bar.close()
        report.get("permanent_magnet", {}).pop("_sweep_arrays", None)
        if out is not None:
            partial = report | {"complete": False, "reason": "interrupted (Ctrl-C) after "
                                f"{len(report)} of {len(sections)} sections"}
            (out / "report.json").write_text(json.dumps(partial, indent=2) + "\n")
        print(f"jaxrod reproduce: interrupted after {len(report)} of {len(sections)} sections"
              + (f"; wrote them to {out / 'report.json'} (marked incomplete)" if out else ""),
              file=sys.stderr)
        return 130
    bar.close()
    magnet = report["permanent_magnet"]
    sweep = magnet.pop("_sweep_arrays")
    report = {k: report[k] for k in ("uniform_field", "permanent_magnet", "youngs_modulus_fit")}
    text = (format_uniform_field_report(report["uniform_field"]) + "\n\n"
            + format_permanent_magnet_report(magnet) + "\n\n"
            + format_youngs_modulus_report(report["youngs_modulus_fit"]))
    if out is not None:
        (out / "report.md").write_text(text + "\n")
        (out / "report.json").write_text(json.dumps(report, indent=2) + "\n")
        from jaxrod.plotting import hysteresis_figure, stability_diagram_figure

        stability_diagram_figure(report["uniform_field"]).savefig(
            out / "stability_diagram.png", dpi=120)
        hysteresis_figure(sweep).savefig(out / "hysteresis_E200.png", dpi=120)
        text += (f"\n\nWrote {out / 'report.md'}, report.json, stability_diagram.png and "
                 "hysteresis_E200.png")
    print(json.dumps(report) if args.json else text)
    return 0


def add_reproduce(sub) -> None:
    r = sub.add_parser("reproduce", help="recompute the paper's tables and verdicts")
    r.add_argument("--out", default=None, help="directory for report.md, report.json, PNGs")
    r.add_argument("--json", action="store_true", help="print the report as JSON")
    r.add_argument("--quiet", action="store_true", help="no progress bar")
    r.set_defaults(func=cmd_reproduce)
