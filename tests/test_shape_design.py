"""Design for a target shape (``jaxrod.inverse.shape_design``) against closed forms.

A hard magnetisation in a uniform field at a = 90 degrees on a clamped-free rod: the moment
balance theta'' + load mu(s) sin(a - theta - phi(s)) = 0 with theta'(1) = 0 (the term's
density -load mu(s) cos(theta + phi(s) - a) varied in theta) gives, for the target
theta*(s) = c (s - s^2 / 2) (theta*(0) = 0, theta*'(1) = 0, theta*'' = -c),

* the strength profile along the tangent (phi = 0): mu(s) = c / (load cos theta*(s));
* the angle profile at uniform strength: sin(a - theta* - phi) = c / load, so
  phi(s) = pi / 2 - arcsin(c / load) - c s + (c / 2) s^2, a quadratic in s (the branch of
  the arcsine that a design started at a small angle reaches: the stable one).
"""

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


@pytest.mark.parametrize("s, target, match", [
    ([0.0, 0.5, math.nan], [0.0, 1.0, 2.0], "finite"),
    ([0.0, 0.5, 1.2], [0.0, 1.0, 2.0], r"s must lie in \[0, 1\]"),
    ([0.0, 1.0], [0.0, 1.0], "at least 3 points")])
def test_bad_targets_are_named(tmp_path, s, target, match):
    rig = _rig(tmp_path, "strength_profile = [1.0, 0.0]")
    with pytest.raises(ParameterError, match=f"target: .*{match}"):
        design_shape(rig, ["magnetisation.strength_profile.1"], s, target, n=8)
