import json
import subprocess
import sys
from pathlib import Path

import pytest

BENCH = Path(__file__).resolve().parent.parent / "benchmarks"


@pytest.mark.parametrize("script", ["greenhill_convergence.py"])
def test_benchmark_quick_runs(script, tmp_path):
    proc = subprocess.run([sys.executable, str(BENCH / script), "--quick", "--out",
                           str(tmp_path)], capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr[-2000:]
    result = json.loads((tmp_path / script.replace(".py", ".json")).read_text())
    # spectral convergence: round-off level reached well before N = 48
    assert all(v is not None and v <= 48 for v in result["N_for_1e-10"].values())
