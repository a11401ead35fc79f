import json
import os
import subprocess
import sys
from pathlib import Path

from conftest import TEST_XLA_FLAG

BENCH = Path(__file__).resolve().parent.parent / "benchmarks"


def run_quick(script, tmp_path):
    """The benchmark's quick form, its programs compiled as users' are (without the tests'
    XLA option: they time what they run)."""
    flags = os.environ.get("XLA_FLAGS", "").replace(TEST_XLA_FLAG, "").strip()
    env = {k: v for k, v in os.environ.items() if k != "XLA_FLAGS"}
    env |= {"XLA_FLAGS": flags} if flags else {}
    proc = subprocess.run([sys.executable, str(BENCH / script), "--quick", "--out",
                           str(tmp_path)], capture_output=True, text=True, timeout=3600,
                          env=env)
    assert proc.returncode == 0, proc.stderr[-2000:]
    return json.loads((tmp_path / script.replace(".py", ".json")).read_text())


def test_greenhill_convergence_quick(tmp_path):
    result = run_quick("greenhill_convergence.py", tmp_path)
    # spectral convergence: round-off level reached well before N = 48
    assert all(v is not None and v <= 48 for v in result["N_for_1e-10"].values())


def test_magnet_performance_quick(tmp_path):
    result = run_quick("magnet_performance.py", tmp_path)
    for E in ("200", "100"):
        assert result["convergence"][E]["N_for_1e-10_deg"] is not None
        assert result["timings"][E]["fold_pair_error_deg"] < 1e-10
    assert (tmp_path / "magnet_performance.png").exists()


def test_extreme_quick(tmp_path):
    result = run_quick("extreme.py", tmp_path)
    for row in result["rows"]:
        assert row["converged"], row
        assert row["folds"] or "no fold" in row["message"]
        if row["folds"] and "max_difference_deg" in row["reduced"]:
            assert row["reduced"]["max_difference_deg"] < 1e-9, row
    for g in result["greenhill"]:
        assert g["N_for_1e-10"] is not None and g["N_for_1e-10"] <= g["default_N"], g


def test_error_vs_time_quick(tmp_path):
    result = run_quick("error_vs_time.py", tmp_path)
    methods = {r["method"] for r in result["rows"]}
    assert {"scipy solve_bvp + natural continuation", "paper's sine series + BFGS",
            "jaxrod reduced route", "jaxrod continuation only"} <= methods
    for r in result["rows"]:
        if r["method"] in ("jaxrod Moore-Spence (fold_pair)", "jaxrod reduced route") \
                and r["setting"] == "N=12":
            assert r["error_deg"] < 1e-10
    assert (tmp_path / "error_vs_time.png").exists()
    assert all(q["ratio"] > 1 for q in result["ratios"])


def test_throughput_quick(tmp_path):
    result = run_quick("throughput.py", tmp_path)
    for r in result["rows"]:
        assert r["converged_fraction"] == 1.0
        if r["dtype"] == "float32":
            assert r["max_error_vs_float64_deg"] < 1e-2
    assert result["baseline_fold_angles"]["max_difference_fold_pairs_vs_fold_angles_deg"] < 1e-9


def test_compile_time_quick(tmp_path):
    result = run_quick("compile_time.py", tmp_path)
    assert all("error" not in r for r in result["rows"])
    assert result["cli"]["folds_cache_warm_s"] > 0


def test_fit_performance_quick(tmp_path):
    # also checks that the vmapped batch and the one-by-one fits agree
    result = run_quick("fit_performance.py", tmp_path)
    assert result["converged"] == result["batch_size"]
    assert result["one_fit_warm_s"] < 5.0


def test_conditioning_quick(tmp_path):
    # the paper's claim: the full Newton matrix blows up at the fold, the reduced one does not
    studies = run_quick("conditioning.py", tmp_path)
    assert len(studies) == 2
    for c in studies.values():
        assert c["full"][0] > 1e3 * c["full"][-1] / 10 and c["full"][0] > 1e6
        assert max(c["reduced"]) < 100 and max(c["moore_spence"]) < 1e4
        assert max(c["w_problem"]) / min(c["w_problem"]) < 1.1


def test_three_d_cost_quick(tmp_path):
    result = run_quick("three_d_cost.py", tmp_path)
    for r in result["rows"]:
        assert r["converged"], r
        # the 3D solve restricted to the plane is the planar one: equal accuracy
        assert abs(r["fold_error_3d_deg"] - r["fold_error_planar_deg"]) < 1e-10
        assert abs(r["equilibrium_error_3d_deg"] - r["equilibrium_error_planar_deg"]) < 1e-10
    assert (tmp_path / "three_d_cost.png").exists()


def test_dense_solve_quick(tmp_path):
    # the vectorised elimination solves the same systems as LAPACK (diagonally dominant)
    result = run_quick("dense_solve.py", tmp_path)
    for r in result["rows"]:
        assert r["max_difference"] < (1e-12 if r["dtype"] == "float64" else 1e-4), r


def test_fold_curves_quick(tmp_path):
    result = run_quick("fold_curves.py", tmp_path)
    assert result["jaxrod"]["cusp_D_error"] < 1e-11
    rows = result["convergence"]["rows"]
    assert rows[-1]["cusp_D_error"] < 1e-11 and rows[-1]["second_cusp_D_error"] < 1e-8
    assert all(r["moore_spence_cond"] < 1e6 for r in result["conditioning"])


def test_calibration_quick(tmp_path):
    """40 synthetic experiments: every fit converges with all three deviations, and the
    coverage of each 68% interval is within 3 binomial standard deviations of 0.68."""
    result = run_quick("calibration.py", tmp_path)
    assert result["fits_failed"] == 0 and result["with_two_folds"] == 40
    for c in result["coverage"].values():
        assert abs(c["covered_68"] - 0.68) <= 3 * (0.68 * 0.32 / 40) ** 0.5


def test_fold_pair_coverage_quick(tmp_path):
    """``fold_pairs`` against ``locate_folds`` on 137 sets (the D sweep at the paper's G and
    M, a D-M map across the cusp, random sets of the design ranges): no set missed,
    spurious, off by more than 1e-9 degrees or left unknown."""
    result = run_quick("fold_pair_coverage.py", tmp_path)
    for row in result["rows"]:
        assert row["agree"] == row["sets"], row
        assert row["missed"] == row["spurious"] == row["off"] == row["unknown"] == 0, row
    assert set(result["throughput"][0]["pairs_per_s"]) >= {"fold_pairs (all tiers)",
                                                            "tier 1 alone (fold_pairs_program)"}


def test_fold_map_against_folds_quick(tmp_path):
    result = run_quick("fold_map_against_folds.py", tmp_path)
    assert result["sets"] == 100 and result["disagreements"] == 0, result["rows"]
    assert result["bistable_sets"] > 0


def test_design_against_ga_quick(tmp_path):
    """The shape design's peers on one problem: every method reaches the target's shape
    (jaxrod and the finite-difference least squares to 1e-8 degrees), jaxrod in fewer
    evaluations of the forward model than either."""
    (problem,) = run_quick("design_against_ga.py", tmp_path)["problems"]
    ours, fd, ga = problem["rows"]
    assert ours["converged"] and ours["shape_error_deg"] <= 1e-8
    assert fd["shape_error_deg"] <= 1e-8
    assert ours["evaluations"] < fd["evaluations"] < ga["evaluations"]
