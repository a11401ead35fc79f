"""Sphinx configuration: API pages generated from ``jaxrod.API``, the notebooks executed and
rendered, Markdown pages by MyST."""

from __future__ import annotations

import os
import re
import shutil
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(ROOT))

import jaxrod  # noqa: E402

project = "jaxrod"
author = "the jaxrod developers"
release = version = __import__("importlib.metadata").metadata.version("jaxrod")

extensions = ["sphinx.ext.autodoc", "sphinx.ext.napoleon", "sphinx.ext.mathjax", "myst_nb"]
source_suffix = {".rst": "restructuredtext", ".md": "myst-nb", ".ipynb": "myst-nb"}
exclude_patterns = ["_build", "figures"]
#: The notebooks are executed when the site is built (``JAXROD_DOCS_EXECUTE=0`` skips it:
#: the tests build the site that way, strictly, and execute the notebooks separately).
nb_execution_mode = "off" if os.environ.get("JAXROD_DOCS_EXECUTE") == "0" else "force"
nb_execution_timeout = 900
nb_execution_raise_on_error = True
myst_heading_anchors = 3
suppress_warnings = ["myst.header"]  # notebooks start at any heading level

autodoc_typehints = "none"           # the docstrings say what each argument is
autodoc_member_order = "bysource"
autodoc_default_options = {"members": False}
nitpicky = True
html_theme = "alabaster"
html_title = f"jaxrod {release}"

GENERATED = HERE / "_generated"


def _write_api() -> None:
    """One page per section of ``jaxrod.API``, every public name documented under it."""
    (GENERATED / "api").mkdir(parents=True, exist_ok=True)
    index = ["API reference", "=============", "",
             "Everything below is importable from the top level: ``import jaxrod as jr``, "
             "then ``jr.<name>``. Deep imports (``jaxrod.magnet.diagram``, ...) keep "
             "working but are not the interface.", "", ".. toctree::", "   :maxdepth: 1", ""]
    for k, (section, names) in enumerate(jaxrod.API.items()):
        page = f"section_{k:02d}"
        index.append(f"   {page}")
        lines = [section, "=" * len(section), "", ".. currentmodule:: jaxrod", ""]
        for name in names:
            obj = getattr(jaxrod, name)
            kind = ("autoexception" if isinstance(obj, type) and issubclass(obj, BaseException)
                    else "autoclass" if isinstance(obj, type) else "autofunction")
            lines += [f".. {kind}:: {name}", ""]
        (GENERATED / "api" / f"{page}.rst").write_text("\n".join(lines))
    (GENERATED / "api" / "index.rst").write_text("\n".join(index) + "\n")


def _copy_notebooks() -> None:
    target = GENERATED / "notebooks"
    target.mkdir(parents=True, exist_ok=True)
    for path in sorted((ROOT / "notebooks").glob("*.ipynb")):
        shutil.copyfile(path, target / path.name)


_write_api()
_copy_notebooks()


_LITERAL = re.compile(r"(``.+?``)")


def _escape(line: str) -> str:
    """Escape the characters reStructuredText would read as markup, outside ``code``."""
    parts = _LITERAL.split(line)
    for j in range(0, len(parts), 2):
        parts[j] = re.sub(r"(?<!\\)([|*])", r"\\\1", parts[j])
    return "".join(parts)


def _module_lines(lines: list[str]) -> list[str]:
    """Module docstrings are plain text: their indented blocks (equations, tables) become
    literal blocks, bullet continuations stay, and the rest is escaped."""
    out, i, bullet = [], 0, False
    while i < len(lines):
        line = lines[i]
        indented = line.startswith(" ") and line.strip()
        if indented and bullet and not (out and not out[-1].strip()):
            out.append(_escape(line))
        elif indented:
            if out and out[-1].strip():
                out.append("")
            out += ["::", ""]
            while i < len(lines) and (lines[i].startswith(" ") or not lines[i].strip()):
                out.append("    " + lines[i] if lines[i].strip() else "")
                i += 1
            out.append("")
            bullet = False
            continue
        else:
            bullet = line.lstrip().startswith("- ") or (bullet and bool(line.strip()))
            out.append(_escape(line))
        i += 1
    return out


def _escape_plain_maths(app, what, name, obj, options, lines) -> None:
    """The docstrings write maths as plain text (|x|, alpha*, theta'^2)."""
    lines[:] = _module_lines(lines) if what == "module" else [_escape(x) for x in lines]


def setup(app):
    app.connect("autodoc-process-docstring", _escape_plain_maths, priority=600)
