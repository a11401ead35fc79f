"""The documentation site builds in strict mode (warnings are errors, every reference
resolved), and a broken reference does fail that build."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

pytestmark = pytest.mark.xdist_group("docs")


def _build(source: Path, out: Path) -> subprocess.CompletedProcess:
    # the notebooks are executed by tests/test_notebooks.py; here only their rendering
    env = os.environ | {"JAXROD_DOCS_EXECUTE": "0"}
    return subprocess.run([sys.executable, "-m", "sphinx", "-W", "--keep-going", "-n", "-q",
                           "-b", "html", str(source), str(out)], capture_output=True,
                          text=True, env=env, timeout=600)


def _copy_docs(tmp_path: Path) -> Path:
    """docs/ and what its pages refer to (notebooks, benchmark figures), outside the tree."""
    tree = tmp_path / "tree"
    for name in ("docs", "notebooks", "benchmarks/results"):
        shutil.copytree(ROOT / name, tree / name, ignore=shutil.ignore_patterns(
            "_build", "_generated"))
    return tree / "docs"


def test_docs_build_strictly(tmp_path):
    proc = _build(ROOT / "docs", tmp_path / "html")
    assert proc.returncode == 0, proc.stderr[-3000:]
    api = (tmp_path / "html" / "_generated" / "api")
    text = "".join(p.read_text() for p in api.glob("section_*.html"))
    import jaxrod as jr

    for name in jr.__all__:
        assert f'id="jaxrod.{name}"' in text, f"{name} missing from the API reference"
    for nb in (ROOT / "notebooks").glob("*.ipynb"):
        assert (tmp_path / "html" / "_generated" / "notebooks" / f"{nb.stem}.html").exists()


def test_a_broken_reference_fails_the_build(tmp_path):
    docs = _copy_docs(tmp_path)
    (docs / "usage.md").write_text((docs / "usage.md").read_text()
                                   + "\nSee {py:func}`jaxrod.no_such_function`.\n")
    proc = _build(docs, tmp_path / "html")
    assert proc.returncode != 0
    assert "no_such_function" in proc.stderr
