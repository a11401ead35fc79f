"""Greenhill stability of the upright rod in a uniform field (paper, "Uniform Magnetic Field").

The straight rod d3 = e3 is strictly stable iff A + beta0(G) > 0 (Proposition "Stability of
the gravity-opposed straight configuration"), where beta0 is the principal eigenvalue of

    -u'' - G (1 - s) u = beta u   on (0, 1),   u'(1) = 0,   u(0) = 0 (clamped) | u'(0) = 0 (pinned)

i.e. the minimum of the Rayleigh quotient int [u'^2 - G (1 - s) u^2] / int u^2. jaxrod takes
the discrete second variation as the autodiff Hessian of the discrete scene energy at theta = 0
(``UniformField``), which is an exact Rayleigh-Ritz discretisation in the polynomials of
degree n; the generalised symmetric eigenproblem H u = beta M u is solved by Cholesky + eigh,
and beta0 is re-evaluated as the Rayleigh quotient of the eigenvector in factored form (the
quotient is stationary, so this halves the digits lost to round-off in ||H|| ~ n^4).

Derived quantities:

* ``A_crit = -beta0(G)``: the anisotropy above which the straight rod is stable.
* ``G_crit``: the clamped Greenhill load, beta0^cl(G_crit) = 0, computed as the smallest
  eigenvalue of int u'^2 = G int (1 - s) u^2. Continuous characterisation (x = 1 - s,
  u = c1 Ai(-G^{1/3} x) + c2 Bi(-G^{1/3} x), u_x(0) = 0 gives c1 = sqrt(3) c2):
  Ai(-G^{1/3}) + Bi(-G^{1/3}) / sqrt(3) = 0, the paper's formula, G_crit = 7.837347...
* ``A2``: the pitchfork coefficient, A(r) = A_crit + A2 r^2 on the buckled branch, with u
  the principal eigenfunction normalised by int u^2 = 1 and r = int theta u
  (Proposition "Character of the first bifurcation"):

      A2 = 1/6 int (4 A_crit - G (1 - s)) u^4 = 1/2 (A_crit int u^4 - int u^2 u'^2).

  A2 < 0: supercritical (buckled branches exist where the straight rod is unstable, A <
  A_crit, and are stable); A2 > 0: subcritical.
"""

from __future__ import annotations

import dataclasses
import functools
import math

import jax
import jax.numpy as jnp
import numpy as np

from jaxrod.discretise.planar import PlanarDiscretisation, check_support, planar_discretisation
from jaxrod.params import ParameterError, Rod, check, check_degree
from jaxrod.programs import jit
from jaxrod.scenes.uniform import UniformField
from jaxrod.solvers.eigen import smallest_generalised_eigenpair
from jaxrod.solvers.newton import newton

#: Largest zeros of Ai and Ai' (DLMF table 9.9.1); they set the paper's explicit bounds.
AIRY_A1 = -2.338107410459767
AIRY_A1_PRIME = -1.018792971647471


def default_degree(G: float) -> int:
    """Chebyshev degree resolving the Airy layer of width G^(-1/3) at the support.

    The convergence study in ``benchmarks/greenhill_convergence.py`` shows beta0 at round-off
    (1e-15 relative) from n = 24 for G <= 1e3 and n = 32 for G = 1e4; this default keeps a
    factor ~1.5 margin (n ~ 16 G^(1/6), rounded up to a multiple of 8 so that nearby G share
    one compiled program).
    """
    n = max(32.0, 16.0 * max(G, 1.0) ** (1.0 / 6.0))
    return int(8 * math.ceil(n / 8.0))


@jit
def _straight_hessian(G, disc: PlanarDiscretisation):
    """Discrete second variation at theta = 0 with A = 0: the matrix of int u'^2 - G(1-s)u^2."""
    energy = lambda theta: UniformField(G, 0.0).energy(theta, disc)
    return jax.hessian(energy)(jnp.zeros(disc.size))


def _quadratic_form(u, G, disc: PlanarDiscretisation):
    """int_0^1 [u'^2 - G (1 - s) u^2] ds in factored form (no matrix of norm n^4)."""
    uq, duq = disc.at_quadrature(u)
    return disc.integrate(duq**2 - G * (1.0 - disc.quad_nodes) * uq**2)


@jit
def principal_eigenpair(G, disc: PlanarDiscretisation):
    """(beta0(G), u) for the support of ``disc``: int u^2 = 1 and int u > 0 (u > 0 inside).

    beta0(G) is the smallest eigenvalue of -u'' - G (1 - s) u = beta u with the support's
    boundary conditions, the discrete form of the second variation of the straight rod
    without field. Pure JAX: differentiable in G (and vmappable over G). Paper: Proposition
    ``thm:uniform_straight_stability`` (eq. ``uniform_straight_second_variation``).
    """
    H = _straight_hessian(G, disc)
    _, u = smallest_generalised_eigenpair(H, disc.mass_matrix())
    u = u * jnp.sign(disc.mean(u))
    u = u / jnp.sqrt(disc.inner(u, u))
    return _quadratic_form(u, G, disc), u


