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
    ([0.0, 1.0], [0.0, 1.0], "at least 3 points")])
def test_bad_targets_are_named(tmp_path, s, target, match):
    rig = _rig(tmp_path, "strength_profile = [1.0, 0.0]")
    with pytest.raises(ParameterError, match=f"target: .*{match}"):
        design_shape(rig, ["magnetisation.strength_profile.1"], s, target, n=8)


def _target_csv(path, rows):
    path.write_text("s,tangent_deg\n" + "".join(f"{a!r},{b!r}\n" for a, b in rows))
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


@pytest.mark.parametrize("rows, words", [
    ([(0.0, 0.0), (0.5, math.nan), (1.0, 2.0)], "finite"),
    ([(0.0, 0.0), (0.5, 1.0), (1.5, 2.0)], "s must lie in"),
    ([(0.0, 0.0), (1.0, 2.0)], "at least 3 rows")])
def test_bad_target_files_exit_2_with_one_line(tmp_path, rows, words):
    from command_line import run_cli

    rig = tmp_path / "rig.toml"
    rig.write_text(RIG.format(magnetisation="strength_profile = [1.0, 0.0]"))
    proc = run_cli("design", rig, "--free", "magnetisation.strength_profile",
                   "--target-shape", _target_csv(tmp_path / "t.csv", rows))
    assert proc.returncode == 2 and proc.stdout == ""
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and "target-shape" in lines[0] and words in lines[0]


def test_a_strength_profile_places_a_fold_at_a_field_angle(tmp_path):
    """A design through the folds (``jr.design_folds``) with a profile's coefficient free:
    the hard-magnetic cantilever (load 5, folds at 212.15 and 147.85 degrees with a uniform
    remanence) gets its first fold at 200 degrees from the slope of its strength; a fresh
    continuation from the straight rod of the designed rig finds it there to 1e-9 degrees,
    and the loop's width (the two folds' difference) with it."""
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


def test_a_stability_margin_the_free_design_violates(tmp_path):
    """The strength profile for the target (six coefficients) holds the rod with the
    Hessian's smallest eigenvalue 0.15; asking 0.3 trades shape for stability: the margin
    met to its tolerance (a penalty that binds), the shape missed, still reached by the
    ramp. One compiled program for both (the margin is traced)."""
    from jaxrod.inverse.shape_design import MARGIN_TOLERANCE

    K = 6
    rig = _rig(tmp_path, f"strength_profile = {[1.0] + [0.0] * (K - 1)}")
    keys = [f"magnetisation.strength_profile.{k}" for k in range(K)]
    free = design_shape(rig, keys, S, TARGET_DEG, n=16)
    assert free.converged and free.shape_error_deg <= 1e-5 and free.smallest_eigenvalue < 0.3
    held = design_shape(rig, keys, S, TARGET_DEG, n=16, margin=0.3)
    assert held.converged and held.margin_met and held.reachable
    assert abs(held.smallest_eigenvalue - 0.3) <= MARGIN_TOLERANCE * 0.3
    assert held.shape_error_deg > 1.0


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
