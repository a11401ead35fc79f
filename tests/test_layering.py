"""The import layering of the package (docs/layout.md): a module imports only from its own
package or from the layers below it, so the data flow parameters -> discretisation -> energy
-> derivatives -> solvers -> analyses -> command line is the folder structure. Parsed with
``ast`` (module-level and function-level imports alike)."""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1] / "jaxrod"

#: Layers, lowest first; a unit is a top-level module or package of jaxrod.
LAYERS = [
    {"status", "params", "design_point", "spectral", "programs", "progress"},
    {"discretise", "derivatives", "stored"},
    {"scenes"},
    {"solvers"},
    {"equilibria"},
    {"uniform"},
    {"magnet"},
    {"three_d", "bistability", "dynamics", "twisted"},
    {"inverse"},
    {"plotting", "reproduce"},
    {"cli"},
]
#: Ground-floor units used by everything (the package's own __init__ is the public table).
LEVEL = {unit: i for i, layer in enumerate(LAYERS) for unit in layer}


def _unit(path: Path) -> str:
    rel = path.relative_to(ROOT)
    return rel.parts[0].removesuffix(".py")


def _imported_units(tree: ast.AST):
    for node in ast.walk(tree):
        names = []
        if isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names = [node.module]
        elif isinstance(node, ast.Import):
            names = [a.name for a in node.names]
        for name in names:
            parts = name.split(".")
            if parts[0] == "jaxrod" and len(parts) > 1:
                yield node.lineno, parts[1]


def test_every_unit_has_a_layer():
    units = {_unit(p) for p in ROOT.rglob("*.py")} - {"__init__"}
    assert units <= set(LEVEL), f"units without a layer: {sorted(units - set(LEVEL))}"


def test_no_module_imports_from_a_higher_layer():
    bad = []
    for path in sorted(ROOT.rglob("*.py")):
        unit = _unit(path)
        if unit == "__init__":
            continue
        for line, target in _imported_units(ast.parse(path.read_text())):
            if target in LEVEL and LEVEL[target] > LEVEL[unit]:
                bad.append(f"{path.relative_to(ROOT.parent)}:{line} ({unit}, layer "
                           f"{LEVEL[unit]}) imports jaxrod.{target} (layer {LEVEL[target]})")
    assert not bad, "\n".join(bad)


def test_the_layering_test_catches_an_upward_import(tmp_path):
    tree = ast.parse("from jaxrod.magnet.diagram import make_scene\n")
    ups = [t for _, t in _imported_units(tree) if LEVEL[t] > LEVEL["solvers"]]
    assert ups == ["magnet"]
    tree = ast.parse("def f():\n    from jaxrod.inverse import fit\n")
    assert [t for _, t in _imported_units(tree) if LEVEL[t] > LEVEL["magnet"]] == ["inverse"]


def test_modules_stay_small():
    """One concept per module: no module over 500 lines, no command-line module over 300."""
    big = []
    for path in sorted(ROOT.rglob("*.py")):
        n = len(path.read_text().splitlines())
        limit = 300 if _unit(path) == "cli" else 500
        if n > limit:
            big.append(f"{path.relative_to(ROOT.parent)}: {n} lines (limit {limit})")
    assert not big, "\n".join(big)


