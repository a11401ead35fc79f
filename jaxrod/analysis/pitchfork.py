"""The nonlinear post-buckled planar branch of the uniform-field scene, and a fit of A2.

This is the independent check of the pitchfork coefficient formula in
``jaxrod.analysis.greenhill``: instead of the Lyapunov-Schmidt formula, solve the full
nonlinear discrete equilibrium equations along the buckled branch and fit A(r).

The branch is parametrised by its amplitude along the critical mode (the paper's r, with
theta = r u + w and int u w = 0): for each r the unknowns z = (theta, A) solve

    grad_theta E_unif(theta; G, A) = 0,      int_0^1 theta u ds - r = 0,

by Newton (the bordered Jacobian is regular at the pitchfork, where dE/dtheta alone is
singular). The amplitudes are stepped with ``lax.scan``, each Newton solve started from a
secant predictor through the previous two solutions. A least-squares fit of
A(r) - A_crit = a2 r^2 + a4 r^4 + a6 r^6 + a8 r^8 gives A2 = a2.
"""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np

from jaxrod.analysis.greenhill import principal_eigenpair
from jaxrod.discretise.planar import PlanarDiscretisation, planar_discretisation
from jaxrod.scenes.uniform import UniformField
from jaxrod.solvers.newton import newton


@dataclasses.dataclass(frozen=True)
class PitchforkBranch:
    """Buckled planar branch: amplitude r, anisotropy A, states theta, solve diagnostics."""

    G: float
    support: str
    A_crit: float
    r: np.ndarray
    A: np.ndarray
    theta: np.ndarray
    converged: np.ndarray
    residual_norm: np.ndarray
    iterations: np.ndarray

    def fit_A2(self, terms: int = 4) -> float:
        """A2 from a least-squares fit of A(r) - A_crit in powers r^2, ..., r^(2 terms)."""
        if not np.all(self.converged):
            raise RuntimeError("cannot fit A2: some branch points did not converge")
        basis = np.stack([self.r ** (2 * j) for j in range(1, terms + 1)], axis=1)
        coef, *_ = np.linalg.lstsq(basis, self.A - self.A_crit, rcond=None)
        return float(coef[0])


def _bordered_residual(z, args):
    G, r, u, disc = args
    theta, A = z[:-1], z[-1]
    grad = jax.grad(lambda th: UniformField(G, A).energy(th, disc))(theta)
    return jnp.append(grad, disc.inner(theta, u) - r)


@jax.jit
def _trace(G, amplitudes, disc: PlanarDiscretisation):
    beta0, u = principal_eigenpair(G, disc)
    a_crit = -beta0

    def step(carry, r):
        z_prev, z_prev2, r_prev, r_prev2 = carry
        # secant predictor in r (the first step starts from the eigenmode at A_crit)
        slope = (z_prev - z_prev2) / jnp.where(r_prev == r_prev2, 1.0, r_prev - r_prev2)
        guess = jnp.where(r_prev == r_prev2, jnp.append(r * u, a_crit),
                          z_prev + (r - r_prev) * slope)
        res = newton(_bordered_residual, guess, (G, r, u, disc), tol=1e-13)
        return (res.x, z_prev, r, r_prev), res

    z0 = jnp.append(jnp.zeros_like(u), a_crit)
    _, results = jax.lax.scan(step, (z0, z0, 0.0, 0.0), amplitudes)
    return a_crit, u, results


def buckled_branch(G: float, support: str = "clamped", n: int = 48, points: int = 12,
                   max_angle: float = 0.25) -> PitchforkBranch:
    """Trace the buckled planar branch from the pitchfork up to a tip angle ~ max_angle (rad).

    The amplitudes r are spaced evenly up to r_max = max_angle / max|u|, so that
    |theta| <= max_angle roughly whatever the shape of the critical mode.
    """
    disc = planar_discretisation(n, support)
    _, u = principal_eigenpair(G, disc)
    r_max = max_angle / float(jnp.max(jnp.abs(disc.full_values(u))))
    amplitudes = jnp.linspace(r_max / points, r_max, points)
    a_crit, _, res = _trace(G, amplitudes, disc)
    z = np.asarray(res.x)
    return PitchforkBranch(
        G=float(G), support=support, A_crit=float(a_crit), r=np.asarray(amplitudes),
        A=z[:, -1], theta=z[:, :-1], converged=np.asarray(res.converged),
        residual_norm=np.asarray(res.residual_norm), iterations=np.asarray(res.iterations))
