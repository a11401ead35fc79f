import numpy as np
import pytest

from jaxrod.uniform.greenhill import greenhill
from jaxrod.uniform.pitchfork import buckled_branch


@pytest.mark.parametrize("support, G, kind", [
    ("clamped", 8.5, "supercritical"),
    ("clamped", 60.0, "subcritical"),
    ("pinned", 2.0, "subcritical"),
])
def test_nonlinear_branch_reproduces_the_a2_formula(support, G, kind):
    branch = buckled_branch(G, support, n=40)
    assert branch.converged.all()
    assert np.max(branch.residual_norm) < 1e-12
    formula = greenhill(G, support, n=40)
    assert formula.criticality == kind
    assert branch.A_crit == pytest.approx(formula.A_crit, rel=1e-13)
    assert abs(branch.fit_A2(terms=5) - formula.A2) <= 1e-4 * abs(formula.A2)
    # the branch really is nonlinear and on the predicted side of A_crit
    assert np.all(np.sign(branch.A - branch.A_crit) == np.sign(formula.A2))
    assert np.max(np.abs(branch.states)) > 0.2
