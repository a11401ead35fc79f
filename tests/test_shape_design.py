"""Design for a target shape (``jaxrod.inverse.shape_design``) against closed forms.

A hard magnetisation in a uniform field at a = 90 degrees on a clamped-free rod: the moment
balance theta'' + load mu(s) sin(a - theta - phi(s)) = 0 with theta'(1) = 0 (the term's
density -load mu(s) cos(theta + phi(s) - a) varied in theta) gives, for the target
theta*(s) = c (s - s^2 / 2) (theta*(0) = 0, theta*'(1) = 0, theta*'' = -c),

* the strength profile along the tangent (phi = 0): mu(s) = c / (load cos theta*(s));
* the angle profile at uniform strength: sin(a - theta* - phi) = c / load, so
  phi(s) = pi / 2 - arcsin(c / load) - c s + (c / 2) s^2, a quadratic in s (the branch of
  the arcsine that a design started at a small angle reaches: the stable one);
* a stiffness taper beta(s) = E I(s) / E I at uniform strength along the tangent:
  (beta theta')' + load cos theta = 0, so beta(s) = int_s^1 load cos theta* dt / theta*'(s).
"""

import json
import math

import numpy as np
import pytest

import jaxrod as jr
from jaxrod.inverse.shape_design import design_shape
from jaxrod.params import ParameterError

LOAD, C = 2.0, 0.6
S = np.linspace(0.0, 1.0, 21)
TARGET_DEG = np.degrees(C * (S - S**2 / 2))
RIG = """units = "nondimensional"
geometry = "planar"
[rod]
support = "clamped"
[magnetisation]
kind = "hard"
{magnetisation}
[[field]]
kind = "uniform"
load = 2.0
angle_deg = 90.0
"""


def _rig(tmp_path, magnetisation: str):
    path = tmp_path / "rig.toml"
    path.write_text(RIG.format(magnetisation=magnetisation))
    return jr.load_scene(str(path))


def test_a_strength_profile_for_a_target_shape_is_the_closed_form(tmp_path):
    """Ten Chebyshev coefficients of mu at N = 16, from the uniform remanence: the designed
    profile is the closed form's to 1e-6 at 101 points (the degree-9 approximation of the
    closed form is ~3e-8 there), the shape to 1e-6 degrees; stable, and the equilibrium that
    ramping the designed rig's load reaches."""
    K = 10
    rig = _rig(tmp_path, f"strength_profile = {[1.0] + [0.0] * (K - 1)}")
    keys = [f"magnetisation.strength_profile.{k}" for k in range(K)]
    d = design_shape(rig, keys, S, TARGET_DEG, n=16)
    assert d.converged and d.stable and d.reachable and d.status is jr.Status.SUCCESS
    assert d.shape_error_deg <= 1e-6
    s = np.linspace(0.0, 1.0, 101)
    mu = np.polynomial.chebyshev.chebval(2 * s - 1, [d.values[k] for k in keys])
    closed = C / (LOAD * np.cos(C * (s - s**2 / 2)))
    np.testing.assert_allclose(mu, closed, rtol=0, atol=1e-6)


def test_an_angle_profile_for_a_target_shape_is_the_closed_form(tmp_path):
    """Three monomial coefficients of phi (degrees in the file), from a profile far from the
    answer: the closed form's quadratic to the least squares' stopping rule (utol 1e-10
    standard deviations of 1 degree: asked 1e-8 rad)."""
    rig = _rig(tmp_path, "profile_deg = [30.0, -10.0, 5.0]")
    keys = [f"magnetisation.profile_deg.{k}" for k in range(3)]
    d = design_shape(rig, keys, S[::2], TARGET_DEG[::2], n=16)
    assert d.converged and d.stable and d.reachable
    closed = [math.pi / 2 - math.asin(C / LOAD), -C, C / 2]
    np.testing.assert_allclose(np.radians([d.values[k] for k in keys]), closed, rtol=0,
                               atol=1e-8)


