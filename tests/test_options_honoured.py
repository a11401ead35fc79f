"""Every option is honoured or refused, and the output records what was used: ``map`` and
``design`` compute at the N they are given (the last release computed both at N = 12 and
recorded the N given)."""

import json

import numpy as np

from jaxrod.bistability import design_map
from jaxrod.bistability.design_map import read_store
from jaxrod.cli import BATCH_N, main
from jaxrod.inverse import fit


def test_the_command_line_default_is_the_programs_default():
    assert BATCH_N == design_map.MAP_N == fit.MODEL_N


def _map(tmp_path, capsys, *extra):
    out = tmp_path / ("map" + "".join(extra).replace("-", "_"))
    assert main(["map", "--G", "2.2", "--M", "0.0236", "--D", "1.2", "--x", "D:1.1:1.2:2",
                 "--y", "M:0.0236:0.025:2", "--chunk", "4", "--out", str(out), "--quiet",
                 "--no-plot", "--json", *extra]) == 0
    return json.loads(capsys.readouterr().out), read_store(out), out


def test_map_computes_at_the_n_it_records(tmp_path, capsys):
    coarse, a, out = _map(tmp_path, capsys, "--n", "4")
    default, b, _ = _map(tmp_path, capsys)
    assert coarse["inputs"]["N"] == {"value": 4, "unit": "", "source": "given"}
    assert default["inputs"]["N"] == {"value": BATCH_N, "unit": "", "source": "default"}
    attrs = json.loads((out / "map.zarr" / ".zattrs").read_text())
    assert json.loads(attrs["jaxrod_map"])["n"] == 4
    # N = 4 is ~1e-3 degrees off the converged folds at these clearances (docs/accuracy.md)
    assert (a["status"] == 0).all() and (b["status"] == 0).all()
    assert 1e-7 < np.max(np.abs(a["capture_deg"] - b["capture_deg"])) < 1e-1


def test_design_computes_at_the_n_it_records(capsys):
    answers = {}
    for n in ("4", "12"):
        assert main(["design", "--G", "2.2", "--M", "0.0236", "--D", "1.2228", "--capture",
                     "30", "--release", "40", "--vary", "D,M", "--n", n, "--json"]) in (0, 1)
        answers[n] = json.loads(capsys.readouterr().out)
        assert answers[n]["inputs"]["N"]["value"] == int(n) and answers[n]["n"] == int(n)
    d4, d12 = (answers[n]["D"] for n in ("4", "12"))
    assert d4 != d12  # the model's folds, and so the design, depend on N
    assert answers["12"]["converged"] is True and answers["4"]["verified"] is False
