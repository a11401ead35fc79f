"""The nonlinear post-buckled branch of the uniform-field scene, and a fit of A2; planar or 3D.

This is the independent check of the pitchfork coefficient formula in
``jaxrod.uniform.greenhill``: instead of the Lyapunov-Schmidt formula, solve the full
nonlinear discrete equilibrium equations along the buckled branch and fit A(r).

Planar. The branch is parametrised by its amplitude along the critical mode (the paper's r,
with theta = r u + w and int u w = 0): for each r the unknowns z = (theta, A) solve

    grad_theta E_unif(theta; G, A) = 0,      int_0^1 theta u ds - r = 0,

by Newton (the bordered Jacobian is regular at the pitchfork, where dE/dtheta alone is
singular).

3D (director discretisation, ``jaxrod.discretise.director``). The kernel at the pitchfork is
two-dimensional, u(s) p for any horizontal unit vector p = (cos phi, sin phi): branch
switching picks the direction phi. The 3D energy is invariant under rotations about e3, so
every buckled state lies on a circle of equilibria and grad E = 0 alone has a singular
Jacobian along the branch. The rotation is fixed by a phase condition with a Lagrange
multiplier mu (zero at a solution, by the symmetry): with k = u p and k_perp = u p_perp in
the chart unknowns v = (v1, v2), the unknowns z = (v, A, mu) solve

    grad_v E_unif3(v; G, A) + mu grad_v <v, k_perp> = 0,   <v, k> - r = 0,   <v, k_perp> = 0.

In both cases the amplitudes are stepped with ``lax.scan``, each Newton solve (the package's
``newton``) started from a secant predictor through the previous two solutions. A
least-squares fit of A(r) - A_crit = a2 r^2 + a4 r^4 + a6 r^6 + a8 r^8 gives A2 = a2.
"""

from __future__ import annotations

import dataclasses
import math

import jax
import jax.numpy as jnp
import numpy as np

from jaxrod.discretise.director import DirectorDiscretisation, director_discretisation
from jaxrod.discretise.planar import PlanarDiscretisation, planar_discretisation
from jaxrod.programs import jit
from jaxrod.scenes.three_d import UniformField3D
from jaxrod.scenes.uniform import UniformField
from jaxrod.solvers.newton import newton
from jaxrod.uniform.greenhill import principal_eigenpair


@dataclasses.dataclass(frozen=True)
class PitchforkBranch:
    """Buckled branch: amplitude r, anisotropy A, solve diagnostics, and the states: planar
    theta (``direction_deg`` None) or the 3D chart unknowns [v1; v2] along the horizontal
    direction ``direction_deg`` (``multiplier``: the phase multiplier mu, zero in theory)."""

    G: float
    support: str
    A_crit: float
    r: np.ndarray
    A: np.ndarray
    states: np.ndarray
    converged: np.ndarray
    residual_norm: np.ndarray
    iterations: np.ndarray
    direction_deg: float | None = None
    multiplier: np.ndarray | None = None

    def fit_A2(self, terms: int = 4) -> float:
        """A2 from a least-squares fit of A(r) - A_crit in powers r^2, ..., r^(2 terms)."""
        if not np.all(self.converged):
            raise RuntimeError("cannot fit A2: some branch points did not converge")
        basis = np.stack([self.r ** (2 * j) for j in range(1, terms + 1)], axis=1)
        coef, *_ = np.linalg.lstsq(basis, self.A - self.A_crit, rcond=None)
        return float(coef[0])


def _bordered_residual(z, args):
    G, r, k, k_perp, disc = args
    if k_perp is None:  # planar
        theta, A = z[:-1], z[-1]
        grad = jax.grad(lambda th: UniformField(G, A).energy(th, disc))(theta)
        return jnp.append(grad, disc.inner(theta, k) - r)
    v, A, mu = z[:-2], z[-2], z[-1]
    lagrangian = lambda y: UniformField3D(G, A).energy(y, disc) + mu * disc.inner(y, k_perp)
    return jnp.concatenate([jax.grad(lagrangian)(v),
                            jnp.stack([disc.inner(v, k) - r, disc.inner(v, k_perp)])])


def _critical_modes(G, disc, phi):
    """(A_crit, k, k_perp): the critical mode along the chosen direction and its partner."""
    if isinstance(disc, DirectorDiscretisation):
        beta0, u = principal_eigenpair(G, disc.planar)
        c, s = jnp.cos(phi), jnp.sin(phi)
        return -beta0, jnp.concatenate([c * u, s * u]), jnp.concatenate([-s * u, c * u])
    beta0, u = principal_eigenpair(G, disc)
    return -beta0, u, None


@jit
def _trace(G, amplitudes, disc: PlanarDiscretisation | DirectorDiscretisation, phi):
    a_crit, k, k_perp = _critical_modes(G, disc, phi)
    tail = jnp.array([a_crit]) if k_perp is None else jnp.array([a_crit, 0.0])

    def step(carry, r):
        z_prev, z_prev2, r_prev, r_prev2 = carry
        # secant predictor in r (the first step starts from the critical mode at A_crit)
        slope = (z_prev - z_prev2) / jnp.where(r_prev == r_prev2, 1.0, r_prev - r_prev2)
        guess = jnp.where(r_prev == r_prev2, jnp.concatenate([r * k, tail]),
                          z_prev + (r - r_prev) * slope)
        res = newton(_bordered_residual, guess, (G, r, k, k_perp, disc), tol=1e-13)
        return (res.x, z_prev, r, r_prev), res

    z0 = jnp.concatenate([jnp.zeros_like(k), tail])
    _, results = jax.lax.scan(step, (z0, z0, 0.0, 0.0), amplitudes)
    return a_crit, results


def buckled_branch(G: float, support: str = "clamped", n: int = 48, points: int = 12,
                   max_angle: float = 0.25, direction_deg: float | None = None) -> PitchforkBranch:
    """Trace the buckled branch from the pitchfork up to a tip angle ~ max_angle (rad).

    ``direction_deg`` None: the planar branch. A number phi: the 3D branch switched onto at
    the pitchfork along the horizontal direction (cos phi, sin phi, 0), computed on the
    director discretisation. The amplitudes r are spaced evenly up to
    r_max = max_angle / max|u|, so that the tilt stays below max_angle roughly whatever the
    shape of the critical mode.

    Paper: the bifurcating branch of eq. ``uniform_bifurcation_branch``, A = A_crit + A2 r^2
    + O(r^3) (Proposition ``thm:uniform_bifurcation_criticality``).
    """
    planar = planar_discretisation(n, support)
    _, u = principal_eigenpair(G, planar)
    r_max = max_angle / float(jnp.max(jnp.abs(planar.full_values(u))))
    amplitudes = jnp.linspace(r_max / points, r_max, points)
    if direction_deg is None:
        disc, phi = planar, 0.0
    else:
        disc, phi = director_discretisation(n, support), math.radians(direction_deg)
    a_crit, res = _trace(G, amplitudes, disc, phi)
    z = np.asarray(res.x)
    three_d = direction_deg is not None
    return PitchforkBranch(
        G=float(G), support=support, A_crit=float(a_crit), r=np.asarray(amplitudes),
        A=z[:, -2] if three_d else z[:, -1], states=z[:, :-2] if three_d else z[:, :-1],
        converged=np.asarray(res.converged), residual_norm=np.asarray(res.residual_norm),
        iterations=np.asarray(res.iterations), direction_deg=direction_deg,
        multiplier=z[:, -1] if three_d else None)