def pitchfork_coefficients(G, disc: PlanarDiscretisation):
    """(beta0, A2 by the u^4 formula, A2 by the u^2 u'^2 formula) at G."""
    beta0, u = principal_eigenpair(G, disc)
    a_crit = -beta0
    uq, duq = disc.at_quadrature(u)
    a2_quartic = disc.integrate((4.0 * a_crit - G * (1.0 - disc.quad_nodes)) * uq**4) / 6.0
    a2_gradient = 0.5 * (a_crit * disc.integrate(uq**4) - disc.integrate(uq**2 * duq**2))
    return beta0, a2_quartic, a2_gradient


@jit
def _greenhill_load(disc: PlanarDiscretisation):
    K = _straight_hessian(0.0, disc)
    W = K - _straight_hessian(1.0, disc)  # matrix of int (1 - s) u^2 (SPD)
    _, u = smallest_generalised_eigenpair(K, W)
    uq, duq = disc.at_quadrature(u)
    return disc.integrate(duq**2) / disc.integrate((1.0 - disc.quad_nodes) * uq**2)


def greenhill_load(n: int = 40) -> float:
    """G_crit: smallest G with beta0^cl(G) = 0, from int u'^2 = G int (1 - s) u^2.

    Paper: Lemma ``lem:greenhill`` (the Airy characteristic equation
    ``clamped_Airy_characteristic``; G_crit = 7.8373...).
    """
    return float(_greenhill_load(planar_discretisation(n, "clamped")))


def criticality(a2: float) -> str:
    """'supercritical' for A2 < 0, 'subcritical' for A2 > 0 (A decreasing destabilises)."""
    if a2 < 0:
        return "supercritical"
    if a2 > 0:
        return "subcritical"
    return "degenerate"


def paper_bounds(G: float, support: str, g_crit: float) -> tuple[float, float]:
    """The paper's explicit (lower, upper) bounds on A_crit = -beta0 (Prop. "Explicit bounds").

    Clamped, G > G_crit: G - |a1| G^(2/3) < A_crit <= G - G_crit^(1/3) G^(2/3).
    Pinned: max(G/2, G - |a1'| G^(2/3)) <= A_crit <= G, and for G > G_crit also
    A_crit <= G - c_p G^(2/3). For clamped G <= G_crit the paper states no bound (nan).
    """
    g23 = G ** (2.0 / 3.0)
    if support == "clamped":
        if G <= g_crit:
            return math.nan, math.nan
        return G - abs(AIRY_A1) * g23, G - g_crit ** (1.0 / 3.0) * g23
    lower = max(G / 2.0, G - abs(AIRY_A1_PRIME) * g23)
    upper = G
    if G > g_crit:
        upper = G - _pinned_bound_constant(g_crit) * g23
    return lower, upper


@functools.lru_cache(maxsize=8)
def _pinned_bound_constant(g_crit: float) -> float:
    """c_p = (beta0^p(G_crit) + G_crit) / G_crit^(2/3) (paper: 0.8686), computed once."""
    disc = planar_discretisation(default_degree(g_crit), "pinned")
    beta_p, _ = _pitchfork_jit(g_crit, disc)[:2]
    return (float(beta_p) + g_crit) / g_crit ** (2.0 / 3.0)


@dataclasses.dataclass(frozen=True)
class GreenhillResult:
    """Stability of the upright rod at (G, A) for one support."""

    G: float
    support: str
    beta0: float
    A_crit: float
    A2: float
    criticality: str
    G_crit: float
    n: int
    A: float | None = None
    stable: bool | None = None

    def as_dict(self) -> dict:
        d = {k: getattr(self, k) for k in ("G", "support", "beta0", "A_crit", "A2",
                                           "criticality", "G_crit")}
        if self.A is not None:
            d["A"] = self.A
            d["stable"] = self.stable
        return d


_G_CRIT_CACHE: dict[int, float] = {}


def greenhill(G: float, support: str = "clamped", A: float | None = None,
              n: int | None = None) -> GreenhillResult:
    """Principal eigenvalue, A_crit, A2, criticality, G_crit and (given A) the verdict.

    Args:
      G: gravity group, > 0.
      support: "clamped" or "pinned".
      A: anisotropy group (optional); the rod is stable iff A + beta0 > 0.
      n: Chebyshev degree (default ``default_degree(G)``).

    The second variation of the straight rod is int [u'^2 + (A - G (1 - s)) u^2] ds;
    beta0(G) is the principal eigenvalue of -u'' - G (1 - s) u, so the rod is stable iff A >
    A_crit = -beta0(G). Paper: Proposition ``thm:uniform_straight_stability`` (eq.
    ``uniform_straight_second_variation``), Lemma ``lem:greenhill`` (G_crit), Proposition
    ``thm:uniform_bifurcation_criticality`` (A2, eq.
    ``uniform_bifurcation_coefficient_simplified``).
    """
    G = check("G", G)
    check_support(support)
    if A is not None:
        A = check("A", A)
    n = default_degree(G) if n is None else check_degree(n)
    disc = planar_discretisation(n, support)
    beta0, a2, _ = (float(v) for v in _pitchfork_jit(G, disc))
    if n not in _G_CRIT_CACHE:
        _G_CRIT_CACHE[n] = greenhill_load(max(n, 32))
    stable = None if A is None else bool(A + beta0 > 0.0)
    return GreenhillResult(G=G, support=support, beta0=beta0, A_crit=-beta0, A2=a2,
                           criticality=criticality(a2), G_crit=_G_CRIT_CACHE[n], n=n, A=A,
                           stable=stable)