def test_a_stiffness_taper_for_a_target_shape_is_the_closed_form(tmp_path):
    """A tapered rod, E I(s) / E I = beta(s) (eight Chebyshev coefficients from a uniform
    beta = 3, near the answer's scale), magnetised along the tangent in the field at 90
    degrees: (beta theta')' + load cos theta = 0 with beta theta'(1) = 0 gives
    beta(s) = int_s^1 load cos theta*(t) dt / theta*'(s) (the integral by scipy's quad), to
    1e-6 on [0, 0.99] (the quotient is 0/0 at s = 1); stable, reached by the ramp."""
    from scipy.integrate import quad

    K = 8
    path = tmp_path / "taper.toml"
    path.write_text(RIG.format(magnetisation="").replace(
        'support = "clamped"', f'support = "clamped"\nstiffness_profile = {[3.0] + [0.0] * 7}'))
    keys = [f"rod.stiffness_profile.{k}" for k in range(K)]
    d = design_shape(jr.load_scene(str(path)), keys, S, TARGET_DEG, n=16)
    assert d.converged and d.stable and d.reachable and d.shape_error_deg <= 1e-6
    s = np.linspace(0.0, 0.99, 34)
    theta = lambda t: C * (t - t**2 / 2)
    closed = [quad(lambda t: LOAD * math.cos(theta(t)), a, 1.0, epsabs=1e-13)[0]
              / (C * (1.0 - a)) for a in s]
    beta = np.polynomial.chebyshev.chebval(2 * s - 1, [d.values[k] for k in keys])
    np.testing.assert_allclose(beta, closed, rtol=0, atol=1e-6)


@pytest.mark.parametrize("s, target, match", [
    ([0.0, 0.5, math.nan], [0.0, 1.0, 2.0], "finite"),
    ([0.0, 0.5, 1.2], [0.0, 1.0, 2.0], r"s must lie in \[0, 1\]"),
    ([0.0, 1.0], [0.0, 1.0], "at least 3 points"),
    ([0.0, 0.5, 1.0], None, "tangent angles .* or the centreline")])
def test_bad_targets_are_named(tmp_path, s, target, match):
    rig = _rig(tmp_path, "strength_profile = [1.0, 0.0]")
    with pytest.raises(ParameterError, match=f"target: .*{match}"):
        design_shape(rig, ["magnetisation.strength_profile.1"], s, target, n=8)


def _target_csv(path, rows, header="s,tangent_deg"):
    path.write_text(header + "\n" + "".join(",".join(map(repr, r)) + "\n" for r in rows))
    return path


def test_the_command_line_designs_a_profile_for_a_target_shape(tmp_path):
    """``jaxrod design RIG --free magnetisation.strength_profile --target-shape FILE.csv
    --json``: the list's key frees its eight coefficients; the remanence load load mu(s) at
    101 points is the closed form's c / cos theta*(s) to 1e-6 (its degree-7 approximation
    ~2e-7); design.json and shape.png with --out."""
    from command_line import run_cli

    rig = tmp_path / "rig.toml"
    rig.write_text(RIG.format(magnetisation=f"strength_profile = {[1.0] + [0.0] * 7}"))
    target = _target_csv(tmp_path / "target.csv",
                         zip(S.tolist(), TARGET_DEG.tolist()))
    proc = run_cli("design", rig, "--free", "magnetisation.strength_profile",
                   "--target-shape", target, "--n", "16", "--out", tmp_path / "out", "--json")
    assert proc.returncode == 0, proc.stderr
    out = json.loads(proc.stdout)
    assert len(out["free"]) == 8 and out["converged"] and out["stable"]
    assert out["shape_error_deg"] <= 1e-6
    s = np.asarray(out["profile"]["s"])
    assert s.size == 101 and s[0] == 0.0 and s[-1] == 1.0
    np.testing.assert_allclose(out["profile"]["strength"], C / np.cos(C * (s - s**2 / 2)),
                               rtol=0, atol=1e-6)
    assert (tmp_path / "out" / "design.json").exists()
    assert (tmp_path / "out" / "shape.png").stat().st_size > 0


@pytest.mark.parametrize("header, rows, words", [
    ("s,tangent_deg", [(0.0, 0.0), (0.5, math.nan), (1.0, 2.0)], "finite"),
    ("s,x,z", [(0.0, 0.0, 0.0), (0.5, 0.1, 0.5), (1.5, 0.2, 0.9)], "s must lie in"),
    ("s,tangent_deg", [(0.0, 0.0), (1.0, 2.0)], "at least 3 rows"),
    ("s,x", [(0.0, 0.0), (0.5, 0.4), (1.0, 0.8)], "header")])
