import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from jaxrod import spectral


@pytest.mark.parametrize("n", [2, 3, 4, 7, 16, 33])
def test_operators_exact_for_polynomials_of_the_degree(n):
    s = spectral.chebyshev_nodes(n)
    D = spectral.differentiation_matrix(n)
    w = spectral.clenshaw_curtis_weights(n)
    S = spectral.cumulative_integration_matrix(n)
    x = np.linspace(0.0, 1.0, 13)
    P = spectral.interpolation_matrix(n, x)
    # monomials in (s - 1/2) keep the values O(1)
    for k in range(n + 1):
        f = (s - 0.5) ** k
        exact_d = k * (s - 0.5) ** (k - 1) if k else np.zeros_like(s)
        exact_int = (0.5 ** (k + 1) - (-0.5) ** (k + 1)) / (k + 1)
        exact_cum = ((s - 0.5) ** (k + 1) - (-0.5) ** (k + 1)) / (k + 1)
        assert np.max(np.abs(D @ f - exact_d)) < 1e-11 * n**2
        assert abs(w @ f - exact_int) < 1e-14
        assert np.max(np.abs(S @ f - exact_cum)) < 1e-14
        assert np.max(np.abs(P @ f - (x - 0.5) ** k)) < 1e-13


def test_small_grids_and_symmetry():
    assert np.array_equal(spectral.chebyshev_nodes(2), [0.0, 0.5, 1.0])
    np.testing.assert_allclose(spectral.clenshaw_curtis_weights(2), [1 / 6, 2 / 3, 1 / 6],
                               atol=1e-16)
    s = spectral.chebyshev_nodes(129)
    assert np.max(np.abs(s + s[::-1] - 1.0)) <= 2.3e-16
    w = spectral.clenshaw_curtis_weights(129)
    assert np.all(w > 0) and np.array_equal(w, w[::-1])
    with pytest.raises(ValueError, match="n"):
        spectral.chebyshev_nodes(1)
    with pytest.raises(ValueError, match="points"):
        spectral.interpolation_matrix(8, [1.5])


def test_interpolation_hits_nodes_exactly():
    s = spectral.chebyshev_nodes(10)
    P = spectral.interpolation_matrix(10, s)
    assert np.array_equal(P, np.eye(11))


def test_spectral_accuracy_for_smooth_functions():
    f = lambda s: np.exp(np.sin(3.0 * s))
    df = lambda s: 3.0 * np.cos(3.0 * s) * f(s)
    from scipy.integrate import quad

    exact = quad(f, 0.0, 1.0, epsabs=0, epsrel=1e-13)[0]
    errors = []
    for n in (4, 8, 16, 32):
        s = spectral.chebyshev_nodes(n)
        errors.append((abs(spectral.clenshaw_curtis_weights(n) @ f(s) - exact),
                       np.max(np.abs(spectral.differentiation_matrix(n) @ f(s) - df(s)))))
    errors = np.array(errors)
    # exponential convergence: each doubling gains many digits, round-off reached at n = 32
    assert errors[-1, 0] < 1e-14 and errors[-1, 1] < 1e-11
    assert np.all(errors[1:-1, 0] < 1e-2 * errors[:-2, 0])


@settings(max_examples=30, deadline=None)
@given(st.integers(min_value=2, max_value=40), st.data())
def test_quadrature_and_cumint_exact_on_random_polynomials(n, data):
    coef = np.array(data.draw(st.lists(st.floats(-1, 1), min_size=n + 1, max_size=n + 1)))
    poly = np.polynomial.Chebyshev(coef, domain=[0, 1])
    s = spectral.chebyshev_nodes(n)
    anti = poly.integ(lbnd=0.0)
    assert abs(spectral.clenshaw_curtis_weights(n) @ poly(s) - anti(1.0)) < 1e-13
    assert np.max(np.abs(spectral.cumulative_integration_matrix(n) @ poly(s) - anti(s))) < 1e-13
