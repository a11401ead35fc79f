"""The framed rod's chart (``jaxrod.discretise.framed``): the frame, its Darboux vector, and
the twisted clamped-clamped rod's buckling against independent methods.

The buckling check: a straight rod (B = 1, L = 1, C / B = gamma) clamped at both ends, the
far end turned by N turns about the axis and pulled by a dead tension t, its far end held on
the axis (int d3_x ds = int d3_y ds = 0). The straight state carries the twisting moment
M = gamma 2 pi N; it loses stability where the second variation restricted to the
constraints' tangent space first has a zero eigenvalue (a double one: the rotational
symmetry). Independent: the linearised Kirchhoff equations for the deflection w = x + i y,
w'''' - i M w''' - t w'' = 0, w = w' = 0 at both ends, a nontrivial solution where the 2 x 2
block of the fundamental matrix expm(A) (A the companion matrix; scipy) is singular; at
t = 0 this is M = 2 x with tan x = x.
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
GAMMA = 0.769


def _energy(disc, tension=0.0, turns=0.0):
    """E(x) = 1/2 int (u1^2 + u2^2 + gamma u3^2) ds - tension int d3_z ds (B = 1, L = 1)."""

    def energy(x, args=None):
        def density(a):
            F, u = framed_jet(a)
            return 0.5 * (u[0] ** 2 + u[1] ** 2) + 0.5 * GAMMA * u[2] ** 2 - tension * F[2, 2]
        return disc.integrate(jax.vmap(density)(disc.jets(x, turns)))

    return energy


def _far_end(disc, shortening=None):
    """g(x): the far end on the axis (int d3_x = int d3_y = 0) and, with ``shortening``, at
    height 1 - shortening."""

    def g(x, args=None):
        d3 = jax.vmap(lambda a: framed_jet(a)[0][:, 2])(disc.jets(x, 0.0))
        ends = [disc.integrate(d3[:, 0]), disc.integrate(d3[:, 1])]
        if shortening is not None:
            ends.append(disc.integrate(d3[:, 2]) - (1.0 - shortening))
        return jnp.stack(ends)

    return g


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


def test_the_twisting_moment_that_buckles_a_clamped_clamped_rod_under_tension():
    """The Greenhill problem of the clamped-clamped rod (module docstring), gamma = 0.769, at
    N = 16: the twisting moment at which the straight rod first has a zero eigenvalue of the
    constrained second variation, found by brentq on the smallest one, is the determinant
    method's to 1e-8 at t = -10, 10 and 100, and 2 x with tan x = x at t = 0."""
    from scipy.linalg import null_space
    from scipy.optimize import brentq

    disc = framed_discretisation(16, "clamped-clamped")
    x0 = jnp.zeros(disc.size)
    Z = null_space(np.asarray(jax.jacfwd(_far_end(disc))(x0)))
    hessian = jax.jit(jax.hessian(lambda x, turns, t: _energy(disc, t, turns)(x)))
    smallest = lambda turns, t: np.linalg.eigvalsh(Z.T @ np.asarray(hessian(x0, turns, t))
                                                   @ Z)[0]
    x = brentq(lambda v: math.tan(v) - v, 4.0, 4.6, xtol=1e-15)
    for t, reference in ((0.0, 2 * x), (-10.0, None), (10.0, None), (100.0, None)):
        reference = reference or _critical_moment_by_determinant(t)
        turns = brentq(lambda v: smallest(v, t), 0.2, 8.0, xtol=1e-14)
        assert abs(GAMMA * 2 * math.pi * turns - reference) <= 1e-8
        if t == 0.0:
            assert abs(_critical_moment_by_determinant(t) - reference) <= 1e-10


def test_a_clamped_clamped_rod_shortened_is_the_euler_elastica():
    """The far end held at 1 - e on the axis (e = 0.1), no turns: the constrained equilibrium
    (``jaxrod.solvers.constrained``) from the first buckling mode is the inflexional
    elastica of four quarter waves, whose thrust is P L^2 / B = 16 K(k)^2 with
    2 E(k) / K(k) - 1 = 1 - e (complete elliptic integrals, modulus k; scipy), here the
    multiplier of the height constraint, to 1e-10 at N = 24; the side reactions vanish. Its
    constrained second variation has one zero eigenvalue (the shape turned about the axis,
    with the frame turned back: a symmetry of the isotropic rod) and no negative one."""
    from scipy.optimize import brentq
    from scipy.special import ellipe, ellipk

    from jaxrod import spectral
    from jaxrod.solvers.constrained import constrained_eigenvalues, constrained_equilibrium

    e, n = 0.1, 24
    disc = framed_discretisation(n, "clamped-clamped")
    energy, held = _energy(disc), _far_end(disc, e)
    x0 = np.zeros(disc.size)
    x0[:disc.free] = 0.6 * np.sin(2 * np.pi * spectral.chebyshev_nodes(n)[1:n])
    out = constrained_equilibrium(energy, held, x0, jnp.array([0.0, 0.0, 4 * np.pi**2]))
    assert bool(out.converged)
    x, mu = np.asarray(out.x[:disc.size]), np.asarray(out.x[disc.size:])
    k = brentq(lambda k: 2 * ellipe(k**2) / ellipk(k**2) - 1 - (1 - e), 1e-6, 0.999,
               xtol=1e-15)
    assert abs(mu[2] - 16 * ellipk(k**2) ** 2) <= 1e-10
    assert np.max(np.abs(mu[:2])) <= 1e-12
    eig = np.asarray(constrained_eigenvalues(energy, held, jnp.asarray(x), jnp.asarray(mu)))
    assert abs(eig[0]) <= 1e-10 and eig[1] > 0.1


def test_twist_and_writhe_add_up_to_the_far_ends_turns():
    """A rod clamped at both ends keeps its linking number: for a smooth bent and twisted
    state (|v| < pi) with the far end turned by 1.7 turns, Tw + Wr (Fuller's writhe against
    the straight rod) is 1.7 to 1e-12 at N = 24; neither alone is (the state writhes)."""
    from jaxrod import spectral
    from jaxrod.discretise.framed import twist_and_writhe

    n = 24
    disc = framed_discretisation(n, "clamped-clamped")
    s = spectral.chebyshev_nodes(n)[1:n]
    x = np.concatenate([1.4 * np.sin(np.pi * s) ** 2 * np.cos(3 * s),
                        1.1 * np.sin(2 * np.pi * s), 0.8 * np.sin(np.pi * s)])
    tw, wr = twist_and_writhe(disc, jnp.asarray(x), 1.7)
    assert abs(float(tw + wr) - 1.7) <= 1e-12
    assert abs(float(wr)) > 0.01
