"""The framed rod's chart (``jaxrod.discretise.framed``): the frame, its Darboux vector, and
the independent reference for the twisted clamped-clamped rod's buckling
(``_critical_moment_by_determinant``, used by tests/test_twisted.py).

The buckling reference: a straight rod (B = 1, L = 1) clamped at both ends, the far end
turned about the axis and pulled by a dead tension t, loses stability at the twisting
moment M where the linearised Kirchhoff equations for the deflection w = x + i y,
w'''' - i M w''' - t w'' = 0, w = w' = 0 at both ends, have a nontrivial solution: where
the 2 x 2 block of the fundamental matrix expm(A) (A the companion matrix; scipy) is
singular; at t = 0 this is M = 2 x with tan x = x.
"""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxrod.discretise.director import director
from jaxrod.discretise.framed import frame, framed_discretisation, framed_jet
from jaxrod.params import ParameterError

RNG = np.random.default_rng(7)


@pytest.mark.parametrize("scale", [1.0, 1e-3])
def test_the_frame_is_a_rotation_whose_third_column_is_the_director(scale):
    """At random chart values (and near v = 0, where the chart's series are used): F^T F = I
    and det F = 1 to round-off, F e3 = the director chart's d3(v); the Darboux vector's
    bending part is |d3'| and its twist psi' - (1 - cos|v|) / |v|^2 (v1 v2' - v2 v1')."""
    for a in scale * RNG.normal(size=(20, 6)):
        F, u = framed_jet(jnp.asarray(a))
        F = np.asarray(F)
        np.testing.assert_allclose(F.T @ F, np.eye(3), rtol=0, atol=1e-14)
        assert abs(np.linalg.det(F) - 1.0) <= 1e-14
        d3, dd3 = jax.jvp(lambda v: director(v[0], v[1]), (jnp.asarray(a[:2]),),
                          (jnp.asarray(a[3:5]),))
        np.testing.assert_allclose(F[:, 2], d3, rtol=0, atol=1e-15)
        assert abs(float(u[0] ** 2 + u[1] ** 2 - jnp.dot(dd3, dd3))) <= 1e-13
        r2 = a[0] ** 2 + a[1] ** 2
        twist = a[5] - (1.0 - math.cos(math.sqrt(r2))) / r2 * (a[0] * a[4] - a[1] * a[3])
        assert abs(float(u[2]) - twist) <= 1e-13 * max(1.0, abs(twist))


def test_the_chart_frame_along_a_cone_turns_by_its_solid_angle():
    """Along v = alpha (cos ks, sin ks) (d3 on a cone of half-angle alpha about e3) with
    psi = 0 the frame twists at -(1 - cos alpha) k: over a turn of d3, minus the solid angle
    2 pi (1 - cos alpha) the cone encloses (the sphere's holonomy); its curvature is
    k sin alpha."""
    alpha, k = 1.1, 3.0
    for s in np.linspace(0.0, 1.0, 7):
        c, sn = math.cos(k * s), math.sin(k * s)
        a = jnp.array([alpha * c, alpha * sn, 0.0, -alpha * k * sn, alpha * k * c, 0.0])
        _, u = framed_jet(a)
        assert abs(float(u[2]) + (1.0 - math.cos(alpha)) * k) <= 1e-14
        assert abs(math.hypot(float(u[0]), float(u[1])) - k * math.sin(alpha)) <= 1e-14


def test_the_twisted_straight_rod_and_the_turned_far_end():
    """Clamped-clamped, x = 0 with N turns: psi = 2 pi N s, the frame at the far end R3(2 pi
    N), u = (0, 0, 2 pi N) at every fine node."""
    disc = framed_discretisation(8, "clamped-clamped")
    jets = disc.jets(jnp.zeros(disc.size), 1.3)
    F, u = jax.vmap(framed_jet)(jets)
    np.testing.assert_allclose(u, np.tile([0.0, 0.0, 2 * math.pi * 1.3], (len(u), 1)),
                               rtol=0, atol=1e-13)
    turn = 2 * math.pi * 1.3
    np.testing.assert_allclose(F[-1], np.asarray(frame(0.0, 0.0, turn)), atol=1e-14)
    with pytest.raises(ParameterError, match="support"):
        framed_discretisation(8, "pinned")


def test_the_grid_gathered_at_the_middle_resolves_a_layer_there():
    """f = sech(40 (s - 1/2)), a localised helix's profile (poles at distance pi / 80 from
    s = 1/2): on the grid mapped into a layer of width 1/40, degree 64, its interpolant's
    derivative at the fine nodes (to 1e-8 of its largest, 20), its integral (to 1e-12) and
    the cumulative integral of f^2 at the nodes (to 1e-12) are the closed forms' (-40 f
    tanh, atan(tanh 10) / 10, (tanh(40 (s - 1/2)) + tanh 20) / 40); on the plain grid of
    the same degree the derivative is off by more than 0.1. The map and its inverse agree
    to round-off."""
    from jaxrod.discretise import grid_map
    from jaxrod.discretise.planar import field_discretisation

    def sech(s):
        return 1.0 / np.cosh(40.0 * (s - 0.5))

    errors = []
    for width in (1.0 / 40.0, None):
        field = field_discretisation(64, "pinned", layer_width=width)
        nodes, s_q = np.asarray(field.nodes), np.asarray(field.quad_nodes)
        values = sech(nodes)
        derivative = np.asarray(field.to_quad_diff) @ values
        exact = -40.0 * sech(s_q) * np.tanh(40.0 * (s_q - 0.5))
        errors.append(np.max(np.abs(derivative - exact)))
        if width is not None:
            integral = float(field.integrate(np.asarray(field.to_quad) @ values))
            assert abs(integral - math.atan(math.tanh(10.0)) / 10.0) <= 1e-12
            cumulative = np.asarray(field.cumint) @ values**2
            exact = (np.tanh(40.0 * (nodes - 0.5)) + math.tanh(20.0)) / 40.0
            assert np.max(np.abs(cumulative - exact)) <= 1e-12
            xi = np.linspace(0.0, 1.0, 11)
            np.testing.assert_allclose(grid_map.grid_coordinate(
                grid_map.arclength(xi, width), width), xi, atol=1e-14)
    assert errors[0] <= 1e-8 * 20 and errors[1] >= 0.1
    with pytest.raises(ParameterError, match="layer_width"):
        field_discretisation(8, "pinned", layer_width=0.0)


def _critical_moment_by_determinant(t: float) -> float:
    """The least M > 0 where w'''' = i M w''' + t w'' has a nontrivial solution with
    w = w' = 0 at s = 0 and 1: det of the (w, w') rows and (w'', w''') columns of expm(A)
    vanishes (times exp(-i M / 2) it is real); bracketed on a grid, then brentq."""
    from scipy.linalg import expm
    from scipy.optimize import brentq

    def g(m):
        A = np.zeros((4, 4), complex)
        A[0, 1] = A[1, 2] = A[2, 3] = 1.0
        A[3, 2], A[3, 3] = t, 1j * m
        block = expm(A)[:2, 2:]
        return (np.linalg.det(block) * np.exp(-0.5j * m)).real

    grid = np.linspace(0.5, 40.0, 800)
    values = np.array([g(m) for m in grid])
    i = int(np.nonzero(np.sign(values[:-1]) != np.sign(values[1:]))[0][0])
    return brentq(g, grid[i], grid[i + 1], xtol=1e-14)
