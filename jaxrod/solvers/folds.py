"""Moore-Spence augmented system for a fold (saddle-node) of E(x, lam).

At a simple fold of the equilibria F(x, lam) = grad_x E = 0 the Hessian H = F_x has a one-
dimensional kernel span{phi}. The fold is a regular solution of the extended system
(Moore & Spence, SIAM J. Numer. Anal. 17 (1980) 567)

    F(x, lam) = 0,      H(x, lam) phi = 0,      l . phi - 1 = 0,

in 2m + 1 unknowns (x, phi, lam), l a fixed vector with l . phi != 0 (the null-vector
estimate from the branch). It is solved by ``jaxrod.solvers.newton`` with the exact Jacobian
from autodiff (third derivatives of E appear through H phi).

At the fold, with phi normalised to int phi = 1 (the paper's reduced coordinate q = int x),
the Lyapunov-Schmidt reduced function F(q, lam) of the paper has

    dF/dlam = phi . F_lam,      d2F/dq2 = D^3E[phi, phi, phi],

(the kernel direction is theta_q at the fold, which makes both independent of the chosen
complement), so the branch is lam(q) = lam* + c (q - q*)^2 + ..., c = -d2F/dq2 / (2 dF/dlam)
(Proposition "Planar saddle-node bifurcation").
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp

from jaxrod.solvers.newton import NewtonResult, implicit_newton, newton

Energy = Callable[[jax.Array, jax.Array, Any], jax.Array]


class FoldPoint(NamedTuple):
    """A converged fold: state, parameter, null vector (int-normalised), diagnostics."""

    x: jax.Array
    lam: jax.Array
    null_vector: jax.Array
    newton: NewtonResult


def _hvp(energy, x, lam, args, v):
    g = lambda z: jax.grad(energy)(z, lam, args)
    return jax.jvp(g, (x,), (v,))[1]


def moore_spence_residual(z, data):
    """[grad E(x, lam); H(x, lam) phi; l . phi - 1] for z = (x, phi, lam), data =
    (energy, l, args)."""
    energy, ell, args = data
    m = ell.shape[0]
    x, phi, lam = z[:m], z[m:2 * m], z[-1]
    F = jax.grad(energy)(x, lam, args)
    return jnp.concatenate([F, _hvp(energy, x, lam, args, phi), jnp.atleast_1d(ell @ phi - 1.0)])


def _solve_fold(energy, x0, lam0, phi0, args, tol):
    ell = phi0 / jnp.dot(phi0, phi0)
    z0 = jnp.concatenate([x0, phi0, jnp.atleast_1d(lam0)])
    res = newton(moore_spence_residual, z0, (energy, ell, args), tol=tol)
    m = x0.shape[0]
    return FoldPoint(res.x[:m], res.x[-1], res.x[m:2 * m], res)


def moore_spence_solve(energy: Energy, x0, lam0, phi0, args, tol: float = 1e-13) -> FoldPoint:
    """Solve the Moore-Spence system from (x0, lam0) and null-vector guess phi0 (traceable).

    The returned ``null_vector`` is normalised by l . phi = 1 with l = phi0 / |phi0|^2.
    """
    return _solve_fold(energy, x0, lam0, phi0, args, tol)



def differentiable_fold(energy: Energy, x0, lam0, phi0, args, tol: float = 1e-13):
    """(z, stats): the fold z = (x, phi, lam), differentiable in ``args``, and the Newton
    statistics (converged as 0/1, residual norm, iterations) as a float array.

    Implicit differentiation (``jaxrod.solvers.newton.implicit_newton``): the primal is the
    Newton solve of the Moore-Spence system R(z; args) = 0 from (x0, phi0, lam0), and the
    tangent is one dense solve with dR/dz at the solution, dz = -(dR/dz)^-1 (dR/dargs) dargs.
    """
    ell = jax.lax.stop_gradient(phi0 / jnp.dot(phi0, phi0))
    z0 = jnp.concatenate([x0, phi0, jnp.atleast_1d(lam0)])
    return implicit_newton(lambda z: moore_spence_residual(z, (energy, ell, args)), z0, tol)


def fold_coefficients(energy: Energy, x, lam, phi, args, mean: Callable[[jax.Array], Any]):
    """(dF/dlam, d2F/dq2, phi normalised by mean(phi) = 1) at a converged fold."""
    phi = phi / mean(phi)
    d_lam = jax.grad(lambda l: jnp.dot(jax.grad(energy)(x, l, args), phi))(lam)
    line = lambda e: energy(x + e * phi, lam, args)
    d3 = jax.grad(jax.grad(jax.grad(line)))(0.0)
    return d_lam, d3, phi
