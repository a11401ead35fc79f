import json
import subprocess
import sys

import pytest
from command_line import run_cli

from jaxrod.cli import main


def test_greenhill_json_keys(capsys):
    assert main(["greenhill", "--G", "10", "--support", "clamped", "--A", "5", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert set(out) == {"G", "support", "beta0", "A_crit", "A2", "criticality", "G_crit", "A",
                        "stable", "inputs", "converged"}
    assert out["inputs"]["N"] == {"value": 32, "unit": "", "source": "default: from G"}
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
    proc = run_cli(*argv)
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and name in lines[0], proc.stderr


def test_reproduce_writes_report(tmp_path):
    proc = subprocess.run([sys.executable, "-m", "jaxrod.cli", "reproduce", "--out",
                           str(tmp_path)], capture_output=True, text=True, timeout=3000)
    assert proc.returncode == 0, proc.stderr
    assert "tab:clamped" in proc.stdout and "MISMATCH" not in proc.stdout.split("## Permanent")[0]
    assert "Permanent magnet" in proc.stdout and (tmp_path / "hysteresis_E200.png").exists()
    report = json.loads((tmp_path / "report.json").read_text())["uniform_field"]
    assert (tmp_path / "stability_diagram.png").stat().st_size > 10_000
    assert (tmp_path / "report.md").exists()
    # every printed number of both tables matches at its printed digits (rounded or cut)
    for row in report["clamped"] + report["pinned"]:
        assert all(m in ("round", "trunc") for m in row["match"]), row
    assert report["G_crit_match"] == "round"
    assert report["critical_length_match"] == ["round", "round"]
    assert report["L_stab_match"] == "round"
    reduced = json.loads((tmp_path / "report.json").read_text())["permanent_magnet"][
        "reduced_route"]
    assert len(reduced) == 4 and all(r["converged"] for r in reduced)
    assert all(abs(r["alpha_star_minus_moore_spence_deg"]) < 1e-10 for r in reduced)
    assert [r["hypotheses_hold"] for r in reduced] == [True, True, True, False]
    for case in json.loads((tmp_path / "report.json").read_text())["permanent_magnet"]["cases"]:
        v = case["out_of_plane"]
        assert v["stable_out_of_plane"] and v["max_coupling"] == 0.0
        assert v["min_eig_perp_on_stable"] > 1.0 and v["max_rel_diff_formula"] < 1e-9
        assert [f["smallest_is_in_plane"] for f in v["folds"]] == [True, True]
    assert "planar loop stable in 3D" in proc.stdout


MAGNET = ["--G", "2.2", "--M", "0.0236", "--D", str(11.25 / 9.2)]


def test_folds_json(capsys):
    assert main(["folds", *MAGNET, "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["converged"] is True
    assert [f["kind"] for f in out["folds"]] == ["lower", "upper"]
    for f in out["folds"]:
        assert {"kind", "alpha_deg", "q", "tip_deg", "dF_dalpha_sign", "d2F_dq2_sign"} <= set(f)
        assert f["dF_dalpha_sign"] == 1
    assert [f["d2F_dq2_sign"] for f in out["folds"]] == [-1, 1]
    assert out["hysteresis_width_deg"] == pytest.approx(
        out["folds"][1]["alpha_deg"] - out["folds"][0]["alpha_deg"])


def test_folds_from_preset_and_no_fold(capsys):
    assert main(["folds", "--preset", "permanent-magnet", "--E", "100e9", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["G"] == pytest.approx(4.4, abs=1e-4) and len(out["folds"]) == 2
    assert main(["folds", "--G", "2.2", "--M", "0.002", "--D", "1.22", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["folds"] == [] and out["hysteresis_width_deg"] is None


def test_sweep_and_branch_write_files(tmp_path, capsys):
    assert main(["sweep", *MAGNET, "--step", "1", "--out", str(tmp_path / "s")]) == 0
    lines = (tmp_path / "s" / "sweep.csv").read_text().splitlines()
    assert lines[0] == "direction,alpha_deg,tip_deg,q,snapped" and len(lines) == 202
    assert (tmp_path / "s" / "sweep.png").stat().st_size > 10_000
    summary = json.loads((tmp_path / "s" / "sweep.json").read_text())
    assert len(summary["snaps"]) == 4 and summary["converged"]
    assert main(["branch", *MAGNET, "--out", str(tmp_path / "b")]) == 0
    assert (tmp_path / "b" / "branch.png").exists() and (tmp_path / "b" / "branch.csv").exists()


@pytest.mark.parametrize("argv, name", [
    (["folds", "--G", "2.2", "--M", "0.02", "--D", "1.0"], "D"),
    (["folds", "--G", "2.2", "--M", "0.02", "--D", "1.05", "--magnet-radius", "0.1"],
     "touch"),
    (["folds", "--G", "2.2", "--D", "1.2"], "M"),
    (["folds", "--G", "2.2", "--M", "-1", "--D", "1.2"], "M"),
    (["folds", "--preset", "permanent-magnet", "--length", "0.11"], "tip cannot touch"),
    (["folds", "--G", "20", "--M", "0.01", "--D", "1.2", "--method", "reduced"], "2M/delta^3"),
])
def test_magnet_bad_input_exit_2(argv, name):
    proc = run_cli(*argv)
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and name in lines[0], proc.stderr


def test_track_json_and_files(tmp_path, capsys):
    assert main(["track", *MAGNET, "--alpha0", "20", "--tilt", "90", "--json",
                 "--out", str(tmp_path)]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["converged"] and len(out["folds"]) == 2 and out["max_out_of_plane"] > 0.5
    # the rod snaps where the magnet's polar angle reaches the planar folds (cf. `folds`)
    assert main(["folds", *MAGNET, "--json"]) == 0
    found = json.loads(capsys.readouterr().out)["folds"]
    planar = sorted(f["alpha_deg"] for f in found)
    polar = sorted(f["magnet_polar_deg"] for f in out["folds"])
    assert polar == pytest.approx(planar, abs=1e-9)
    # with the tip leaning as far as in the plane (its polar angle the planar tip angle)
    tips = sorted(f["tip_polar_deg"] for f in out["folds"])
    assert tips == pytest.approx(sorted(f["tip_deg"] for f in found), abs=1e-9)
    lines = (tmp_path / "track.csv").read_text().splitlines()
    assert lines[0].startswith("t_deg,") and len(lines) == out["points"] + 1
    with pytest.raises(SystemExit) as stop:
        main(["track", *MAGNET, "--alpha0", "95"])
    assert stop.value.code == 2


PAPER_POINT = ["--G", "2.2", "--M", "0.0236", "--D", "1.2228260869565217"]


def test_cusp_json(capsys):
    assert main(["cusp", *PAPER_POINT, "--vary", "D", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["vary"] == "D" and out["converged"] is True
    assert {"along", "value", "q", "tip_angle_deg", "cubic_coefficient"} <= set(out["cusp"])
    # the fold system's value, against the one-parameter fold pair just before the cusp
    from jaxrod.magnet.diagram import make_scene
    from jaxrod.magnet.folds import locate_folds

    rep = locate_folds(make_scene(2.2, 0.0236, out["cusp"]["along"] - 3e-3))
    low, up = rep.folds
    assert rep.converged and up.alpha_deg - low.alpha_deg < 0.1  # ~ (D_c - D)^(3/2)
    assert abs(low.alpha_deg - out["cusp"]["value"]) < 0.5
    assert abs(up.alpha_deg - out["cusp"]["value"]) < 0.5


def test_foldcurve_writes_files(tmp_path, capsys):
    out = tmp_path / "fc"
    assert main(["foldcurve", *PAPER_POINT, "--vary", "D", "--to", "1.5", "--out", str(out),
                 "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["cusp"] is not None and summary["converged"]
    for name in ("foldcurve.csv", "foldcurve.json", "foldcurve.png"):
        assert (out / name).exists()
    header = (out / "foldcurve.csv").read_text().splitlines()[0]
    assert header.startswith("curve,D,alpha_deg,tip_angle_deg,q,dF_dvalue,d2F_dq2")


@pytest.mark.parametrize("argv, name", [
    (["cusp", *PAPER_POINT, "--vary", "K"], "--vary"),
    (["cusp", *PAPER_POINT, "--vary", "E"], "vary"),
    (["foldcurve", *PAPER_POINT, "--vary", "D", "--to", "0.95"], "D must stay in"),
    (["foldcurve", "--preset", "permanent-magnet", "--vary", "track-radius", "--to", "0.095"],
     "track-radius must stay in"),
    (["cusp", "--G", "2.2", "--M", "0.001", "--D", "1.2228", "--vary", "D"],
     "no fold to start from"),
    (["foldcurve", *PAPER_POINT, "--vary", "D", "--to", "1.4", "--out", "/proc/nope"], "out"),
])
def test_fold_curve_bad_input_exit_2(argv, name):
    proc = run_cli(*argv)
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and name in lines[0], proc.stderr