def test_bad_target_files_exit_2_with_one_line(tmp_path, header, rows, words):
    from command_line import run_cli

    rig = tmp_path / "rig.toml"
    rig.write_text(RIG.format(magnetisation="strength_profile = [1.0, 0.0]"))
    proc = run_cli("design", rig, "--free", "magnetisation.strength_profile",
                   "--target-shape", _target_csv(tmp_path / "t.csv", rows, header))
    assert proc.returncode == 2 and proc.stdout == ""
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and "target-shape" in lines[0] and words in lines[0]


@pytest.mark.parametrize("header", ["s,x,z", "s,x,z,tangent_deg", "s,tangent_deg,x,z"])
def test_a_target_file_of_centreline_points(tmp_path, header):
    """A target file's columns by its header: the angles and the points (x, z) come back as
    written, in any order after s."""
    from jaxrod.cli.shape_design import read_target

    names = header.split(",")
    rows = [{"s": s, "x": 0.1 * s, "z": 0.9 * s, "tangent_deg": 10.0 * s} for s in (0, .5, 1)]
    path = _target_csv(tmp_path / "t.csv", [[r[c] for c in names] for r in rows], header)
    s, angles, points = read_target(str(path))
    np.testing.assert_array_equal(s, [0.0, 0.5, 1.0])
    np.testing.assert_array_equal(points, [[0.0, 0.0], [0.05, 0.45], [0.1, 0.9]])
    if "tangent_deg" in names:
        np.testing.assert_array_equal(angles, [0.0, 5.0, 10.0])
    else:
        assert angles is None


def test_a_strength_profile_places_a_fold_at_a_field_angle(tmp_path):
    """A design through the folds (``jr.design_folds``) with a profile's coefficient free:
    the hard-magnetic cantilever (load 5, folds at 212.15 and 147.85 degrees with a uniform
    remanence) gets its first fold at 200 degrees from the slope of its strength; a fresh
    continuation from the straight rod of the designed rig finds it there to 1e-9 degrees,
    and the loop's width (the two folds' difference) with it; a width of 50 degrees as the
    target, likewise."""
    from command_line import run_cli

    path = tmp_path / "hm.toml"
    path.write_text(RIG.format(magnetisation="strength_profile = [1.0, 0.0]").replace(
        "load = 2.0", "load = 5.0"))
    rig = jr.load_scene(str(path))
    key = "magnetisation.strength_profile.1"
    d = jr.design_folds(rig, "field.0.angle_deg", (90.0, 359.0), [200.0, math.nan], [key],
                        n=16)
    assert d.converged
    fresh = jr.folds(jr.load_scene(str(path), [f"{key}={d.estimates[key]!r}"]),
                     "field.0.angle_deg", 90.0, 359.0, n=16)
    assert len(fresh) == 2 and abs(fresh[0].value - 200.0) <= 1e-9
    assert abs((fresh[0].value - fresh[1].value) - (d.folds[0] - d.folds[1])) <= 1e-9

    # the width as the target: the first fold met less the second, 50 degrees (the
    # command line's --width)
    proc = run_cli("design", path, "--path", "field.0.angle_deg", "--from", "90", "--to",
                   "359", "--width", "50", "--free", key, "--n", "16", "--json")
    assert proc.returncode == 0, proc.stderr
    out = json.loads(proc.stdout)
    fresh = jr.folds(jr.load_scene(str(path), [f"{key}={out['estimates'][key]!r}"]),
                     "field.0.angle_deg", 90.0, 359.0, n=16)
    assert abs((fresh[0].value - fresh[1].value) - 50.0) <= 1e-9
    assert abs(out["width"] - 50.0) <= 1e-9


