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
