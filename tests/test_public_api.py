"""The public namespace: every name importable, documented, and used by the examples."""

from __future__ import annotations

import ast
import importlib
import importlib.util
import inspect
import json
import re
import subprocess
import sys
from pathlib import Path

import pytest

import jaxrod as jr

ROOT = Path(__file__).resolve().parents[1]

#: Sections whose names implement the paper's mathematics: their docstrings cite it.
CITING = ("Inputs, units and valid ranges", "Scenes (energies)", "Discretisations",
          "Uniform field: the magnetic Greenhill problem",
          "Permanent magnet: branches, folds, hysteresis", "The reduced route",
          "Three dimensions", "Fold curves, the cusp and design maps",
          "Calibration and inverse design")
#: Names in those sections that hold no mathematics of their own (errors, grid specs, I/O).
NOT_MATHEMATICAL = {"ParameterError", "MapAxis", "MapSpec", "read_map", "Prior"}


def test_all_lists_every_section_name_once():
    names = [name for section in jr.API.values() for name in section]
    assert len(names) == len(set(names))
    assert jr.__all__ == names


@pytest.mark.parametrize("name", jr.__all__)
def test_public_name_imports_and_has_its_own_docstring(name):
    obj = getattr(jr, name)
    module, attribute = next(where for section in jr.API.values()
                             for public, where in section.items() if public == name)
    assert obj is getattr(importlib.import_module(module), attribute)  # deep import works
    doc = inspect.getdoc(obj) or ""
    own = obj.__dict__.get("__doc__") if inspect.isclass(obj) else obj.__doc__
    assert own, f"{name} has no docstring of its own"
    assert not doc.startswith(f"{obj.__name__}("), f"{name}: only the dataclass signature"
    assert len(doc.split()) >= 6, f"{name}: docstring too short: {doc!r}"


@pytest.mark.parametrize("name", [n for s in CITING for n in jr.API[s]
                                  if n not in NOT_MATHEMATICAL])
def test_mathematical_names_cite_the_paper(name):
    doc = inspect.getdoc(getattr(jr, name))
    assert re.search(r"paper", doc, re.IGNORECASE), f"{name} does not cite the paper"


def test_star_import_and_unknown_name():
    space: dict = {}
    exec("from jaxrod import *", space)
    assert set(jr.__all__) <= set(space)
    with pytest.raises(AttributeError, match="no attribute 'nonexistent'"):
        jr.nonexistent  # noqa: B018
    assert set(jr.__all__) <= set(dir(jr))


def test_import_is_lazy_and_sets_float64():
    code = ("import sys, jax, jaxrod; "
            "print(json.dumps([jax.config.jax_enable_x64, "
            "sorted(m for m in sys.modules if m.startswith('jaxrod.'))]))")
    out = subprocess.run([sys.executable, "-c", "import json; " + code], check=True,
                         capture_output=True, text=True, cwd=ROOT).stdout
    x64, loaded = json.loads(out)
    assert x64 is True
    analyses = ("jaxrod.plotting", "jaxrod.uniform", "jaxrod.magnet",
                "jaxrod.three_d", "jaxrod.bistability", "jaxrod.inverse", "jaxrod.equilibria")
    assert not [m for m in loaded if m.startswith(analyses)]


def _public_objects() -> dict[int, str]:
    return {id(getattr(jr, name)): name for name in jr.__all__}


def _deep_imports(source: str):
    """(module, attribute) of every ``from jaxrod.X import a`` in Python source, and of
    every ``m.a`` where ``m`` is a jaxrod module imported there."""
    tree = ast.parse(source)
    modules = {}
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and (node.module or "").startswith("jaxrod."):
            for alias in node.names:
                yield node.module, alias.name
                full = f"{node.module}.{alias.name}"
                if importlib.util.find_spec(full.split(".")[0]) and _is_module(full):
                    modules[alias.asname or alias.name] = full
        elif isinstance(node, ast.ImportFrom) and node.module == "jaxrod":
            for alias in node.names:
                if _is_module(f"jaxrod.{alias.name}"):
                    modules[alias.asname or alias.name] = f"jaxrod.{alias.name}"
    for node in ast.walk(tree):
        if (isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name)
                and node.value.id in modules):
            yield modules[node.value.id], node.attr


def _is_module(name: str) -> bool:
    try:
        return importlib.util.find_spec(name) is not None
    except ModuleNotFoundError:
        return False


def _example_sources():
    yield "README.md", "\n".join(re.findall(r"```python\n(.*?)```", (ROOT / "README.md")
                                            .read_text(), re.DOTALL))
    for path in sorted((ROOT / "notebooks").glob("*.ipynb")):
        cells = json.loads(path.read_text())["cells"]
        code = "\n".join("".join(c["source"]) for c in cells if c["cell_type"] == "code")
        yield path.name, "\n".join(line for line in code.splitlines()
                                   if not line.lstrip().startswith(("%", "!")))
    for path in sorted((ROOT / "benchmarks").glob("*.py")):
        yield path.name, path.read_text()
    for path in sorted((ROOT / "docs").glob("*.md")):
        yield path.name, "\n".join(re.findall(r"```python\n(.*?)```", path.read_text(),
                                              re.DOTALL))


def test_examples_use_the_public_names():
    public = _public_objects()
    deep = []
    for where, source in _example_sources():
        for module, attribute in _deep_imports(source):
            obj = getattr(importlib.import_module(module), attribute, None)
            if id(obj) in public:
                deep.append(f"{where}: from {module} import {attribute} "
                            f"(public: jr.{public[id(obj)]})")
    assert not deep, "\n".join(deep)


def test_readme_tour_runs_and_prints_what_it_says():
    """The README's Python tour, run as a newcomer would (in this process), prints what its
    comments say: the rig's folds in the magnet's angle (the paper's 30.128 and 39.308
    degrees at its rounded groups; the shipped file's physical constants give G = 2.20001,
    M = 0.0236029), the two folds in Young's modulus, Euler's buckling of the opposed
    cantilever at pi^2 / 4 in the load (closed form, in tesla), and the batch's verdict."""
    import contextlib
    import io
    import math

    code = re.findall(r"```python\n(.*?)```", (ROOT / "README.md").read_text(), re.DOTALL)
    assert len(code) == 1

    with contextlib.redirect_stdout(io.StringIO()) as printed:  # in this process: its programs
        exec(compile(code[0], "README.md", "exec"), {})
    lines = printed.getvalue().splitlines()
    assert lines[0].startswith("['39.3108") and "'30.1292" in lines[0]
    assert lines[1].startswith("[238837") and ", 137727" in lines[1]
    kind, value = eval(lines[2])[0]
    rig = jr.load_scene("hard-magnetic-cantilever")
    tesla_per_load = 1.25e-3 / rig.scene.value("field0.load")  # the file's B per unit load
    assert kind == "branch_point"
    assert abs(value - math.pi**2 / 4 * tesla_per_load) <= 1e-12
    assert lines[-1] == "True"