"""Ingredients of the paper's Lyapunov-Schmidt reduction (permanent-magnet scene).

Paper, Lemmas "Mode decomposition" and "Properties of the normalized mode": with
delta = D - 1, a0(s) = 2M/delta^3 - G (1 - s) and V = {v in H^1: v(0) = 0},

    B0(u, v) = int [u' v' + a0 u v] + (3M/delta^4) (int u)(int v),

the normalised mode psi = argmin {B0(phi, phi): phi in V, int phi = 1} solves the linear BVP

    -psi'' + a0 psi = lambda_psi,   psi(0) = 0,  psi'(1) = 0,  int psi = 1,
    lambda_psi = int (psi'^2 + a0 psi^2),

and mu_perp = inf {int v'^2 / int v^2 : v in V, int v = 0} is the Poincare constant of the
mean-zero space Y (paper: 20.1907; exactly k^2 with k the first positive root of tan k = k).

Both are computed on the planar Chebyshev discretisation: psi from the KKT system of the
constrained quadratic minimisation, mu_perp from the generalised eigenproblem restricted to
the null space of the mean functional. The rest of the reduction (w(q, alpha), F and its
derivatives, the contraction constants) is not implemented yet.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from jaxrod.discretise.planar import PlanarDiscretisation
from jaxrod.scenes.terms import bending_energy


def _mean_functional(disc: PlanarDiscretisation) -> jax.Array:
    """Row vector m with m . v = int_0^1 v ds for free nodal values v."""
    return disc.quad_weights @ disc.to_quad


def _stiffness(disc: PlanarDiscretisation) -> jax.Array:
    """Matrix of int v'^2 (the Hessian of the bending energy)."""
    return jax.hessian(bending_energy)(jnp.zeros(disc.size), disc)


def poincare_mean_zero(disc: PlanarDiscretisation) -> jax.Array:
    """mu_perp: smallest int v'^2 / int v^2 over v(0) = 0, int v = 0 (clamped discretisation)."""
    m = _mean_functional(disc)
    # orthonormal basis of {v : m . v = 0} from the QR factorisation of m^T
    Q, _ = jnp.linalg.qr(m[:, None], mode="complete")
    Z = Q[:, 1:]
    K = Z.T @ _stiffness(disc) @ Z
    M = Z.T @ disc.mass_matrix() @ Z
    L = jnp.linalg.cholesky(M)
    solve_l = lambda b: jax.scipy.linalg.solve_triangular(L, b, lower=True)
    C = solve_l(solve_l(K).T).T
    return jnp.linalg.eigvalsh(0.5 * (C + C.T))[0]


def normalised_mode(G, M, D, disc: PlanarDiscretisation):
    """(psi, lambda_psi, ||psi||^2): the minimiser of B0 with int psi = 1.

    Solves the KKT system [B0 m^T; m 0] [psi; -mult] = [0; 1] with B0 the matrix of the
    bilinear form (stiffness + a0-weighted mass + (3M/delta^4) m^T m).
    """
    delta = D - 1.0
    m = _mean_functional(disc)
    a0 = 2.0 * M / delta**3 - G * (1.0 - disc.quad_nodes)
    P = disc.to_quad
    B = _stiffness(disc) + P.T @ ((disc.quad_weights * a0)[:, None] * P) \
        + (3.0 * M / delta**4) * jnp.outer(m, m)
    n = m.shape[0]
    kkt = jnp.block([[B, m[:, None]], [m[None, :], jnp.zeros((1, 1))]])
    sol = jnp.linalg.solve(kkt, jnp.zeros(n + 1).at[-1].set(1.0))
    psi = sol[:n]
    pq, dpq = disc.at_quadrature(psi)
    lam = disc.integrate(dpq**2 + a0 * pq**2)
    return psi, lam, disc.integrate(pq**2)


def _alpha_gradient(theta, alpha, scene, disc):
    from jaxrod.analysis.magnet import alpha_energy

    return jax.grad(alpha_energy)(theta, alpha, (scene, disc))


def one_mode_function(q, alpha, psi, scene, disc: PlanarDiscretisation):
    """F0(q, alpha) = dE[q psi](psi): the reduced function with the correction w dropped."""
    return jnp.dot(_alpha_gradient(q * psi, alpha, scene, disc), psi)


def one_mode_fold(psi, scene, disc: PlanarDiscretisation, q_guess, alpha_guess):
    """(q0, alpha0) solving F0 = dF0/dq = 0 by Newton from a guess (the paper's initial
    approximation of a fold)."""
    from jaxrod.solvers.newton import newton

    def residual(x, _):
        f = lambda q: one_mode_function(q, x[1], psi, scene, disc)
        return jnp.stack([f(x[0]), jax.grad(f)(x[0])])

    return newton(residual, jnp.array([q_guess, alpha_guess]), None, tol=1e-14)
