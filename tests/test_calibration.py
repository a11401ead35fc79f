"""Multi-parameter calibration and inverse design of the paper's experiment (the generic
fit on its rig: jaxrod.inverse.scene_fit, fit, design).

Synthetic angles come from ``locate_folds`` (the paper's scene, continuation from the
straight rod and Moore-Spence at N = 16), independent of the fit's warm-started fold model
on the rig file (N = 12).
"""

from __future__ import annotations

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from figure_checks import check_figure

from jaxrod.design_point import DesignPoint
from jaxrod.equilibria.folds import folds as fresh_folds
from jaxrod.inverse import scene_fit
from jaxrod.inverse.design import design
from jaxrod.inverse.fit import Prior, default_point, fit, profile
from jaxrod.magnet.diagram import make_scene
from jaxrod.magnet.folds import locate_folds
from jaxrod.params import ParameterError
from jaxrod.plotting import profile_figure
from jaxrod.scenes.dipole import KEYS, rig_of


def synthetic_angles(point: DesignPoint, offset: float = 0.0) -> np.ndarray:
    G, M, D = point.groups()
    folds = locate_folds(make_scene(G, M, D, point.radius()), n=16).folds
    lower, upper = (f.alpha_deg for f in folds)
    return np.array([-lower, upper, lower, -upper]) + offset


@pytest.mark.parametrize("hidden, free", [
    ({"E": 180e9, "remanence": 7.6e5}, ("E", "remanence", "offset")),
    ({"E": 230e9, "track-radius": 0.118}, ("E", "track-radius", "offset")),
    ({"E": 160e9, "magnet-diameter": 0.016}, ("E", "magnet-diameter", "offset")),
])
def test_hidden_parameters_recovered_from_exact_angles(hidden, free):
    truth = default_point()
    for name, v in hidden.items():
        truth = truth.replace(name, v)
    measured = synthetic_angles(truth, offset=0.7)
    cal = fit(measured, free)  # starts from the paper's values, offset 0
    assert cal.converged, cal.reason
    for name, v in hidden.items():
        assert abs(cal.estimates[name] / v - 1.0) < 1e-6, (name, cal.estimates[name], v)
    assert abs(cal.estimates["offset"] - 0.7) < 1e-6
    assert cal.chi2 < 1e-10
    magnet = set(hidden) & {"remanence", "magnet-diameter"}
    if magnet:
        # exact data pin the point, but the magnet's strength M_s a^3 and E enter the angles
        # almost only through M ~ M_s a^3 / E and G ~ 1 / E: at sigma = 1 degree the angles
        # leave one combination free to a factor e^10, and neither gets a deviation
        loose = [e for e in cal.identifiability if not e["fixed_by_data"]]
        assert len(loose) == 1 and set(loose[0]["combination"]) == {"E"} | magnet
        assert cal.std["E"] is None
    else:
        assert all(e["fixed_by_data"] for e in cal.identifiability)
        assert all(cal.std[n] is not None for n in free)


def test_fold_derivatives_match_central_differences_of_fresh_continuations():
    """The fit's fold model differentiated in the rig's numbers (forward mode through the
    implicitly differentiated Moore-Spence solves) against central differences of the folds
    found afresh (continuation from the straight rod) at each perturbed rig."""
    scene, angle, span, _, _ = rig_of(default_point())
    keys = [KEYS[n][0] for n in ("E", "remanence", "track-radius", "length")]
    problem, path = scene_fit._prepare(scene, angle, span, [1.0, 1.0], keys, 1.0, None, 12,
                                       None, False, None)
    a = problem.arrays
    p = np.array(path.start[1:])
    J = jax.jacfwd(lambda q: scene_fit.fold_values(a["path"], a["disc"], a["origin"],
                                                   a["span"], q, a["z0"])[0])(jnp.asarray(p))
    for j, key in enumerate(keys):
        h = 1e-5 * p[j]
        at = lambda v: [f.value for f in fresh_folds(scene_fit.with_values(scene, {key: v}),
                                                     angle, *span, n=12)]
        fd = (np.array(at(p[j] + h)) - np.array(at(p[j] - h))) / (2 * h)
        assert np.allclose(np.asarray(J[:, j]), fd, rtol=1e-6), key


def test_unidentifiable_combination_is_flagged_not_given_a_std():
    """E and the magnet's remanence enter the four angles almost only through M ~ M_s / E
    and G ~ 1 / E; with the track radius also free the angles fix three combinations and
    leave one: E and remanence get no standard deviation, the offset and the track radius
    keep theirs. A prior on the remanence restores them."""
    truth = default_point().replace("E", 190e9)
    measured = synthetic_angles(truth)
    free = ("E", "remanence", "track-radius", "offset")
    cal = fit(measured, free)
    assert cal.std["E"] is None and cal.std["remanence"] is None
    assert cal.std["offset"] is not None and cal.std["track-radius"] is not None
    loose = [e for e in cal.identifiability if not e["fixed_by_data"]]
    assert len(loose) == 1 and set(loose[0]["combination"]) >= {"E", "remanence"}
    assert any("cannot tell apart" in w for w in cal.warnings)
    with_prior = fit(measured, free, priors={"remanence": Prior(8e5, 4e4)})
    assert with_prior.converged and all(v is not None for v in with_prior.std.values())


