"""Branch points: stability changes without a fold, refined by Moore's augmented system,
and the branch that bifurcates there, against closed forms and shooting with scipy."""

import contextlib
import io
import json
import math

import numpy as np
import pytest
from airy_reference import straight_rod_branch_loads
from scipy.optimize import brentq
from scipy.special import jv
from test_scene_files import shooting_equilibria

import jaxrod as jr
from jaxrod.scenes.terms import Zeeman

OPPOSED = jr.Scene({"bending": jr.Bending(), "field": Zeeman(0.0, math.pi)})


@pytest.mark.parametrize("n", [8, 12, 16, 24])
def test_the_opposed_field_buckles_the_cantilever_at_pi_squared_over_four(n):
    """A hard-magnetic cantilever with the field opposite its magnetisation is the
    tip-loaded elastica: the straight rod bifurcates at load pi^2 / 4 (Euler)."""
    points = jr.branch_points(OPPOSED, "field.load", 0.0, 4.0, n=n)
    assert len(points) == 1
    p = points[0]
    assert abs(p.value - math.pi**2 / 4) <= 1e-10
    assert p.morse_index == (0, 1) and abs(p.unfolding) <= 1e-12
    assert np.max(np.abs(p.state)) <= 1e-12  # on the straight branch
    assert not jr.folds(OPPOSED, "field.load", 0.0, 4.0, n=n, throw=False)


def test_a_branch_holds_its_special_points_in_the_order_met():
    """``jr.branch`` refines what it meets (BifurcationKit's continuation result): the
    opposed field's straight branch to load 70 meets the Euler loads (2k - 1)^2 pi^2 / 4
    (closed form) as branch points, in order; the paper's branch in the magnet's angle
    meets its two folds (upper, then lower), each what ``jr.folds`` refines."""
    b = jr.branch(OPPOSED, "field.load", 0.0, 70.0, n=24)
    assert [p.kind for p in b.special_points] == ["branch_point"] * 3
    euler = [(2 * k - 1) ** 2 * math.pi**2 / 4 for k in (1, 2, 3)]
    assert np.allclose([p.value for p in b.special_points], euler, rtol=0, atol=1e-9)
    paper = jr.DipoleMagnet(2.2, 0.0236, 1.2228, 0.0).scene
    b = jr.branch(paper, "magnet.alpha", 0.0, 0.5 * math.pi, n=12)
    folds = jr.folds(paper, "magnet.alpha", 0.0, 0.5 * math.pi, n=12)
    assert [p.kind for p in b.special_points] == ["fold", "fold"]
    assert [p.value for p in b.special_points] == [f.value for f in folds]
    assert b.special_points[0].value > b.special_points[1].value  # upper, then lower