_pitchfork_jit = jit(pitchfork_coefficients)


def stability_curve(G_values, support: str = "clamped", n: int | None = None):
    """(A_crit, A2) at many G at once (one compiled, vmapped program for a fixed degree n).

    Paper: the curves of Figures ``fig:clamped1`` and ``fig:pinned``, bounded by Proposition
    ``thm:uniform_eigenvalue_bounds``.
    """
    G_values = jnp.asarray(G_values, dtype=jnp.float64)
    n = n or default_degree(float(jnp.max(G_values)))
    disc = planar_discretisation(n, support)
    beta0, a2, _ = _pitchfork_batch(G_values, disc)
    return -np.asarray(beta0), np.asarray(a2)


_pitchfork_batch = jit(jax.vmap(pitchfork_coefficients, in_axes=(0, None)))


def _a2_residual(x, disc):
    return jnp.atleast_1d(pitchfork_coefficients(x[0], disc)[1])


@jit
def _solve_a2_zero(g0, disc):
    # A2 carries round-off ~ eps ||H|| / gap ~ 1e-12..1e-11 from the eigenvector (||H|| ~ n^4),
    # so |A2| <= 1e-10 is the honest stopping test (an error in G of ~5e-10).
    return newton(_a2_residual, jnp.atleast_1d(g0), disc, tol=1e-10)


def criticality_switch_load(n: int = 48, bracket: tuple[float, float] = (8.0, 200.0)) -> float:
    """The G at which the clamped pitchfork turns from super- to subcritical (A2(G) = 0).

    The paper proves a sign change exists (A2 < 0 near G_crit, A2 > 0 for large G) but does
    not locate it. The root is bracketed by a scan in log G and polished by Newton with the
    exact derivative dA2/dG (autodiff through the eigensolver).
    """
    disc = planar_discretisation(n, "clamped")
    grid = np.geomspace(*bracket, 40)
    values = np.array(jax.vmap(lambda G: _a2_residual(jnp.atleast_1d(G), disc))(
        jnp.asarray(grid)))[:, 0]
    change = np.nonzero(np.sign(values[:-1]) != np.sign(values[1:]))[0]
    if change.size == 0:
        raise RuntimeError(f"A2 has no sign change for G in {bracket}")
    result = _solve_a2_zero(0.5 * (grid[change[0]] + grid[change[0] + 1]), disc)
    if not bool(result.converged):
        raise RuntimeError(f"A2 = 0 solve failed: {result.message()}")
    return float(result.x[0])


def _stability_margin(x, args):
    """(A + beta0(G)) / G at L = exp(x), with G = g L^3 and A = a L^2."""
    g_per_l3, a_per_l2, disc = args
    L = jnp.exp(x[0])
    G = g_per_l3 * L**3
    beta0, _ = principal_eigenpair(G, disc)
    return jnp.atleast_1d((a_per_l2 * L**2 + beta0) / G)


@jit
def _solve_critical_log_length(x0, g_per_l3, a_per_l2, disc):
    return newton(_stability_margin, jnp.atleast_1d(x0), (g_per_l3, a_per_l2, disc), tol=1e-15)


def critical_length(rod: Rod, support: str = "clamped", field_on: bool = True,
                    n: int | None = None) -> float:
    """Length (m) at which the upright rod loses stability: A(L) + beta0(G(L)) = 0.

    With the field off and a clamped support this is the Greenhill length
    L_c = (G_crit E b^2 / (4 rho g))^(1/3). A pinned rod without field is unstable at every
    length (returns 0.0). With the field on, G ~ L^3 and A ~ L^2 and the root is found by
    Newton in log L, started from the stabilisation length K_d / (rho g) (where A = G).

    Paper: Theorems ``thm:uniform_physical_clamped`` and ``thm:uniform_physical_pinned``.
    """
    check_support(support)
    g_per_l3 = rod.G / rod.length**3
    if not field_on:
        if support == "pinned":
            return 0.0
        return (greenhill_load() / g_per_l3) ** (1.0 / 3.0)
    a_per_l2 = rod.A(True) / rod.length**2
    if a_per_l2 == 0.0:
        return critical_length(rod, support, field_on=False, n=n)
    l_stab = a_per_l2 / g_per_l3
    disc = planar_discretisation(n or default_degree(g_per_l3 * (4.0 * l_stab) ** 3), support)
    result = _solve_critical_log_length(math.log(l_stab), g_per_l3, a_per_l2, disc)
    if not bool(result.converged):
        raise ParameterError(f"critical length solve failed: {result.message()}")
    return float(math.exp(result.x[0]))
