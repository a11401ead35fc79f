"""Fits and designs on any scene file: the rail rig's inputs from its folds (computed by
shooting, an independent method), a design verified by shooting at the answer, and the
generic fit of the paper's rig against the paper's own calibration program."""

import json
import math

import numpy as np
import pytest
from test_scene_files import RAIL, _cli, rail_folds_by_shooting

import jaxrod as jr
from jaxrod.inverse.scene_fit import design_folds, fit_folds
from jaxrod.params import ParameterError
from jaxrod.scenes.files import load


@pytest.fixture(scope="module")
def rail(tmp_path_factory):
    path = tmp_path_factory.mktemp("rig") / "rail.toml"
    path.write_text(RAIL)
    return path


def test_fit_recovers_the_magnet_from_folds_computed_by_shooting(rail):
    """The folds at M = 0.25, height 1.2 by shooting; the fit starts at M = 0.2, height 1.22
    and recovers both to 1e-8 (two folds, two inputs: an exact fit)."""
    data = rail_folds_by_shooting(0.25, 1.2)
    file = load(rail, ["field.0.M=0.2", "field.0.position.1=1.22"])
    key, _ = file.input_of("field.0.position.0")
    fit = fit_folds(file.scene, key, (0.0, 1.5), data, ["field0.M", "field0.position.2"],
                    sigma=1e-3)
    assert fit.converged, fit.reason
    assert abs(fit.estimates["field0.M"] - 0.25) <= 1e-8
    assert abs(fit.estimates["field0.position.2"] - 1.2) <= 1e-8
    assert all(abs(r) <= 1e-9 for r in fit.residuals)
    assert all(s > 0 for s in fit.std.values())


def test_design_hits_targets_verified_by_shooting(rail):
    """Release at 1.05 and capture at 0.99 rod lengths along the rail: the design's magnet,
    checked by shooting at the answer (1e-8) and by a fresh continuation (1e-9)."""
    file = load(rail, ["field.0.M=0.2", "field.0.position.1=1.22"])
    key, _ = file.input_of("field.0.position.0")
    d = design_folds(file.scene, key, (0.0, 1.5), [1.05, 0.99],
                     ["field0.M", "field0.position.2"], bounds={"field0.M": (0.05, 0.5)})
    assert d.converged, d.reason
    M, z = d.estimates["field0.M"], d.estimates["field0.position.2"]
    release, capture = rail_folds_by_shooting(M, z)
    assert abs(release - 1.05) <= 1e-8 and abs(capture - 0.99) <= 1e-8
    again = jr.folds(file.scene.replace("field0.M", M).replace("field0.position.2", z),
                           key, 0.0, 1.5)
    assert [abs(f.value - t) <= 1e-9 for f, t in zip(again, (1.05, 0.99))] == [True, True]


def test_impossible_targets_are_reported(rail):
    """The release comes before the capture along the rail: targets in the other order
    cannot be hit; the design says so."""
    file = load(rail, ["field.0.M=0.2", "field.0.position.1=1.22"])
    d = design_folds(file.scene, "field0.position.0", (0.0, 1.5), [0.95, 1.0],
                     ["field0.M", "field0.position.2"])
    assert not d.converged and "miss the targets" in d.reason


def test_a_fit_starts_from_guesses_near_the_refined_folds(rail):
    """The fit's start (``fold_guesses``: the branch without its spectrum, stopped after the
    folds the data need) lies within one continuation step (ds_max = 0.05 of the range) of
    each fold that ``folds`` refines; asked for more folds than the range holds it gives
    what there is, and the fit says the data need more."""
    from jaxrod.equilibria.folds import fold_guesses

    file = load(rail, ["field.0.M=0.2", "field.0.position.1=1.22"])
    key = "field0.position.0"
    refined = jr.folds(file.scene, key, 0.0, 1.5)
    z, status = fold_guesses(file.scene, key, 0.0, 1.5, 5)
    assert len(z) == len(refined) == 2 and status.ok
    for f, row in zip(refined, z):
        assert abs(1.5 * row[-1] - f.value) <= 0.05 * 1.5
    with pytest.raises(ParameterError, match="the data need 3"):
        fit_folds(file.scene, key, (0.0, 1.5), [1.0, 0.98, 0.9], ["field0.M"],
                  readout=[(0, 1), (1, 1), (2, 1)])