def test_the_bent_branch_is_followed_and_matches_shooting():
    """Branch switching at the pitchfork: the bent branch (supercritical: stable, the load
    rising from pi^2 / 4) against shooting at the same loads, tip position to 1e-11."""
    p = jr.branch_points(OPPOSED, "field.load", 0.0, 4.0, n=24)[0]
    bent = jr.bifurcated_branch(OPPOSED, p, 8.0, n=24)
    assert bent.complete and bent.value[0] >= p.value and bent.value[-1] >= 8.0 - 1e-9
    assert np.all(bent.stable[1:])
    for i in (len(bent.value) // 3, len(bent.value) - 1):
        lam = float(bent.value[i])
        X = bent.tip_position[i]
        refs = shooting_equilibria(lam, math.pi, k_max=8.0)
        ref = min(refs, key=lambda r: abs(r[1] - X[0]) + abs(r[2] - X[2]))
        assert abs(X[0] - ref[1]) <= 1e-11 and abs(X[2] - ref[2]) <= 1e-11
    other = jr.bifurcated_branch(OPPOSED, p, 8.0, n=24, side=-1)
    assert np.allclose(other.tip_position[-1][[0, 2]] * [-1, 1],
                       bent.tip_position[-1][[0, 2]], atol=1e-6) or \
        other.tip_position[-1][0] * bent.tip_position[-1][0] < 0


def test_greenhill_as_a_branch_point():
    """The upright rod under its own weight (no field): the branch point in G is
    Greenhill's G_c = (9/4) j^2, j the first zero of J_{-1/3} (a closed form)."""
    j = brentq(lambda x: jv(-1.0 / 3.0, x), 1.0, 2.5, xtol=1e-15)
    scene = jr.Scene({"bending": jr.Bending(), "gravity": jr.Gravity(0.0)})
    points = jr.branch_points(scene, "gravity.G", 0.0, 10.0, n=24)
    assert len(points) == 1 and abs(points[0].value - 2.25 * j**2) <= 1e-9


def test_a_fold_is_not_a_branch_point():
    """The field rotating round the cantilever: the stability changes there are folds."""
    scene = jr.Scene({"bending": jr.Bending(), "field": Zeeman(5.0, math.pi / 2)})
    assert not jr.branch_points(scene, "field.angle", math.pi / 2, math.radians(359.0), n=16)


#: Later branch points, each against an independent method: the opposed field's Euler loads
#: (2k + 1)^2 pi^2 / 4 (the tip-loaded elastica, closed form), and the heavy rod held by a
#: field along it, clamped and pinned, varied in G: the zeros in G of the Airy
#: characteristic function of -u'' - G (1 - s) u + load u = 0 (tests/airy_reference.py).
LATER_BRANCH_POINTS = [
    ("opposed field", "clamped", "field.load", 0.0, 70.0, 0.0,
     lambda: [(2 * k + 1) ** 2 * math.pi**2 / 4 for k in range(3)]),
    ("heavy rod, field along it", "clamped", "gravity.G", 0.0, 200.0, 2.0,
     lambda: straight_rod_branch_loads(2.0, "clamped", 200.0, 3)),
    ("heavy rod, pinned base", "pinned", "gravity.G", 0.0, 150.0, 3.0,
     lambda: straight_rod_branch_loads(3.0, "pinned", 150.0, 3)),
]


@pytest.mark.parametrize("name,support,vary,start,stop,load,reference", LATER_BRANCH_POINTS,
                         ids=[row[0] for row in LATER_BRANCH_POINTS])
def test_every_branch_point_along_a_range_is_its_own(name, support, vary, start, stop, load,
                                                     reference):
    """The first three branch points met along the range, each refined to the kernel of the
    eigenvalue that crosses zero there (Morse index k -> k + 1), listed once, against the
    independent value to 1e-9 (N = 24 resolves the third to 1e-12). The refinement used to
    slide back to the first kernel from every later bracket: each later point was the first
    one again, reported converged."""
    if vary == "field.load":
        scene = OPPOSED
    else:
        scene = jr.Scene({"bending": jr.Bending(), "gravity": jr.Gravity(0.0),
                          "field": Zeeman(load, 0.0)}, support=support)
    points = jr.branch_points(scene, vary, start, stop, n=24)
    expected = reference()
    assert [p.morse_index for p in points] == [(0, 1), (1, 2), (2, 3)]
    assert np.all(np.abs(np.array([p.value for p in points]) - expected) <= 1e-9)
    assert all(abs(p.unfolding) <= 1e-10 for p in points)


def test_cli_branch_lists_the_branch_points_inside_its_range(tmp_path):
    """jaxrod branch on the shipped hard-magnetic cantilever, opposed field from 3 to 6 mT:
    the one branch point inside is the second Euler load, 9 pi^2 / 4 (lambda = 4000 B); the
    first (0.617 mT) lies outside the range and is not listed. With --out: branch.csv,
    branch.json and the figure branch.png."""
    from jaxrod.cli import main

    with contextlib.redirect_stdout(io.StringIO()) as out:
        code = main(["branch", "hard-magnetic-cantilever", "--vary", "field.0.B", "--from",
                     "3e-3", "--to", "6e-3", "--set", "field.0.angle_deg=180", "--json",
                     "--out", str(tmp_path)])
    assert code == 0
    assert all((tmp_path / f"branch.{ext}").stat().st_size > 0 for ext in ("csv", "json",
                                                                             "png"))
    result = json.loads(out.getvalue())
    (bp,) = result["branch_points"]
    assert abs(bp["value"] - 9 * math.pi**2 / 4 / 4000.0) <= 1e-13
    assert {"value", "tip_angle_deg"} <= set(bp) and result["folds"] == []
