"""A magnet moved along a path that passes within the rod's reach: the branch stops where
the magnet enters it (the part before kept, a status that says why), and the command line
says so with exit status 1 and its JSON; the entry against its closed form."""

import contextlib
import io
import json
import math

import numpy as np
import pytest

import jaxrod as jr
from jaxrod.cli import main
from jaxrod.scenes.files import load
from jaxrod.scenes.terms import Zeeman
from jaxrod.status import SolverError, Status

#: A magnet on a horizontal rail at height 0.8 rod lengths: it enters the reach (|c| = 1)
#: at along = 2.5 - sqrt(1 - 0.8^2) = 1.9.
RAIL = """units = "nondimensional"
[magnetisation]
kind = "hard"
[[field]]
kind = "dipole"
M = 2.0
position = [-2.5, 0.8]
moment_direction = [0.0, 1.0]
rail = [1.0, 0.0]
along = 0.0
"""
ENTRY = 2.5 - math.sqrt(1.0 - 0.8**2)


@pytest.fixture(scope="module")
def rail(tmp_path_factory):
    path = tmp_path_factory.mktemp("rigs") / "rail.toml"
    path.write_text(RAIL)
    return path


def test_the_branch_stops_where_the_magnet_enters_the_reach(rail):
    file = load(rail)
    b = jr.branch(file.scene, "field0.along", 0.0, 4.0, n=12)
    assert b.status[-1] == Status.MAGNET_IN_REACH and not b.complete
    assert np.all(b.value <= ENTRY) and b.value[-1] >= ENTRY - 0.1
    assert np.max(b.residual_norm) <= 1e-10  # what was kept is converged
    with pytest.raises(SolverError, match="reach"):
        jr.folds(file.scene, "field0.along", 0.0, 4.0, n=12)


def _run(argv):
    with contextlib.redirect_stdout(io.StringIO()) as out:
        code = main(argv)
    return code, json.loads(out.getvalue())


@pytest.mark.parametrize("command", ["folds", "branch"])
def test_the_command_line_says_the_path_failed(rail, command):
    """Exit 1 (a path that failed), the JSON still printed: converged false, the status
    that says why, where the branch ended, and no fold or branch point beyond it (the
    folds at 1e88 and -4.9e149 printed before came from the magnet inside the rod)."""
    code, out = _run([command, str(rail), "--vary", "field.0.along", "--from", "0", "--to",
                      "4", "--n", "12", "--json"])
    assert code == 1
    assert out["converged"] is False and out["status"] == "magnet_in_reach"
    assert out["last_value"] <= ENTRY
    for point in out["folds"] + out.get("branch_points", []):
        assert 0.0 <= point["value"] <= ENTRY


def test_a_magnet_within_reach_at_the_start_is_refused(rail):
    file = load(rail)
    with pytest.raises(jr.ParameterError, match="field0.along"):
        jr.branch(file.scene, "field0.along", 2.2, 4.0, n=12)


def test_an_equilibrium_whose_ramp_stopped_short_is_not_converged(monkeypatch):
    """The load ramp cut short (a ramp of 3 points: capacity full before full load), Newton
    then polished from where it stopped: the status says NOT_CONVERGED, and ``converged``
    agrees (it said True beside that status, and the command line exited 0)."""
    from jaxrod.equilibria import equilibrium as module

    monkeypatch.setattr(module, "CAPACITY", 3)
    scene = jr.Scene({"bending": jr.Bending(), "field": Zeeman(5.0, 1.0)})
    eq = jr.equilibrium(scene, n=7, throw=False)  # a degree no other test traces
    assert eq.status == Status.NOT_CONVERGED and eq.converged is False
    # a branch from that ramp says so beside its own end (the same program)
    from jaxrod.equilibria.trace import branch_options, trace

    key = scene.inputs()[0]
    b = trace(scene, key, 5.0, 6.0, n=7, options=branch_options(3))
    assert Status.NOT_CONVERGED in b.status and not b.complete


def test_a_range_the_branch_cannot_cover_says_so():
    """jaxrod folds RIG --to 1e9: the branch stops at its capacity far short of the range's
    end; it printed the folds it met and exited 0. Now: exit 1, status capacity_full, and
    where it ended."""
    code, out = _run(["folds", "hard-magnetic-cantilever", "--vary", "field.0.angle_deg",
                      "--from", "90", "--to", "1e9", "--json"])
    assert code == 1 and out["converged"] is False
    assert out["status"] == "capacity_full" and out["last_value"] < 1e9
