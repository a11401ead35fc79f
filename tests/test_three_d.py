"""3D branches on the director discretisation: the uniform-field pitchfork switched onto along
a horizontal direction, and a magnet track that leaves the plane."""

import math

import numpy as np
import pytest

import jaxrod as jr
from jaxrod.magnet import diagram as magnet
from jaxrod.magnet import folds as magnet_folds
from jaxrod.three_d.track import trace_track
from jaxrod.uniform.greenhill import greenhill
from jaxrod.uniform.pitchfork import buckled_branch

D = 11.25 / 9.2


@pytest.mark.parametrize("support, G, kind", [
    ("clamped", 8.5, "supercritical"),
    ("clamped", 60.0, "subcritical"),
    ("pinned", 2.0, "subcritical"),
])
def test_3d_post_buckled_branch_reproduces_the_a2_formula(support, G, kind):
    phi = 30.0
    branch = buckled_branch(G, support, n=40, direction_deg=phi)
    assert branch.converged.all() and np.max(branch.residual_norm) < 1e-12
    formula = greenhill(G, support, n=40)
    assert formula.criticality == kind
    assert abs(branch.fit_A2(terms=5) - formula.A2) <= 1e-4 * abs(formula.A2)
    assert np.all(np.sign(branch.A - branch.A_crit) == np.sign(formula.A2))
    # the rod buckles in the vertical plane through the chosen direction: the 3D states are
    # theta (cos phi, sin phi) with theta the planar branch, and the phase multiplier is zero
    planar = buckled_branch(G, support, n=40)
    m = planar.states.shape[1]
    c, s = math.cos(math.radians(phi)), math.sin(math.radians(phi))
    np.testing.assert_allclose(branch.states[:, :m], c * planar.states, atol=1e-12)
    np.testing.assert_allclose(branch.states[:, m:], s * planar.states, atol=1e-12)
    np.testing.assert_allclose(branch.A, planar.A, rtol=1e-12)
    assert np.max(np.abs(branch.multiplier)) < 1e-12
    assert np.max(np.abs(branch.states[:, m:])) > 0.1


def test_magnet_track_leaving_the_plane_snaps_where_the_planar_folds_are():
    scene = magnet.make_scene(2.2, 0.0236, D)
    found = magnet_folds.locate_folds(scene, n=16).folds
    planar = {f.kind: f.alpha_deg for f in found}
    planar_tip = {f.kind: f.tip_deg for f in found}
    track = trace_track(scene, alpha0_deg=20.0, tilt_deg=90.0, n=16)
    assert track.status == (jr.Status.REACHED_BOUND,) and track.complete and track.vary == "t"
    assert track.out_of_plane.max() > 0.5  # genuinely 3D states
    upper, lower = track.folds  # the branch runs round the upper fold, then the lower one
    for fold, kind in ((upper, "upper"), (lower, "lower")):
        assert fold.converged and fold.residual_norm < 1e-12
        # by the symmetry about e3 the fold sits where the magnet's polar angle reaches the
        # planar fold angle, with the rod leaning towards the magnet's azimuth
        assert abs(fold.magnet_polar_deg - planar[kind]) < 1e-9
        assert abs(fold.rod_azimuth_deg - fold.magnet_azimuth_deg) < 1e-9
        # ... and the tip leaning as far as in the plane: its polar angle is the planar
        # fold's tip angle; its angle from +z toward +x is that of the tip position, as for
        # every special point and the branch's column
        assert abs(fold.tip_polar_deg - planar_tip[kind]) < 1e-9
        X = fold.tip_position
        assert abs(fold.tip_angle_deg - math.degrees(math.atan2(X[0], X[2]))) < 1e-12
        assert abs(fold.tip_angle_deg - fold.tip_polar_deg) > 1.0  # off the xz-plane
        assert abs(fold.hessian_smallest[0]) < 1e-9 < fold.hessian_smallest[1]
    assert 0.0 < lower.t_deg < upper.t_deg
    stable = track.stable & (track.t_deg < upper.t_deg)
    np.testing.assert_allclose(track.rod_azimuth_deg[stable][1:],
                               track.magnet_azimuth_deg[stable][1:], atol=1e-8)
    end = track.centreline(len(track.t_deg) - 1)[-1]
    np.testing.assert_allclose(end, track.tip_position[-1], atol=1e-12)
    # the Branch record's columns, as for any 3D scene: the tip position's angle, q = int v1
    np.testing.assert_allclose(track.tip, np.arctan2(track.tip_position[:, 0],
                                                     track.tip_position[:, 2]), atol=1e-14)
    assert len(track.fold_indices) == 2 and np.all(np.isfinite(track.energy))
