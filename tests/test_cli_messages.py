"""Messages that name the problem (each failed on the last release): design's varied inputs
and bounds, a family of designs, priors on fixed inputs and their standard deviations, a
sign slip in the measured angles, fold-curve statuses in plain words, and the package's
version and public names."""

import json
import subprocess
import sys
from pathlib import Path

import pytest
from command_line import run_cli

import jaxrod as jr
from jaxrod.cli import main


@pytest.mark.parametrize("argv, says", [
    (["design", "--G", "2.2", "--capture", "30", "--release", "40", "--vary", "D,Q"],
     "vary: unknown input 'Q'"),
    (["design", "--G", "2.2", "--capture", "30", "--release", "40", "--vary", "D,D"],
     "vary: an input is named twice"),
    (["design", "--G", "2.2", "--capture", "30", "--release", "40", "--vary",
      "track-radius,M"], "vary: track-radius is a physical input"),
    (["design", "--G", "2.2", "--M", "0.0236", "--capture", "30", "--release", "40",
      "--vary", "D", "--bounds", "D=0.9:1.5"], "bounds D:"),
    (["fit", "--angles", "-25", "38", "24", "-42", "--prior", "remanence=8e5:4e4"],
     "prior remanence: remanence is not free"),
    (["fit", "--angles", "-25", "38", "24", "-42", "--free", "E,remanence", "--prior",
      "remanence=8e5:-4e4"], "prior remanence: prior sd"),
    (["equilibrium", str(Path(jr.__file__).parent / "rigs" / "hard-magnetic-cantilever.toml"),
      "--centred"],
     "centred: only for a rod that carries its frame"),
    (["branch", "--layer-width", "0.1"], "layer-width: name a scene file first"),
])
def test_one_line_that_names_the_problem(argv, says):
    proc = run_cli(*argv)
    assert proc.returncode == 2, proc.stderr
    assert says in proc.stderr and len(proc.stderr.strip().splitlines()) == 1, proc.stderr


def test_three_inputs_for_two_targets_are_a_family(capsys):
    code = main(["design", "--G", "2.2", "--M", "0.0236", "--D", "1.2", "--capture", "30",
                 "--release", "40", "--vary", "D,M,G", "--json"])
    out = json.loads(capsys.readouterr().out)
    assert code == 0 and out["family"] == 1 and len(out["solutions"]) >= 2


def test_a_sign_slip_gets_a_hint(capsys):
    assert main(["fit", "--angles", "25", "-38", "-24", "42", "--json"]) in (0, 1)
    out = json.loads(capsys.readouterr().out)
    assert any("signs are the opposite of the convention" in w for w in out["warnings"])
    assert main(["fit", "--angles", "-25", "38", "24", "-42", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert not any("signs" in w for w in out["warnings"])


def test_fold_curve_statuses_in_plain_words():
    from jaxrod.solvers.fold_curve import CURVE_STATUS

    for text in CURVE_STATUS.values():
        assert "max_cusps" not in text and "lam" not in text.split(), text


def test_version_and_public_names():
    assert jr.__version__ != "unknown" and jr.__version__.count(".") >= 1
    assert jr.FitSetup is not None and jr.FoldPairs is not None


def test_no_fold_is_listed_twice():
    """At (2.2, 0.015, 1.0231) two of the branch's four fold starts reached one fold, which
    was listed twice; the branch is re-traced with a finer step and four distinct folds
    are listed (a second S-shape near 78-79 degrees)."""
    report = jr.folds(jr.magnet_scene(2.2, 0.015, 1.0231))
    alphas = sorted(f.alpha_deg for f in report.folds)
    assert len(alphas) == 4 and min(b - a for a, b in zip(alphas, alphas[1:])) > 1e-3
    assert report.converged


def test_a_design_whose_branch_has_four_folds_says_so(capsys):
    assert main(["design", "--G", "2.2", "--M", "0.0236", "--D", "1.2228", "--capture", "25",
                 "--release", "85", "--vary", "D,M", "--json"]) == 1
    out = json.loads(capsys.readouterr().out)
    assert out["verified"] is False and "finds 4 folds" in out["check"]


def test_enable_caches_keeps_programs_on_disk(tmp_path):
    """``jr.enable_caches`` (documented in the README's tour) sets JAX's persistent cache
    and jaxrod's store of traced programs to one folder, which a first call fills (in a
    fresh process: it changes the process's JAX configuration)."""
    code = (f"import jax, jaxrod as jr; d = jr.enable_caches({str(tmp_path)!r}); "
            "assert jax.config.jax_compilation_cache_dir == str(d); "
            "jr.folds(jr.magnet_scene(2.2, 0.0236, 1.2228), n=12); "
            "import pathlib; p = pathlib.Path(d); "
            "assert any(p.glob('exported/*')), list(p.iterdir()); "
            "assert any(f.name != 'exported' for f in p.iterdir()); print('ok')")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=600)
    assert proc.returncode == 0 and "ok" in proc.stdout, proc.stderr[-2000:]


def test_the_readme_says_how_long_the_docs_take_and_how_to_skip_the_notebooks():
    from pathlib import Path

    root = Path(__file__).resolve().parent.parent
    readme = (root / "README.md").read_text()
    assert "JAXROD_DOCS_EXECUTE=0" in readme and "minutes" in readme
    assert 'os.environ.get("JAXROD_DOCS_EXECUTE") == "0"' in (root / "docs" / "conf.py").read_text()