def test_one_profile_for_two_target_shapes_under_two_fields(tmp_path):
    """Two load cases at once (the field at 90 and at 45 degrees): the targets are the
    shapes of the profile mu*(s) = 1 + 0.3 (2 s - 1) under both fields by scipy's solve_bvp
    (theta'' + load mu* sin(a - theta) = 0, theta(0) = 0, theta'(1) = 0, tol 1e-10: an
    independent method). From the uniform remanence the two coefficients come back to 1e-7
    (the targets' accuracy), both shapes to 1e-6 degrees; the designed rig ramped in each
    field reaches each designed equilibrium."""
    from scipy.integrate import solve_bvp

    def shape(a):
        mu = lambda s: 1.0 + 0.3 * (2 * s - 1)
        sol = solve_bvp(lambda s, y: np.vstack([y[1], -LOAD * mu(s) * np.sin(a - y[0])]),
                        lambda ya, yb: np.array([ya[0], yb[1]]), np.linspace(0, 1, 50),
                        np.zeros((2, 50)), tol=1e-10, max_nodes=100000)
        assert sol.success
        return np.degrees(sol.sol(S)[0])

    rig = _rig(tmp_path, "strength_profile = [1.0, 0.0]")
    keys = ["magnetisation.strength_profile.0", "magnetisation.strength_profile.1"]
    targets = np.stack([shape(math.radians(90.0)), shape(math.radians(45.0))])
    d = design_shape(rig, keys, S, targets, n=16, cases={"field.0.angle_deg": [90.0, 45.0]})
    assert d.converged and d.stable and d.reachable and d.tangent_deg.shape == (2, S.size)
    assert d.shape_error_deg <= 1e-6
    np.testing.assert_allclose([d.values[k] for k in keys], [1.0, 0.3], rtol=0, atol=1e-7)


def test_roughness_smooths_a_profile_and_keeps_a_smooth_one(tmp_path):
    """``roughness`` penalises int_0^1 mu''(s)^2 ds of the free profile. The shape of the
    linear profile 1 + 0.3 (2s - 1) (scipy's solve_bvp, tol 1e-10) comes back to 1e-7 with
    eight coefficients and the penalty on (it vanishes there); a target with a ripple no
    profile of eight coefficients follows (0.5 sin(40 s) degrees) gets a profile whose
    int mu''^2 falls by more than 1e3 at roughness 0.1."""
    from scipy.integrate import solve_bvp

    from jaxrod.inverse.profile_conditions import roughness_rows

    K = 8
    rig = _rig(tmp_path, f"strength_profile = {[1.0] + [0.0] * (K - 1)}")
    keys = [f"magnetisation.strength_profile.{k}" for k in range(K)]
    mu = lambda s: 1.0 + 0.3 * (2 * s - 1)
    sol = solve_bvp(lambda s, y: np.vstack([y[1], -LOAD * mu(s) * np.cos(y[0])]),
                    lambda ya, yb: np.array([ya[0], yb[1]]), np.linspace(0, 1, 50),
                    np.zeros((2, 50)), tol=1e-10, max_nodes=100000)
    assert sol.success
    target = np.degrees(sol.sol(S)[0])
    smooth = design_shape(rig, keys, S, target, n=16, roughness=1.0)
    assert smooth.converged and smooth.reached
    np.testing.assert_allclose([smooth.values[k] for k in keys], [1.0, 0.3] + [0.0] * 6,
                               rtol=0, atol=1e-7)
    R = roughness_rows(keys)
    bend = lambda d: float(np.sum((R @ [d.values[k] for k in keys]) ** 2))
    rippled = target + 0.5 * np.sin(40 * S)
    free = design_shape(rig, keys, S, rippled, n=16)
    held = design_shape(rig, keys, S, rippled, n=16, roughness=0.1)
    assert free.converged and held.converged and bend(held) < 1e-3 * bend(free)
    with pytest.raises(ParameterError, match="roughness"):
        design_shape(rig, keys[1:], S, target, n=16, roughness=1.0)


