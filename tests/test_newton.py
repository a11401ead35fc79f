import jax
import jax.numpy as jnp

from jaxrod.solvers.newton import CONVERGED, MAX_STEPS, NONFINITE, newton


def _circle(x, r):
    return jnp.array([x[0] ** 2 + x[1] ** 2 - r**2, x[0] - x[1]])


def test_converges_quadratically_and_reports():
    res = newton(_circle, jnp.array([3.0, 1.0]), 2.0)
    assert bool(res.converged) and int(res.status) == CONVERGED
    assert jnp.allclose(res.x, jnp.sqrt(2.0), atol=1e-14)
    assert float(res.residual_norm) < 1e-12
    assert int(res.iterations) < 10


def test_jit_and_vmap_over_parameters():
    solve = jax.jit(jax.vmap(lambda r: newton(_circle, jnp.array([3.0, 1.0]), r)))
    res = solve(jnp.array([1.0, 2.0, 5.0]))
    assert res.converged.all()
    assert jnp.allclose(res.x[:, 0], jnp.array([1.0, 2.0, 5.0]) / jnp.sqrt(2.0))


def test_failure_is_reported_not_silent():
    # x^2 + 1 = 0 has no real root
    res = newton(lambda x, _: x**2 + 1.0, jnp.array([0.5]), None, max_steps=30)
    assert not bool(res.converged)
    assert int(res.status) != CONVERGED
    assert float(res.residual_norm) > 0.5
    assert res.message() != "converged"


def test_nonfinite_and_budget():
    res = newton(lambda x, _: jnp.log(x), jnp.array([-1.0]), None)
    assert int(res.status) == NONFINITE and not bool(res.converged)
    res = newton(lambda x, _: jnp.arctan(x), jnp.array([1.5]), None, max_steps=1)
    assert int(res.status) == MAX_STEPS and int(res.iterations) == 1


def test_kept_jacobian_is_the_jacobian_at_the_returned_point():
    """keep_jacobian returns dF/dx at the final x (what the continuations and fold reports
    use instead of assembling it again), checked against forward-mode autodiff there."""
    linearise = lambda x, r: (_circle(x, r), jax.jacfwd(_circle)(x, r))
    for x0 in (jnp.array([3.0, 1.0]), jnp.array([2.0 + 1e-12, 2.0])):  # many steps / one
        res = newton(None, x0, 2.0, linearise=linearise, keep_jacobian=True)
        assert bool(res.converged)
        assert jnp.allclose(res.jacobian, jax.jacfwd(_circle)(res.x, 2.0), atol=1e-15)
    assert newton(_circle, jnp.array([3.0, 1.0]), 2.0).jacobian is None


def _no_root_at_negative_lam(x, lam, args):
    """E = sum(exp(x) - lam x): grad E = exp(x) - lam has no root for lam <= 0."""
    return jnp.sum(jnp.exp(x) - lam * x)


def test_a_continuation_from_a_start_that_is_no_equilibrium_says_so():
    """The driver's first pass corrects the start at its lam: where there is nothing to
    converge to, the run stops with NOT_CONVERGED (one point recorded, its residual
    large), never a branch that looks traced; from a true start it runs."""
    from jaxrod.solvers.continuation import ContinuationOptions, pseudo_arclength
    from jaxrod.status import Status

    opts = ContinuationOptions(lam_min=-2.0, lam_max=2.0, max_points=50)
    bad = pseudo_arclength(_no_root_at_negative_lam, jnp.zeros(2), -1.0, None, opts)
    assert Status(int(bad.status)) == Status.NOT_CONVERGED
    assert int(bad.num_points) == 1 and not float(bad.residual_norm[0]) <= opts.tol
    good = pseudo_arclength(_no_root_at_negative_lam, jnp.zeros(2), 1.0, None, opts)
    assert Status(int(good.status)) == Status.REACHED_BOUND
    assert float(good.residual_norm[0]) <= opts.tol