@pytest.mark.parametrize("free, match", [(["field0.position.0"], "met along"),
                                         (["field0.Q"], "field0.Q"), ([], "at least one")])
def test_bad_fit_requests(rail, free, match):
    file = load(rail)
    with pytest.raises((ParameterError, ValueError), match=match):
        fit_folds(file.scene, "field0.position.0", (0.0, 1.5), [1.0, 0.98], free)


def test_cli_fit_and_design_on_a_scene_file(rail):
    base = [str(rail), "--set", "field.0.M=0.2", "--set", "field.0.position.1=1.22"]
    data = rail_folds_by_shooting(0.25, 1.2)
    proc = _cli("fit", *base, "--vary", "field.0.position.0", "--from", "0", "--to", "1.5",
                "--folds", *(repr(float(v)) for v in data), "--free",
                "field.0.M,field.0.position.1", "--sigma", "1e-3", "--json")
    assert proc.returncode == 0, proc.stderr
    out = json.loads(proc.stdout)
    assert abs(out["estimates"]["field.0.M"] - 0.25) <= 1e-8 and out["converged"]
    proc = _cli("design", *base, "--path", "field.0.position.0", "--from", "0", "--to", "1.5",
                "--targets", "1.05", "0.99", "--free", "field.0.M,field.0.position.1",
                "--json")
    assert proc.returncode == 0, proc.stderr
    out = json.loads(proc.stdout)
    assert out["converged"] and abs(out["folds"][0] - 1.05) <= 1e-9
    proc = _cli("fit", *base, "--vary", "field.0.position.0", "--from", "0", "--to", "1.5",
                "--folds", "1.0", "--free", "rod.length")
    assert proc.returncode == 2 and "rod.length" in proc.stderr.strip().splitlines()[-1]
    assert len(proc.stderr.strip().splitlines()) == 1


def test_the_generic_fit_of_the_papers_scene_agrees_with_the_papers_fit():
    """One fit, two programs: the paper's calibration (``jr.fit`` on the physical experiment,
    four switching angles, the offset fixed, the magnet's remanence free: M is proportional
    to it) and the generic ``fit_folds`` on the same rig as a scene of terms (M free), both
    at N = 12, on angles with unequal errors. With the offset fixed the four angles' squared
    residuals are 2 (l - (m3 - m1) / 2)^2 + 2 (u - (m2 - m4) / 2)^2 plus a constant, so the
    generic fit of those two folds has the same minimiser and, with sigma of 1 degree in
    radians, a relative standard deviation sqrt(2) times the paper's (half the information).
    Both stop within 1e-10 standard deviations of their minimiser (the least-squares
    program's ``utol``; a relative standard deviation of 0.05 here): their M agree to 1e-10
    with a margin of ten. (A fit that stopped where its loss stops resolving the distance,
    ~1e-7 standard deviations, found them 2e-9 apart on some CPUs.)"""
    from jaxrod.inverse.fit import default_point, fit

    point = default_point()
    G, M, D = point.groups()
    lower, upper = (f.alpha_deg for f in jr.folds(jr.DipoleMagnet(G, 0.9 * M, D, 0.0),
                                                  n=12).folds)
    measured = np.array([-lower - 0.4, upper + 0.3, lower + 0.2, -upper + 0.5])
    paper = fit(measured, free=("remanence",), point=point)
    assert paper.converged, paper.reason
    ratio = paper.estimates["remanence"] / point.values[point.index("remanence")]

    # along the magnet's angle from 0 the branch meets the upper fold first, then turns back
    # to the lower one (the order fit_folds takes its data in)
    data = np.radians([(measured[1] - measured[3]) / 2, (measured[2] - measured[0]) / 2])
    generic = fit_folds(jr.DipoleMagnet(G, M, D, 0.0).scene, "magnet.alpha",
                        (0.0, 0.5 * np.pi), data, ["magnet.M"], sigma=np.radians(1.0), n=12)
    assert generic.converged, generic.reason
    assert abs(generic.estimates["magnet.M"] / (ratio * M) - 1.0) <= 1e-10
    relative_std = generic.std["magnet.M"] / generic.estimates["magnet.M"]
    paper_std = paper.std["remanence"] / paper.estimates["remanence"]
    assert abs(relative_std / (math.sqrt(2.0) * paper_std) - 1.0) <= 1e-9
    assert np.allclose(np.degrees(generic.folds), [paper.model[1], paper.model[2]],
                       atol=1e-9, rtol=0)