def test_a_magnet_placed_for_a_target_shape(tmp_path):
    """A dipole's field: the shape of the rod under a magnet at (0.6, 1.3) rod lengths (by
    jaxrod at N = 16) is the target; from (0.5, 1.4) the design finds the magnet's position
    to 1e-8, and ramping the designed rig's magnet up reaches the designed equilibrium."""
    from jaxrod import spectral

    rig = tmp_path / "dipole.toml"
    rig.write_text(RIG.replace('kind = "uniform"\nload = 2.0\nangle_deg = 90.0',
                               'kind = "dipole"\nM = 0.5\nposition = [0.6, 1.3]\n'
                               'moment_direction = [0.0, 1.0]').format(magnetisation=""))
    shape = jr.equilibrium(jr.load_scene(str(rig)), n=16).state
    s = S[::2]
    rows = spectral.interpolation_matrix(16, s) @ np.asarray(jr.planar_discretisation(16).to_full)
    keys = ["field.0.position.0", "field.0.position.1"]
    start = jr.load_scene(str(rig), [f"{keys[0]}=0.5", f"{keys[1]}=1.4"])
    d = design_shape(start, keys, s, np.degrees(rows @ shape), n=16)
    assert d.converged and d.stable and d.reachable
    np.testing.assert_allclose([d.values[k] for k in keys], [0.6, 1.3], rtol=0, atol=1e-8)


def test_a_stability_margin_along_the_ramp_the_free_design_violates(tmp_path):
    """The field at 150 degrees bends the rod against its stiffness: along the ramp of the
    free design (six coefficients, target c = 1.2) the smallest eigenvalue of the second
    variation per unit int dtheta^2 dips below its value at full load. A margin between
    the two (1.757) holds at the design but not on the way; kept along the ramp it is met
    to its tolerance on the continued ramp (every point of ``jr.branch`` in load_scale,
    and the parabola through the least three), reached by the ramp, at the cost of the
    shape. The eigenvalue's normalisation: with the field at 90 degrees the least along the
    ramp is the unloaded rod's, pi^2 / 4 (EI theta'' = -lambda theta, theta(0) = 0,
    theta'(1) = 0) to 1e-10."""
    from jaxrod.inverse.shape_design import MARGIN_TOLERANCE

    K, c = 6, 1.2
    keys = [f"magnetisation.strength_profile.{k}" for k in range(K)]
    target = np.degrees(c * (S - S**2 / 2))
    straight = design_shape(_rig(tmp_path, f"strength_profile = {[1.0] + [0.0] * (K - 1)}"),
                            keys, S, TARGET_DEG, n=16)
    assert abs(straight.path_smallest_eigenvalue - math.pi**2 / 4) <= 1e-10
    path = tmp_path / "against.toml"
    path.write_text(RIG.format(magnetisation=f"strength_profile = {[1.0] + [0.0] * (K - 1)}")
                    .replace("angle_deg = 90.0", "angle_deg = 150.0"))
    rig = jr.load_scene(str(path))
    margin = 1.757
    free = design_shape(rig, keys, S, target, n=16)
    assert free.converged and free.shape_error_deg <= 1e-3 and free.reachable
    assert free.path_smallest_eigenvalue < margin < free.smallest_eigenvalue
    held = design_shape(rig, keys, S, target, n=16, margin=margin)
    assert held.converged and held.margin_met and held.reachable
    assert held.path_smallest_eigenvalue >= margin * (1.0 - MARGIN_TOLERANCE)
    assert held.shape_error_deg > 10 * free.shape_error_deg


