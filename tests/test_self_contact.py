"""Self-contact of a twisted rod (``jaxrod.twisted.self_contact``): the penalty's assembled
derivatives against autodiff, its double integral against an independent quadrature, and
its inputs' messages."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxrod import spectral
from jaxrod.discretise.director import director
from jaxrod.params import ParameterError
from jaxrod.twisted.rod import TwistedRod
from jaxrod.twisted.self_contact import (
    EXCLUSION,
    contact_energy,
    contact_terms,
    self_contact,
    self_distance,
)


def _coiled_state(n: int) -> np.ndarray:
    """x (v1, v2, psi on the free nodes) of a rod coiled in 3.5 turns of a helix of cone
    angle 1.486 sin(pi s) (v = 0 at both ends): at the middle its radius is 0.045 and its
    pitch 0.024, so turns one apart come within 0.0375 (under the diameter 0.042 of the
    tests), while a bend never brings one strand's points 3h apart along it within h."""
    s = spectral.chebyshev_nodes(n)[1:n]
    cone = 1.486 * np.sin(np.pi * s)
    return np.concatenate([cone * np.cos(7 * np.pi * s), cone * np.sin(7 * np.pi * s),
                           np.zeros(n - 1)])


def test_the_assembled_contact_derivatives_are_autodiffs():
    """``contact_terms`` (the pairs' blocks chained through the centreline) against
    jax.grad and jax.hessian of ``contact_energy``, n = 24 on a layered grid (layer width
    0.2), a state in contact: to 1e-12 of the largest entry (round-off)."""
    n = 24
    contact = self_contact(n, 0.2, 0.042, 1.0e4)
    x = jnp.asarray(_coiled_state(n))
    assert float(self_distance(x, contact)) < 0.042 and float(contact_energy(x, contact)) > 0
    g, H = contact_terms(x, contact, x.shape[0])
    g_ad, H_ad = jax.grad(contact_energy)(x, contact), jax.hessian(contact_energy)(x, contact)
    assert np.abs(g - g_ad).max() <= 1e-12 * np.abs(g_ad).max()
    assert np.abs(H - H_ad).max() <= 1e-12 * np.abs(H_ad).max()


def test_the_contact_energy_is_its_double_integral():
    """E_c = (kappa / 2) int int_{|s - s'| > 3h} (1 - |r(s) - r(s')| / h)_+^3 of a coiled
    rod (n = 32, h = 0.042) against the trapezoid rule on 3201 equal steps of the
    centreline integrated there (numpy, the bending angles interpolated from the nodes; its
    error O(step^2), about 1e-4 here: 1601 steps differ by 6e-5). The contact grid of
    degree 8n agrees to 1e-3; at 4n the penalty's kink at |r - r'| = h costs about 2%,
    at 2n half the energy: the default (``CONTACT_DEGREE_FACTOR``) is checked on the
    contact branch by doubling it (tests/test_twisted.py)."""
    n, h, kappa = 32, 0.042, 1.0e3
    x = _coiled_state(n)
    s = np.linspace(0.0, 1.0, 3201)
    full = np.zeros((n + 1, 2))
    full[1:n] = x[:2 * (n - 1)].reshape(2, n - 1).T
    v = spectral.interpolation_matrix(n, s) @ full
    d3 = np.asarray(director(jnp.asarray(v[:, 0]), jnp.asarray(v[:, 1])))
    step = s[1] - s[0]
    r = np.vstack([np.zeros(3), np.cumsum(0.5 * step * (d3[1:] + d3[:-1]), axis=0)])
    w = np.full(s.size, step)
    w[[0, -1]] *= 0.5
    d = np.linalg.norm(r[:, None] - r[None, :], axis=-1)
    apart = np.abs(s[:, None] - s[None, :]) > EXCLUSION * h
    reference = 0.5 * kappa * np.sum(np.outer(w, w) * apart * np.clip(1 - d / h, 0, None) ** 3)
    errors = [abs(float(contact_energy(jnp.asarray(x), self_contact(n, None, h, kappa, k * n)))
                  / reference - 1) for k in (4, 8)]
    assert reference > 0 and errors[1] <= 1e-3 < errors[0]


@pytest.mark.parametrize("options, name", [
    (dict(contact_diameter=0.0), "contact_diameter"),
    (dict(contact_diameter=0.2), "contact_diameter"),
    (dict(contact_diameter=float("nan")), "contact_diameter"),
    (dict(contact_diameter=0.01, contact_stiffness=-1.0), "contact_stiffness"),
    (dict(contact_diameter=0.01, contact_grid=0), "contact_grid"),
])
def test_bad_contact_inputs_name_the_parameter(options, name):
    with pytest.raises(ParameterError, match=name):
        TwistedRod(shortening=0.03, **options)
    with pytest.raises(ParameterError, match="both ends held"):
        TwistedRod(support="clamped", contact_diameter=0.01)
