"""Conditioning of the fold computations as a fold is approached (paper, discussion after
Theorem "Physical consequences of Permanent Magnet Regime": the full Newton solve is ill-
conditioned near a saddle-node, the reduced one is not).

Branch points at a prescribed distance from a fold come from the reduced route itself: at
q = q* + dq, alpha solves F(q, alpha) = 0 (a scalar Newton; dF/dalpha != 0 at a fold) and
theta = q psi + w(q, alpha). At each point the 2-norm condition numbers of

    full        the Hessian H (the Jacobian of Newton on grad E = 0 at fixed alpha),
    bordered    [H, dgrad/dalpha; t^T] (pseudo-arclength corrector, t the unit tangent),
    moore_spence  the Jacobian of (grad E, H phi, l.phi - 1) in (theta, phi, alpha) at the
                point, phi the lowest eigenvector of H,
    w_problem   Z^T H Z (the mean-zero correction's Newton matrix, coercive on Y),
    reduced     the 2 x 2 Jacobian of (F, dF/dq) in (q, alpha),

are reported against |alpha - alpha*|.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

from jaxrod.discretise.planar import planar_discretisation
from jaxrod.magnet.reduction import ReducedFold, reduced_function, reduced_state, reduction
from jaxrod.programs import jit
from jaxrod.scenes.dipole import DipoleMagnet
from jaxrod.solvers.folds import moore_spence_linearisation
from jaxrod.solvers.newton import newton


def _energy(theta, alpha, args):
    scene, disc = args
    return scene.with_alpha(alpha).energy(theta, disc)


def _condition_numbers(q, alpha, red, scene, disc):
    args = (scene, disc)
    theta, _ = reduced_state(q, alpha, red, scene, disc)
    H = jax.hessian(_energy)(theta, alpha, args)
    g_alpha = jax.jacfwd(jax.grad(_energy), 1)(theta, alpha, args)
    J = jnp.concatenate([H, g_alpha[:, None]], axis=1)
    t = jnp.linalg.svd(J)[2][-1]  # null vector of [H, g_alpha]: the branch tangent
    bordered = jnp.concatenate([J, t[None, :]], axis=0)
    phi = jnp.linalg.eigh(H)[1][:, 0]
    ell = phi / jnp.dot(phi, phi)
    z = jnp.concatenate([theta, phi, jnp.atleast_1d(alpha)])
    ms = moore_spence_linearisation(z, (_energy, ell, args))[1]
    fold_system = lambda x: jnp.stack([
        reduced_function(x[0], x[1], red, scene, disc),
        jax.grad(reduced_function)(x[0], x[1], red, scene, disc)])
    reduced = jax.jacfwd(fold_system)(jnp.stack([q, alpha]))
    cond = jnp.linalg.cond
    return {"full": cond(H), "bordered": cond(bordered), "moore_spence": cond(ms),
            "w_problem": cond(red.Z.T @ H @ red.Z), "reduced": cond(reduced)}


_condition_batch = jit(jax.vmap(_condition_numbers, in_axes=(0, 0, None, None, None)))


@jit
def _alpha_on_branch(q, alpha0, red, scene, disc):
    """alpha with F(q, alpha) = 0 at each q, by Newton from alpha0 (one program)."""

    def alpha_at(qi):
        res = newton(lambda a, _: jnp.atleast_1d(reduced_function(qi, a[0], red, scene, disc)),
                     jnp.atleast_1d(alpha0), None, tol=1e-14)
        return res.x[0], res.converged

    return jax.vmap(alpha_at)(q)


def conditioning_near_fold(scene: DipoleMagnet, fold: ReducedFold, n: int = 16,
                           offsets=None, side: float = -1.0) -> dict:
    """Condition numbers at branch points q = q* + side * dq for dq in ``offsets``.

    Returns arrays keyed ``distance_deg`` (|alpha - alpha*|), ``dq`` and one per system.

    Systems compared: the Newton Hessian H (singular at the fold), the bordered continuation
    Jacobian and the Moore-Spence Jacobian. Paper: the folds of Proposition
    ``thm:planar_fold``.
    """
    offsets = np.logspace(-7, -1, 13) if offsets is None else np.asarray(offsets, float)
    disc = planar_discretisation(n, "clamped")
    red = reduction(scene, disc)
    a_star = np.radians(fold.alpha_deg)
    q = fold.q + side * offsets

    alpha, ok = _alpha_on_branch(np.asarray(q), a_star, red, scene, disc)
    if not bool(jnp.all(ok)):
        raise RuntimeError("conditioning_near_fold: F(q, alpha) = 0 not solved at every offset")
    cond = _condition_batch(jnp.asarray(q), alpha, red, scene, disc)
    return {"dq": offsets.tolist(),
            "distance_deg": np.degrees(np.abs(np.asarray(alpha) - a_star)).tolist(),
            **{k: np.asarray(v).tolist() for k, v in cond.items()}}
