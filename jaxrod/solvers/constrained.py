"""Equilibria under equality constraints: stationary points of E(x) with g(x) = 0.

The unknowns z = (x, mu) solve the Karush-Kuhn-Tucker system of the Lagrangian
L(x, mu) = E(x) + mu . g(x),

    grad_x E(x) + G(x)^T mu = 0,    g(x) = 0,    G = dg/dx,

by ``jaxrod.solvers.newton`` with the exact Jacobian (the Hessian of L in (x, mu): the
bordered matrix [H_L, G^T; G, 0], symmetric indefinite). The multipliers are the constraints'
reactions (on a rod whose far end is held: the end force).

Stability is the second variation restricted to the constraints' tangent space: the
eigenvalues of Z^T H_L Z, Z an orthonormal basis of ker G (from the complete QR of G^T).
Their inertia, not their values, is the metric-free answer (the count of negative ones).
"""

from __future__ import annotations

from collections.abc import Callable

import jax
import jax.numpy as jnp

from jaxrod.solvers.newton import NewtonResult, newton


def constrained_equilibrium(energy: Callable, constraints: Callable, x0, mu0, args=None, *,
                            tol: float = 1e-12, max_steps: int = 50) -> NewtonResult:
    """The KKT point (x, mu) from (x0, mu0) (module docstring); ``energy(x, args)`` a scalar,
    ``constraints(x, args)`` the vector g. The result's ``x`` is z = (x, mu)."""
    x0, mu0 = jnp.asarray(x0), jnp.asarray(mu0)
    n = x0.shape[0]

    def L(z, a):
        return energy(z[:n], a) + jnp.dot(z[n:], constraints(z[:n], a))

    return newton(jax.grad(L), jnp.concatenate([x0, mu0]), args, tol=tol,
                  max_steps=max_steps, jacobian=jax.hessian(L))


def constrained_eigenvalues(energy: Callable, constraints: Callable, x, mu,
                            args=None) -> jax.Array:
    """The eigenvalues (ascending) of the second variation of L on ker G at (x, mu): those of
    Z^T H_L Z with Z an orthonormal basis of ker G."""
    H = jax.hessian(lambda y: energy(y, args) + jnp.dot(mu, constraints(y, args)))(x)
    G = jax.jacfwd(lambda y: constraints(y, args))(x)
    Q, _ = jnp.linalg.qr(G.T, mode="complete")
    Z = Q[:, G.shape[0]:]
    return jnp.linalg.eigvalsh(Z.T @ H @ Z)
