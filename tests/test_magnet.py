import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import shooting_reference as shooting

from jaxrod import spectral
from jaxrod.discretise.planar import planar_discretisation
from jaxrod.magnet import diagram as magnet
from jaxrod.magnet import folds as magnet_folds
from jaxrod.magnet import sweep as magnet_sweep
from jaxrod.params import ParameterError
from jaxrod.scenes.dipole import tip_angle, tip_position

D_EXP = 11.25 / 9.2
CASES = {200: (2.2, 0.0236), 100: (4.4, 0.0472)}


@pytest.fixture(scope="module")
def reports():
    return {e: magnet_folds.locate_folds(magnet.make_scene(G, M, D_EXP))
            for e, (G, M) in CASES.items()}


def _shooting_fold(G, M, fold, n=16):
    disc = planar_discretisation(n, "clamped")
    kappa = (spectral.differentiation_matrix(n) @ np.asarray(disc.full_values(fold.theta)))[0]
    X = np.asarray(tip_position(jnp.asarray(fold.theta), disc))
    return math.degrees(shooting.fold_alpha(G, M, D_EXP, (kappa - 0.02, kappa + 0.02),
                                            [math.radians(fold.alpha_deg), *X], fold.kind))


@pytest.mark.parametrize("E", [200, 100])
def test_folds_agree_with_independent_shooting(reports, E):
    G, M = CASES[E]
    rep = reports[E]
    assert rep.converged and [f.kind for f in rep.folds] == ["lower", "upper"]
    for fold in rep.folds:
        assert abs(fold.alpha_deg - _shooting_fold(G, M, fold)) < 1e-9


def test_folds_match_the_issue_independent_values_to_printed_digits(reports):
    # Chebyshev + shooting values quoted in the issue (D = 11.25/9.2, rounded G and M)
    expected = {200: ("30.128181", "39.308447"), 100: ("40.957599", "61.506116")}
    for E, (lo, up) in expected.items():
        folds = reports[E].folds
        assert f"{folds[0].alpha_deg:.6f}" == lo and f"{folds[1].alpha_deg:.6f}" == up
    # and the paper's printed widths to within the ~2e-3 deg the paper's own numerics allow
    assert abs(reports[200].hysteresis_width_deg - 9.1795) < 2e-3
    assert abs(reports[100].hysteresis_width_deg - 20.5471) < 2e-3


def test_spectral_convergence_of_fold_angle():
    G, M = CASES[200]
    scene = magnet.make_scene(G, M, D_EXP)
    ref = magnet_folds.locate_folds(scene, n=32).folds
    errors = []
    for n in (6, 8, 10, 12):
        folds = magnet_folds.locate_folds(scene, n=n).folds
        errors.append(max(abs(a.alpha_deg - b.alpha_deg) for a, b in zip(folds, ref)))
    assert errors[-1] < 1e-10
    assert errors[0] > 1e2 * errors[-1]  # exponential decay, not stuck


def test_fold_signs_normal_form_and_null_vector(reports):
    for rep in reports.values():
        lower, upper = rep.folds
        assert lower.dF_dalpha > 0 and upper.dF_dalpha > 0
        assert lower.d2F_dq2 < 0 < upper.d2F_dq2
        assert lower.opens == "increasing alpha" and upper.opens == "decreasing alpha"
        for f in rep.folds:
            # exactly one zero eigenvalue of the Hessian
            assert abs(f.hessian_smallest[0]) < 1e-10 and f.hessian_smallest[1] > 0.1
            assert f.residual_norm < 1e-12


def test_normal_forms_against_nearby_equilibria(reports):
    """alpha - alpha* = c (q - q*)^2 and = c_tip (tip - tip*)^2 to leading order."""
    G, M = CASES[200]
    scene = magnet.make_scene(G, M, D_EXP)
    disc = planar_discretisation(magnet.DEFAULT_N, "clamped")
    from jaxrod.solvers.newton import newton

    for f in reports[200].folds:
        a_star = math.radians(f.alpha_deg)
        preds = []
        for dq in (1e-4, -1e-4):  # the average of +-dq cancels the cubic term
            alpha = a_star + f.normal_form_c * dq**2
            res = newton(lambda th, args, alpha=alpha: jax.grad(magnet.alpha_energy)(
                th, alpha, args), jnp.asarray(f.theta + dq * f.null_vector), (scene, disc),
                tol=1e-13)
            assert bool(res.converged)
            q = float(disc.mean(res.x))
            tip = float(tip_angle(res.x, disc))
            preds.append(((alpha - a_star) / (q - f.q) ** 2,
                          (alpha - a_star) / (tip - math.radians(f.tip_deg)) ** 2))
        pred_c, pred_tip = np.mean(preds, axis=0)
        assert pred_c == pytest.approx(f.normal_form_c, rel=1e-4)
        assert pred_tip == pytest.approx(f.tip_parabola_c, rel=1e-4)