def test_profile_matches_laplace_near_the_optimum(tmp_path):
    measured = synthetic_angles(default_point().replace("E", 210e9), 0.3) + np.array(
        [0.4, -0.3, 0.2, -0.5])
    cal = fit(measured, ("E", "offset"), sigma_deg=0.5)
    prof = profile(measured, "E", ("E", "offset"), sigma_deg=0.5, fitted=cal, span=1.0,
                   count=5)
    assert all(prof["converged"])
    assert abs(prof["chi2"][2] - cal.chi2) < 1e-8  # the centre is the optimum
    # within one standard deviation the profile is the Laplace parabola to a few percent
    rise = np.array(prof["chi2"]) - cal.chi2
    laplace = np.array(prof["laplace_chi2"]) - cal.chi2
    assert np.allclose(rise[[0, 1, 3, 4]], laplace[[0, 1, 3, 4]], rtol=0.1)
    check_figure(profile_figure([prof], cal), tmp_path, "profile")


def test_coverage_on_a_small_batch():
    """68% intervals of E on 40 noisy synthetic experiments: the fraction covering the truth
    lies within 3 binomial standard deviations of 0.68 (the benchmark runs 1000)."""
    rng = np.random.default_rng(7)
    base = default_point()
    hits, z = 0, []
    for _ in range(40):
        E = rng.uniform(150e9, 250e9)
        clean = synthetic_angles(base.replace("E", E))
        cal = fit(clean + rng.normal(0.0, 0.5, 4), ("E", "offset"), sigma_deg=0.5)
        assert cal.converged
        z.append((cal.estimates["E"] - E) / cal.std["E"])
        hits += abs(z[-1]) <= 1.0
    sd = math.sqrt(0.68 * 0.32 / 40)
    assert abs(hits / 40 - 0.68) <= 3 * sd, hits
    assert abs(np.mean(z)) <= 3.0 / math.sqrt(40)  # unbiased within the standard error


def test_design_recovers_the_inputs_of_a_known_forward_solve():
    known = default_point().replace("track-radius", 0.105).replace("magnet-diameter", 0.012)
    measured = synthetic_angles(known)
    capture, release = measured[2], measured[1]
    result = design(default_point(), capture, release, ("track-radius", "magnet-diameter"))
    assert result.designs and all(d.verified for d in result.designs)
    best = min(result.designs, key=lambda d: abs(d.values["track-radius"] / 0.105 - 1))
    assert abs(best.values["track-radius"] / 0.105 - 1.0) < 1e-6
    assert abs(best.values["magnet-diameter"] / 0.012 - 1.0) < 1e-6
    assert abs(best.verified_capture_deg - capture) < 1e-6
    assert abs(best.verified_release_deg - release) < 1e-6


def test_design_with_groups():
    known = DesignPoint.from_groups(2.2, 0.018, 1.18)
    measured = synthetic_angles(known)
    start = DesignPoint.from_groups(2.2, 0.0236, 1.2228)
    result = design(start, measured[2], measured[1], ("D", "M"))
    d = result.designs[0]
    assert d.verified and abs(d.values["D"] / 1.18 - 1) < 1e-6
    assert abs(d.values["M"] / 0.018 - 1) < 1e-6


@pytest.mark.parametrize("kwargs, name", [
    ({"capture_deg": 40, "release_deg": 30}, "release"),
    ({"capture_deg": 20, "release_deg": 95}, "release"),
    ({"capture_deg": -5, "release_deg": 30}, "capture"),
    ({"capture_deg": 20, "release_deg": 45, "vary": ("K",)}, "vary"),
    ({"capture_deg": 20, "release_deg": 45, "bounds": {"track-radius": (0.2, 0.1)}},
     "bounds"),
])
def test_design_refuses_bad_targets(kwargs, name):
    kwargs = {"vary": ("track-radius", "magnet-diameter")} | kwargs
    with pytest.raises(ParameterError, match=name):
        design(default_point(), **kwargs)


def test_design_reports_an_unreachable_target():
    """A track radius alone cannot make a 5-80 degree loop within its bounds."""
    with pytest.raises(ParameterError, match="no bistable design.*closest"):
        design(default_point(), 5.0, 80.0, ("track-radius",))


@pytest.mark.parametrize("kwargs, name", [
    ({"free": ("E", "stiffness")}, "unknown parameter"),
    ({"free": ()}, "at least one"),
    ({"priors": {"remanence": (8e5, 1.0)}}, "Prior"),
    ({"priors": {"K": Prior(1.0, 1.0)}}, "unknown parameter"),
    ({"bounds": {"E": (3e11, 1e11)}}, "bounds E"),
])
def test_fit_refuses_bad_input(kwargs, name):
    with pytest.raises(ParameterError, match=name):
        fit([-25, 38, 24, -42], **kwargs)


def test_prior_sd_must_be_positive():
    with pytest.raises(ParameterError, match="prior sd"):
        Prior(8e5, 0.0)
    with pytest.raises(ParameterError, match="prior sd"):
        Prior(8e5, -1.0)


def test_cli_design_and_fit(capsys):
    """``jaxrod design`` with the groups: the answer's keys, verified; bounds excluding every
    bistable design exit 2 with one line (found only by the search, so not time-limited)."""
    import json

    from jaxrod.cli import main

    assert main(["design", "--G", "2.2", "--capture", "25", "--release", "40", "--vary",
                 "D,M", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["converged"] and {"D", "M", "capture_deg", "release_deg"} <= set(out)
    assert abs(out["capture_deg"] - 25) < 1e-6 and abs(out["release_deg"] - 40) < 1e-6
    assert main(["design", "--G", "2.2", "--capture", "20", "--release", "45", "--vary", "D,M",
                 "--bounds", "D=1.5:1.6", "--bounds", "M=1e-4:2e-4"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "no bistable design" in err[0]
    assert main(["fit", "--angles", "-25", "38", "24", "-42", "--free", "E,track-radius,offset",
                 "--prior", "track-radius=0.1125:0.001", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["converged"] and out["std"]["track-radius"] is not None
    assert out["inputs"]["track-radius"]["source"] == "preset permanent-magnet"
