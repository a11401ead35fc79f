import json
import subprocess
import sys

import pytest

from jaxrod.cli import main


def run(*args):
    return subprocess.run([sys.executable, "-m", "jaxrod.cli", *args], capture_output=True,
                          text=True, timeout=600)


def test_greenhill_json_keys(capsys):
    assert main(["greenhill", "--G", "10", "--support", "clamped", "--A", "5", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert set(out) == {"G", "support", "beta0", "A_crit", "A2", "criticality", "G_crit", "A",
                        "stable"}
    assert out["stable"] is True and out["support"] == "clamped"
    assert main(["greenhill", "--G", "10", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert "stable" not in out and "A" not in out


def test_greenhill_physical_inputs(capsys):
    assert main(["greenhill", "--preset", "clamped-12cm", "--E", "100e9", "--field", "off",
                 "--json"]) == 0
    off = json.loads(capsys.readouterr().out)
    assert off["stable"] is False and off["A"] == 0.0
    assert main(["greenhill", "--preset", "clamped-12cm", "--E", "100e9", "--json"]) == 0
    on = json.loads(capsys.readouterr().out)
    assert on["stable"] is True and on["A"] == pytest.approx(138.24)
    assert main(["greenhill", "--diameter", "0.3e-3", "--length", "0.11", "--support", "pinned",
                 "--field", "off"]) == 0
    assert "UNSTABLE" in capsys.readouterr().out


@pytest.mark.parametrize("argv, name", [
    (["greenhill", "--G", "-3"], "G"),
    (["greenhill", "--G", "nan"], "G"),
    (["greenhill"], "G"),
    (["greenhill", "--G", "2", "--n", "2"], "N"),
    (["greenhill", "--length", "-0.1", "--diameter", "1e-4"], "length"),
    (["greenhill", "--preset", "clamped-8cm", "--E", "0"], "E"),
    (["greenhill", "--G", "1", "--support", "hinged"], "support"),
])
def test_bad_input_exit_2_one_line(argv, name):
    proc = run(*argv)
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and name in lines[0], proc.stderr


def test_reproduce_writes_report(tmp_path):
    proc = run("reproduce", "--out", str(tmp_path))
    assert proc.returncode == 0, proc.stderr
    assert "tab:clamped" in proc.stdout and "MISMATCH" not in proc.stdout
    report = json.loads((tmp_path / "report.json").read_text())["uniform_field"]
    assert (tmp_path / "stability_diagram.png").stat().st_size > 10_000
    assert (tmp_path / "report.md").exists()
    # every printed number of both tables matches at its printed digits (rounded or cut)
    for row in report["clamped"] + report["pinned"]:
        assert all(m in ("round", "trunc") for m in row["match"]), row
    assert report["G_crit_match"] == "round"
    assert report["critical_length_match"] == ["round", "round"]
    assert report["L_stab_match"] == "round"
