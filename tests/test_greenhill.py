import airy_reference as airy
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.special import ai_zeros

from jaxrod.discretise.planar import planar_discretisation
from jaxrod.params import NICKEL, ParameterError, Rod
from jaxrod.uniform import greenhill as gh

G_VALUES = [0.1, 0.5, 2.0, 5.0, 20.0, 100.0, 400.0, 1000.0]


def test_greenhill_load_matches_the_papers_airy_formula():
    ref = airy.greenhill_load_paper_formula()
    assert f"{ref:.4f}" == "7.8373"  # the paper's printed value: its formula is right
    # and it is the root of the general clamped characteristic equation at beta = 0
    assert abs(airy.characteristic(0.0, ref, "clamped")) < 1e-14
    assert abs(gh.greenhill_load() - ref) / ref < 1e-12
    assert abs(gh.greenhill(3.0).G_crit - ref) / ref < 1e-12


@pytest.mark.parametrize("support", ["clamped", "pinned"])
def test_principal_eigenvalue_matches_airy_characteristic_equation(support):
    for G in G_VALUES:
        ref = airy.principal_eigenvalue(G, support)
        res = gh.greenhill(G, support)
        assert abs(res.beta0 - ref) <= 1e-10 * abs(ref), (G, res.beta0, ref)
        assert res.A_crit == -res.beta0


def test_beta0_vanishes_at_g_crit_and_changes_sign():
    g_crit = airy.greenhill_load_paper_formula()
    disc = planar_discretisation(40, "clamped")
    beta, _ = gh.principal_eigenpair(g_crit, disc)
    assert abs(float(beta)) < 1e-11
    assert gh.greenhill(g_crit * 0.99).stable is None
    assert gh.greenhill(g_crit * 0.99, A=0.0).stable
    assert not gh.greenhill(g_crit * 1.01, A=0.0).stable


@pytest.mark.parametrize("support", ["clamped", "pinned"])
def test_pitchfork_coefficient_matches_airy_quadrature(support):
    # G = 10 sits next to the clamped A2's zero (G = 9.9998, A2 = 4e-5 there): a relative
    # error is meaningless there, so the error is measured against max(|A2|, 1)
    for G in (0.5, 9.0, 10.0, 10.5, 100.0):
        ref = airy.pitchfork_coefficient(G, support)
        res = gh.greenhill(G, support)
        assert abs(res.A2 - ref) <= 1e-9 * max(abs(ref), 1.0), (G, res.A2, ref)
        assert res.criticality == ("subcritical" if ref > 0 else "supercritical")


def test_both_a2_formulas_agree_and_signs_follow_the_paper():
    disc_c = planar_discretisation(48, "clamped")
    disc_p = planar_discretisation(48, "pinned")
    for G in (8.0, 50.0, 500.0):
        beta, a2q, a2g = gh.pitchfork_coefficients(G, disc_c)
        assert abs(a2q - a2g) < 1e-9 * max(1.0, abs(a2q))
        if -beta >= G / 4.0:  # the paper's sufficient condition for subcriticality
            assert a2q > 0
    for G in np.geomspace(0.01, 1000.0, 9):
        assert gh.pitchfork_coefficients(G, disc_p)[1] > 0  # pinned: always subcritical
    g_crit = gh.greenhill_load()
    assert gh.pitchfork_coefficients(g_crit * 1.001, disc_c)[1] < 0  # supercritical near G_crit


def test_criticality_switch_load_is_a2_zero_by_independent_quadrature():
    from scipy.optimize import brentq

    g_switch = gh.criticality_switch_load()
    ref = brentq(lambda G: airy.pitchfork_coefficient(G, "clamped"), 9.0, 11.0, xtol=1e-13)
    assert abs(g_switch - ref) < 1e-8


@pytest.mark.parametrize("support", ["clamped", "pinned"])
def test_exact_a_crit_lies_within_the_papers_bounds(support):
    g_crit = gh.greenhill_load()
    G = np.geomspace(0.05, 1000.0, 25)
    a_crit, _ = gh.stability_curve(G, support)
    for g, a in zip(G, a_crit):
        lo, hi = gh.paper_bounds(g, support, g_crit)
        if np.isfinite(lo):
            assert lo - 1e-9 <= a <= hi + 1e-9, (g, lo, a, hi)


def test_airy_constants():
    a, ap, _, _ = ai_zeros(1)
    assert gh.AIRY_A1 == pytest.approx(a[0], abs=1e-15)
    assert gh.AIRY_A1_PRIME == pytest.approx(ap[0], abs=1e-15)


def test_eigenvalue_is_differentiable_hellmann_feynman():
    disc = planar_discretisation(32, "clamped")
    G = 12.0
    d_beta = jax.grad(lambda g: gh.principal_eigenpair(g, disc)[0])(G)
    _, u = gh.principal_eigenpair(G, disc)
    uq, _ = disc.at_quadrature(u)
    # d beta / dG = -int (1 - s) u^2 for normalised u
    assert float(d_beta) == pytest.approx(-float(disc.integrate((1 - disc.quad_nodes) * uq**2)),
                                          rel=1e-10)
    batch = jax.vmap(lambda g: gh.principal_eigenpair(g, disc)[0])(jnp.array([1.0, 12.0]))
    assert batch.shape == (2,)


def test_critical_lengths():
    rod = Rod(NICKEL.with_youngs_modulus(100e9), 50e-6, 0.1)
    L_c = gh.critical_length(rod, "clamped", field_on=False)
    assert Rod(rod.material, 50e-6, L_c).G == pytest.approx(gh.greenhill_load(), rel=1e-12)
    for support in ("clamped", "pinned"):
        L = gh.critical_length(rod, support, field_on=True)
        at = rod.with_length(L)
        assert at.A(True) == pytest.approx(gh.greenhill(at.G, support).A_crit, rel=1e-10)
        assert L > rod.stabilisation_length  # A > G suffices below L_stab
    assert gh.critical_length(rod, "pinned", field_on=False) == 0.0


def test_bad_input():
    with pytest.raises(ParameterError, match="G"):
        gh.greenhill(-1.0)
    with pytest.raises(ParameterError, match="support"):
        gh.greenhill(1.0, "hinged")
    with pytest.raises(ParameterError, match="A"):
        gh.greenhill(1.0, A=float("nan"))
    with pytest.raises(ParameterError, match="N"):
        gh.greenhill(1.0, n=3)
