"""The fold's normal form in time (jaxrod.dynamics.normal_form): its two constants against
scipy, its scalings and its bad inputs."""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.special import ai_zeros

from jaxrod.dynamics.normal_form import NormalForm, escape_time
from jaxrod.params import ParameterError


def test_the_damped_escape_time_is_the_first_airy_zero():
    """x' = -tau - x^2 is x = -d/dtau log Ai(-tau): it escapes at the first zero of Ai."""
    assert escape_time(0.0, 1.0) == pytest.approx(-ai_zeros(1)[0][0], rel=1e-10)


def _escape_by_scipy(k):
    """x'' + k x' = -tau - x^2 from the stable branch (sqrt(z) + k / 4z + 1 / 8z^2, z = -tau,
    and at k = 0 the next term -49 / 128 z^(9/2)), by scipy's DOP853 with an event at
    x = -1e6, plus the run-away's tail 2 sqrt(3/2 / 1e6)."""
    z = 30.0
    x0 = math.sqrt(z) + k / (4 * z) + 1 / (8 * z * z) - (0 if k else 49 / 128 * z**-4.5)
    v0 = -(0.5 / math.sqrt(z) - k / (4 * z * z) - 1 / (4 * z**3) + (0 if k else
                                                                    441 / 256 * z**-5.5))
    y0, tau0 = [x0, v0], -z

    def away(t, y):
        return y[0] + 1e6
    away.terminal = True
    sol = solve_ivp(lambda t, y: [y[1], -t - y[0] ** 2 - k * y[1]], (tau0, 20.0), y0,
                    method="DOP853", rtol=1e-13, atol=1e-13, events=away)
    return sol.t_events[0][0] + 2.0 * math.sqrt(1.5 / 1e6)


@pytest.mark.parametrize("k", [0.0, 0.5])
def test_the_inertial_escape_time_against_scipy(k):
    """x'' + k x' = -tau - x^2 (Painleve I at k = 0: tau_i = 3.41167179) against DOP853."""
    assert escape_time(1.0, k) == pytest.approx(_escape_by_scipy(k), rel=1e-7)


def test_the_lag_joins_its_two_power_laws():
    """The full lag follows P_i eps^(4/5) at fast rates and P_d eps^(2/3) at slow ones (to
    the scaled equation's own corrections), continuous where the scalings swap (k = 1)."""
    nf = NormalForm("v", 0.0, mass=0.3, drive=2.0, curvature=-40.0, damping=0.5)
    slow, fast = 1e-15, 1e2
    assert nf.lag(slow) == pytest.approx(nf.damped_prefactor * slow ** (2 / 3), rel=0.01)
    assert nf.lag(fast) == pytest.approx(nf.inertial_prefactor * fast**0.8, rel=0.05)
    ab = abs(2.0 * -40.0) / 0.3**2
    at_k1 = ab * 0.5**5  # c T_i = 1
    below, above = nf.lag(at_k1 * (1 + 1e-9)), nf.lag(at_k1 * (1 - 1e-9))
    assert below == pytest.approx(above, rel=1e-6)
    c = nf.crossover_rate
    assert nf.damped_prefactor * c ** (2 / 3) == pytest.approx(nf.inertial_prefactor * c**0.8)
    # invariant under the null vector's scale: phi -> s phi
    s = 3.7
    scaled = NormalForm("v", 0.0, mass=0.3 * s**2, drive=2.0 * s, curvature=-40.0 * s**3,
                        damping=0.5)
    assert scaled.lag(1e-4) == pytest.approx(nf.lag(1e-4), rel=1e-12)


@pytest.mark.parametrize("rate", [0.0, float("nan"), float("inf")])
def test_bad_rates(rate):
    nf = NormalForm("v", 0.0, mass=1.0, drive=1.0, curvature=1.0, damping=0.0)
    with pytest.raises(ParameterError, match="rate"):
        nf.lag(rate)


def test_no_drag_has_no_damped_law():
    nf = NormalForm("v", 0.0, mass=1.0, drive=1.0, curvature=1.0, damping=0.0)
    assert math.isinf(nf.damped_prefactor) and nf.crossover_rate == 0.0
    assert np.isfinite(nf.lag(1e-3))