def test_centreline_points_and_a_tip_pose(tmp_path):
    """Targets on the centreline, r(s) = int_0^s (sin theta, cos theta): the points of the
    shape of mu*(s) = 0.6 + 0.15 T1 - 0.05 T2 (Chebyshev in 2s - 1) under the field at 90
    degrees, by scipy's solve_bvp with the centreline integrated beside theta (tol 1e-10),
    give back the three coefficients to 1e-8 from the uniform remanence; the tip's pose
    (x, z, tangent angle) under load 3 at 120 degrees gives back the field's load and angle
    from (2.5, 100), by the command line (``--target-tip X,Z,DEG``)."""
    from command_line import run_cli
    from scipy.integrate import solve_bvp

    def solved(load, a, mu, s):
        sol = solve_bvp(lambda t, y: np.vstack([y[1], -load * mu(t) * np.sin(a - y[0]),
                                                np.sin(y[0]), np.cos(y[0])]),
                        lambda ya, yb: np.array([ya[0], yb[1], ya[2], ya[3]]),
                        np.linspace(0, 1, 50), np.vstack([0.5 * np.linspace(0, 1, 50),
                                                          np.full(50, 0.5), np.zeros(50),
                                                          np.linspace(0, 1, 50)]),
                        tol=1e-10, max_nodes=100000)
        assert sol.success
        return sol.sol(s)

    coef = [0.6, 0.15, -0.05]
    s = np.linspace(0.05, 1.0, 20)
    y = solved(LOAD, math.pi / 2, lambda t: np.polynomial.chebyshev.chebval(2 * t - 1, coef), s)
    keys = [f"magnetisation.strength_profile.{k}" for k in range(3)]
    d = design_shape(_rig(tmp_path, "strength_profile = [1.0, 0.0, 0.0]"), keys, s, None,
                     n=16, target_xz=np.stack([y[2], y[3]], axis=1))
    assert d.converged and d.reached and d.reachable and d.target_deg is None
    np.testing.assert_allclose([d.values[k] for k in keys], coef, rtol=0, atol=1e-8)

    tip = solved(3.0, math.radians(120.0), lambda t: 1.0, 1.0)
    rig = tmp_path / "tip.toml"
    rig.write_text(RIG.format(magnetisation="").replace("load = 2.0", "load = 2.5")
                   .replace("angle_deg = 90.0", "angle_deg = 100.0"))
    proc = run_cli("design", rig, "--free", "field.0.load,field.0.angle_deg", "--target-tip",
                   ",".join(map(repr, [float(tip[2]), float(tip[3]), math.degrees(tip[0])])),
                   "--n", "16", "--json")
    assert proc.returncode == 0, proc.stderr
    out = json.loads(proc.stdout)
    assert out["reached"] and out["position_error"] <= 1e-8
    np.testing.assert_allclose([out["values"]["field.0.load"],
                                out["values"]["field.0.angle_deg"]], [3.0, 120.0], rtol=0,
                               atol=1e-7)


def test_bounds_on_a_profile_that_must_change_sign(tmp_path):
    """theta*(s) = 0.2 (s - s^2 / 2) + 1.2 (s^3 / 3 - s^4 / 4) curves back (theta*'' > 0 near
    s = 1/3): its remanence mu = -theta*'' / (load cos theta*) changes sign. Free, the design
    reaches it with mu < 0 there; bounded to mu(s) in [0, 10] (the profile's values at 101
    points), it keeps mu >= 0 and says that the target is not reached at its bounds."""
    K = 8
    rig = _rig(tmp_path, f"strength_profile = {[1.0] + [0.0] * (K - 1)}")
    keys = [f"magnetisation.strength_profile.{k}" for k in range(K)]
    target = np.degrees(0.2 * (S - S**2 / 2) + 1.2 * (S**3 / 3 - S**4 / 4))
    s = np.linspace(0.0, 1.0, 101)
    mu = lambda d: np.polynomial.chebyshev.chebval(2 * s - 1, [d.values[k] for k in keys])
    free = design_shape(rig, keys, S, target, n=16)
    assert free.converged and free.reached and mu(free).min() < -0.05
    held = design_shape(rig, keys, S, target, n=16,
                        bounds={"magnetisation.strength_profile": (0.0, 10.0)})
    assert not held.reached and held.shape_error_deg > 1.0 and mu(held).min() >= 0.0
    assert "not reached" in held.reason and "bounds" in held.reason
    with pytest.raises(ParameterError, match="bounds"):
        design_shape(rig, keys[1:], S, target, n=16,
                     bounds={"magnetisation.strength_profile": (0.0, 10.0)})


def test_a_design_at_too_small_a_degree_says_so(tmp_path):
    """At N = 4 the designed equilibrium's Chebyshev tail is far above 1e-8 rad: the design
    converges but its status is UNDER_RESOLVED (at N = 16 the same design is a success)."""
    rig = _rig(tmp_path, "strength_profile = [1.0, 0.0]")
    keys = ["magnetisation.strength_profile.0", "magnetisation.strength_profile.1"]
    coarse = design_shape(rig, keys, S, TARGET_DEG, n=4)
    assert coarse.converged and coarse.error_estimate > 1e-8
    assert coarse.status is jr.Status.UNDER_RESOLVED and not coarse.status.ok
    fine = design_shape(rig, keys, S, TARGET_DEG, n=16)
    assert fine.status is jr.Status.SUCCESS and fine.error_estimate <= 1e-8
