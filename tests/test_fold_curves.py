"""Fold curves in a second parameter and the cusp, against independent methods.

The cusp is checked against the one-parameter fold pairs of ``locate_folds`` (Moore-Spence at
fixed parameters, itself checked against shooting in test_magnet): approaching the cusp the
two folds merge, and the squared separation of their reduced coordinates, (q_up - q_low)^2,
is an analytic function of the parameter with a simple zero at the cusp (a symmetric
function of the two roots of the normal form), as are the mean angle and mean q. A degree-6
polynomial through nine fold pairs within 0.1-1 % of the cusp extrapolates them to it.
"""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxrod.bistability import fold_curves as fc
from jaxrod.discretise.planar import planar_discretisation
from jaxrod.magnet.diagram import _equilibrium
from jaxrod.magnet.folds import locate_folds
from jaxrod.params import ParameterError
from jaxrod.scenes.dipole import DipoleMagnet
from jaxrod.solvers.continuation import REACHED_BOUND

D_EXP = 11.25 / 9.2
CASES = {200: (2.2, 0.0236), 100: (4.4, 0.0472)}


@pytest.fixture(scope="module")
def cusps():
    out = {}
    for e, (G, M) in CASES.items():
        point = fc.DesignPoint.from_groups(G, M, D_EXP)
        for vary in ("D", "M", "G"):
            out[e, vary] = (point, fc.find_cusp(point, vary))
    return out


def _extrapolated_cusp(point, vary, cusp):
    """(value, alpha_deg, q) of the cusp from fold pairs on the bistable side."""
    v0 = point.values[point.index(vary)]
    side = math.copysign(1.0, v0 - cusp.along_value)
    rows = []
    for h in np.geomspace(1e-3, 1e-2, 9) * cusp.along_value:
        G, M, D = point.replace(vary, cusp.along_value + side * h).groups()
        rep = locate_folds(DipoleMagnet(G, M, D, 0.0))
        assert rep.converged and [f.kind for f in rep.folds] == ["lower", "upper"]
        low, up = rep.folds
        rows.append((side * h, (up.q - low.q) ** 2, 0.5 * (up.alpha_deg + low.alpha_deg),
                     0.5 * (up.q + low.q)))
    h, dq2, alpha, q = np.array(rows).T
    roots = np.roots(np.polyfit(h, dq2, 6))
    root = roots[np.argmin(np.abs(roots))].real
    return (cusp.along_value + root, np.polyval(np.polyfit(h, alpha, 6), root),
            np.polyval(np.polyfit(h, q, 6), root))


@pytest.mark.parametrize("E", [200, 100])
@pytest.mark.parametrize("vary", ["D", "M", "G"])
def test_cusp_agrees_with_merging_fold_pairs(cusps, E, vary):
    point, cusp = cusps[E, vary]
    assert cusp.kind == "cusp" and cusp.converged
    assert abs(cusp.d2F_dq2) < 1e-9 and abs(cusp.hessian_smallest[0]) < 1e-9
    value, alpha, q = _extrapolated_cusp(point, vary, cusp)
    assert abs(value - cusp.along_value) < 1e-10 * max(1.0, abs(cusp.along_value))
    assert abs(alpha - cusp.value) < 1e-9
    assert abs(q - cusp.q) < 1e-10


def test_cubic_coefficient_from_equilibria_at_the_cusp(cusps):
    """alpha - alpha_c = -F_qqq / (6 F_alpha) (q - q_c)^3 + O(dq^4) on the equilibria at the
    cusp's parameter; the mean of dq = +-h cancels the quartic term."""
    point, cusp = cusps[200, "D"]
    G, M, D = point.replace("D", cusp.along_value).groups()
    scene = DipoleMagnet(G, M, D, 0.0)
    disc = planar_discretisation(fc.DEFAULT_N, "clamped")
    m = disc.size
    theta_c, phi = cusp.w[:m], cusp.w[m:2 * m]
    phi = phi / float(disc.mean(jnp.asarray(phi)))
    alpha_c = math.radians(cusp.value)
    # dF_dvalue is per degree of the magnet angle: F_alpha per radian is 180 / pi times it
    c3 = -cusp.cubic_coefficient / (6.0 * math.degrees(cusp.dF_dvalue))
    estimates = []
    for h in (0.02, 0.01):
        ratios = []
        for dq in (h, -h):
            alpha = alpha_c + c3 * dq**3
            res = _equilibrium(jnp.asarray(theta_c + dq * phi), alpha, scene, disc)
            assert bool(res.converged)
            ratios.append((alpha - alpha_c) / (float(disc.mean(res.x)) - cusp.q) ** 3)
        estimates.append(np.mean(ratios))
    # the symmetric mean is O(h^2) from c3: Richardson on h = 0.02, 0.01
    richardson = (4.0 * estimates[1] - estimates[0]) / 3.0
    assert abs(richardson / c3 - 1.0) < 1e-4


def test_cusp_location_derivatives_match_finite_differences(cusps):
    point, cusp = cusps[200, "D"]
    location = fc.cusp_location(point, "D", cusp)
    values = jnp.asarray(point.values)
    (d_value, d_alpha, _), = [jax.jacfwd(location)(values)]
    value, alpha, stats = location(values)
    assert float(stats[0]) == 1.0 and abs(float(value) - cusp.along_value) < 1e-12
    for i, name in ((0, "G"), (1, "M")):
        h = 1e-5 * point.values[i]
        plus = fc.find_cusp(point.replace(name, point.values[i] + h), "D")
        minus = fc.find_cusp(point.replace(name, point.values[i] - h), "D")
        fd_value = (plus.along_value - minus.along_value) / (2 * h)
        fd_alpha = math.radians(plus.value - minus.value) / (2 * h)
        assert abs(float(d_value[i]) - fd_value) < 1e-6 * abs(fd_value)
        assert abs(float(d_alpha[i]) - fd_alpha) < 1e-6 * max(abs(fd_alpha), 1.0)
    assert abs(float(d_value[2])) < 1e-12  # the varied input's own start has no effect