def test_branch_shape_stability_and_detected_folds(reports):
    br = reports[200].branch
    assert br.complete
    assert np.degrees(br.alpha.min()) <= -90 + 1e-6 and np.degrees(br.alpha.max()) >= 90 - 1e-6
    lower, upper = reports[200].folds
    idx = br.fold_indices
    right = [i for i in idx if br.alpha[i] > 0]
    assert len(idx) == 4 and len(right) == 2
    # the Moore-Spence folds are the extrema of alpha between the detected points
    for i, f, sign in zip(sorted(right, key=lambda i: br.alpha[i]), (lower, upper), (-1, 1)):
        near = np.degrees(br.alpha[i:i + 2])
        assert sign * (f.alpha_deg - near).min() >= 0.0
    # engaged branch from alpha = 0 to the upper fold is stable, middle branch index 1
    zero = int(np.argmin(np.abs(br.alpha)))
    start_up = max(right, key=lambda i: br.alpha[i])
    start_lo = min(right, key=lambda i: br.alpha[i])
    assert np.all(br.morse_index[zero:start_up + 1] == 0)
    assert np.all(br.morse_index[start_up + 1:start_lo + 1] == 1)
    assert np.all(br.morse_index[start_lo + 1:] == 0)
    assert np.max(br.residual_norm) < 1e-11


def test_hysteresis_sweep_snaps_just_past_the_folds(reports):
    G, M = CASES[200]
    lower, upper = reports[200].folds
    sweep = magnet_sweep.hysteresis_sweep(magnet.make_scene(G, M, D_EXP), step_deg=0.25)
    assert sweep["converged"]
    snaps = {(s["direction"], s["alpha_deg"] > 0): s["alpha_deg"] for s in sweep["snaps"]}
    assert len(sweep["snaps"]) == 4
    assert -lower.alpha_deg < snaps[("cw", False)] <= -lower.alpha_deg + 0.25 + 1e-9
    assert upper.alpha_deg < snaps[("cw", True)] <= upper.alpha_deg + 0.25 + 1e-9
    assert lower.alpha_deg - 0.25 - 1e-9 <= snaps[("ccw", True)] < lower.alpha_deg
    assert -upper.alpha_deg - 0.25 - 1e-9 <= snaps[("ccw", False)] < -upper.alpha_deg


def test_square_root_law(reports):
    G, M = CASES[200]
    scene = magnet.make_scene(G, M, D_EXP)
    for f in reports[200].folds:
        fit = magnet_sweep.square_root_law(scene, f)
        assert sorted(side["stable"] for side in fit.values()) == [False, True]
        for side in fit.values():
            assert side["converged"]
            assert abs(side["exponent"] - 0.5) < 0.01


def test_no_fold_no_hysteresis():
    rep = magnet_folds.locate_folds(magnet.make_scene(2.2, 0.002, D_EXP))
    assert rep.folds == [] and rep.hysteresis_width_deg is None and rep.converged


def test_changing_parameters_does_not_recompile():
    magnet.trace_diagram(magnet.make_scene(2.2, 0.0236, D_EXP))
    before = magnet._diagram.jitted._cache_size()
    magnet.trace_diagram(magnet.make_scene(3.0, 0.03, 1.3))
    assert magnet._diagram.jitted._cache_size() == before


def test_bad_input():
    with pytest.raises(ParameterError, match="D"):
        magnet.make_scene(2.2, 0.0236, 0.9)
    with pytest.raises(ParameterError, match="tip cannot touch"):
        magnet.make_scene(2.2, 0.0236, 1.05, magnet_radius=0.08)
    with pytest.raises(ParameterError, match="M"):
        magnet.make_scene(2.2, float("nan"), 1.2)
    with pytest.raises(ParameterError, match="G"):
        magnet.make_scene(-1.0, 0.01, 1.2)


def test_throw_turns_a_failure_into_a_solver_error(reports, monkeypatch):
    """throw= on the paper's entry points (True by default, as on every host entry point): a
    converged answer passes; a report that is not converged (a diagram cut short), a fold
    pair that does not exist and a sweep whose step failed raise SolverError with
    NOT_CONVERGED, or with throw=False return the flags."""
    import dataclasses

    from jaxrod.status import SolverError, Status

    G, M = CASES[200]
    scene = magnet.make_scene(G, M, D_EXP)
    rep = reports[200]
    assert rep.status == Status.SUCCESS
    cut = dataclasses.replace(rep.branch, complete=False)
    assert magnet_folds.locate_folds(scene, branch=cut, throw=False).status == \
        Status.NOT_CONVERGED
    with pytest.raises(SolverError, match="did not reach its end") as err:
        magnet_folds.locate_folds(scene, branch=cut, throw=True)
    assert err.value.status == Status.NOT_CONVERGED
    assert magnet_folds.fold_pair(scene, throw=True)[1]
    no_folds = magnet.make_scene(2.2, 0.002, D_EXP)
    assert not magnet_folds.fold_pair(no_folds, throw=False)[1]
    with pytest.raises(SolverError, match="fold_pair"):
        magnet_folds.fold_pair(no_folds, throw=True)
    real = magnet_sweep._as_dict
    monkeypatch.setattr(magnet_sweep, "_as_dict",
                        lambda *a: real(*a) | {"converged": False})
    assert not magnet_sweep.hysteresis_sweep(scene, alpha_max_deg=5.0,
                                             throw=False)["converged"]
    with pytest.raises(SolverError, match="hysteresis_sweep"):
        magnet_sweep.hysteresis_sweep(scene, alpha_max_deg=5.0)  # throw: the default