def test_fold_curve_points_are_folds_of_locate_folds():
    point = fc.DesignPoint.from_groups(*CASES[200], D_EXP)
    curves = fc.fold_curves(point, "G", 5.0)
    assert all(c.converged and not c.cusps for c in curves)
    for curve in curves:
        assert [p.kind for p in curve.special_points] == ["end"]
        assert curve.along_values[-1] == pytest.approx(5.0, abs=1e-12)
        for j in (len(curve.values) // 3, len(curve.values) - 1):
            rep = locate_folds(DipoleMagnet(curve.along_values[j], CASES[200][1], D_EXP, 0.0))
            fold = {f.kind: f for f in rep.folds}[curve.name]
            assert abs(fold.alpha_deg - curve.values[j]) < 1e-9
            assert abs(fold.q - curve.q[j]) < 1e-10


def test_fold_curve_follows_round_the_cusp_back_to_the_other_fold():
    """From the lower fold with D increasing, the curve turns back in D at the cusp and
    returns as the upper fold: at the starting D it is locate_folds' upper fold."""
    point = fc.DesignPoint.from_groups(*CASES[200], D_EXP)
    w0 = fc._start(point, fc.DEFAULT_N)
    folds = sorted(locate_folds(DipoleMagnet(*point.groups(), 0.0)).folds,
                   key=lambda f: f.alpha_deg)
    runs, _, args = fc._run(point, "D", -0.01, 0.5, w0[[0]], [1.0], fc.DEFAULT_N, math.inf)
    run = jax.tree_util.tree_map(lambda v: v[0], runs)
    k = int(run.num_points)
    assert int(run.status) == REACHED_BOUND
    u = np.asarray(run.w[:k, -1])
    m = args[1].size
    assert u.max() > 0.06 and u[-1] < 0  # went past the cusp (D = 1.3064) and came back
    assert np.sum(np.diff(np.sign(np.diff(u))) != 0) == 1  # one turning point in D
    j = k - 2  # the last point with u >= 0: refine to u = 0 exactly
    end = fc.special_point("u", np.asarray(run.w[j]), args, 0.0, fc._scales(point, "D"))
    assert end.converged and abs(end.value - folds[1].alpha_deg) < 1e-9
    assert abs(end.q - folds[1].q) < 1e-10
    assert np.asarray(run.w[j, 2 * m]) > np.asarray(run.w[0, 2 * m])


def test_physical_input_cusp_matches_group_cusp():
    """Varying the track radius R with L fixed is varying D = R / L."""
    from jaxrod.params import NDFEB_MAGNET, preset

    rod, _ = preset("permanent-magnet")
    point = fc.DesignPoint.from_physical(rod, NDFEB_MAGNET)
    by_radius = fc.find_cusp(point, "track-radius")
    G, M, D = point.groups()
    by_D = fc.find_cusp(fc.DesignPoint.from_groups(G, M, D), "D")
    assert abs(by_radius.along_value / rod.length - by_D.along_value) < 1e-11
    assert abs(by_radius.value - by_D.value) < 1e-9


def test_bad_inputs_are_refused():
    point = fc.DesignPoint.from_groups(*CASES[200], D_EXP)
    with pytest.raises(ParameterError, match="vary must be one of"):
        point.index("E")
    with pytest.raises(ParameterError, match="D must stay in"):
        fc.fold_curves(point, "D", 0.99)
    with pytest.raises(ParameterError, match="no fold to start from"):
        fc.find_cusp(fc.DesignPoint.from_groups(2.2, 0.001, D_EXP), "D")
    with pytest.raises(ParameterError, match="D"):
        fc.DesignPoint.from_groups(2.2, 0.0236, 1.0)


@pytest.mark.parametrize("groups", [(*CASES[200], D_EXP), (*CASES[100], D_EXP),
                                    (2.887, 0.01795, 1.1915)])
def test_fold_curves_start_at_the_folds_of_locate_folds(groups, monkeypatch):
    """The start of every fold curve, from the batched fold-pair path (or from the generic
    folds of the branch where that path does not converge), is the pair of folds of the
    paper's diagram (locate_folds): same angles, same states. (2.887, 0.01795, 1.1915) is the
    13-degree loop the batched path once flagged as not converged; with the batched path
    forced to fail, the fallback gives the same start."""
    point = fc.DesignPoint.from_groups(*groups)
    folds = sorted(locate_folds(DipoleMagnet(*groups, 0.0)).folds, key=lambda f: f.alpha_deg)
    assert [f.kind for f in folds] == ["lower", "upper"]
    m = planar_discretisation(fc.DEFAULT_N).size

    def check(w0):
        for w, fold in zip(w0, folds):
            assert abs(math.degrees(w[2 * m]) - fold.alpha_deg) < 1e-10
            np.testing.assert_allclose(w[:m], fold.theta, atol=1e-10)
            phi = w[m:2 * m]  # a null vector: parallel to locate_folds' one
            cos = abs(phi @ fold.null_vector) / np.linalg.norm(phi) / np.linalg.norm(
                fold.null_vector)
            assert cos > 1 - 1e-12
            assert w[-1] == 0.0

    check(fc._start(point, fc.DEFAULT_N))
    z, _ = fc._pair_start(*(jnp.asarray(v) for v in groups),
                          planar_discretisation(fc.DEFAULT_N, "clamped"))
    monkeypatch.setattr(fc, "_pair_start", lambda *a: (z, False))
    check(fc._start(point, fc.DEFAULT_N))

