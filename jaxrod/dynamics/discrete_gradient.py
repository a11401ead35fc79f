"""An energy-conserving integrator: Gonzalez's discrete gradient on the rod's Hamiltonian.

In the canonical variables x = (q, p), p = M(q) v (``jaxrod.dynamics.modes``: the mass
matrix of T = 1/2 int |dr/dt|^2 ds), the rod's energy is

    H(q, p) = 1/2 p . M(q)^-1 p + E(q),
    grad_p H = v = M(q)^-1 p,   grad_q H = grad E(q) - dT/dq (q, v)   (T at fixed v).

One step from x0 to x1 solves, by Newton (``jaxrod.solvers.newton``),

    q1 - q0 = h gbar_p,   p1 - p0 = -h gbar_q + h f,

with the discrete gradient (O. Gonzalez, J. Nonlinear Sci. 6, 1996)

    gbar = grad H(x_m) + [H(x1) - H(x0) - grad H(x_m) . dx] / (dx . dx) dx,
    x_m = (x0 + x1) / 2,  dx = x1 - x0,

for which gbar . dx = H(x1) - H(x0) exactly, so that without damping (f = 0)

    H(x1) - H(x0) = h (gbar_q . gbar_p - gbar_p . gbar_q) = 0:

the energy is conserved to the Newton tolerance and round-off, whatever the step (the
midpoint variational integrator keeps it to O(h^2) only). The scheme is second order,
symmetric and, on a linear system, the implicit midpoint rule (A-stable: the stiff bending
modes that h does not resolve ring at their energy, neither grow nor decay). Damping
enters as f = -c M(q_m) gbar_p - eta K(q_m) gbar_p (drag c, Kelvin-Voigt eta,
``jaxrod.dynamics.integrate``), so that the energy falls by exactly h gbar_p . f <= 0 in
each step. A load moving in time (``vary``) is held at the step's midpoint time in both
H(x0) and H(x1). Where |dx|^2 is below 1e-24 (the rod at rest) the correction, then
smaller than round-off, is left out.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from jaxrod.dynamics.lagrangian import curvature_rate_form, kinetic, scene_at
from jaxrod.dynamics.modes import mass_matrix
from jaxrod.equilibria.equilibrium import FIXED, tip, tip_tangent
from jaxrod.programs import jit, steps_loop
from jaxrod.solvers.newton import newton

TINY = 1e-24


def hamiltonian(scene, disc, q, p):
    """H(q, p) and the velocity v = M(q)^-1 p."""
    v = jnp.linalg.solve(mass_matrix(scene, q, disc), p)
    return 0.5 * jnp.dot(p, v) + FIXED.energy(q, 0.0, (scene, disc)), v


def hamiltonian_gradient(scene, disc, q, p):
    """(grad_q H, grad_p H) = (grad E(q) - dT/dq (q, v), v), v = M(q)^-1 p."""
    v = jnp.linalg.solve(mass_matrix(scene, q, disc), p)
    dTdq = jax.grad(lambda y: kinetic(scene, disc, y, v))(q)
    return FIXED.gradient(q, 0.0, (scene, disc)) - dTdq, v


def _residual(x1, args):
    x0, H0, h, c, scene, disc = args
    m = x0.shape[0] // 2
    dx = x1 - x0
    xm = 0.5 * (x0 + x1)
    gq, gp = hamiltonian_gradient(scene, disc, xm[:m], xm[m:])
    g = jnp.concatenate([gq, gp])
    H1, _ = hamiltonian(scene, disc, x1[:m], x1[m:])
    dd = jnp.dot(dx, dx)
    big = dd > TINY
    coef = jnp.where(big, (H1 - H0 - jnp.dot(g, dx)) / jnp.where(big, dd, 1.0), 0.0)
    gbar = g + coef * dx
    vbar = gbar[m:]
    drag, kv = c
    qm = xm[:m]
    f = -drag * mass_matrix(scene, qm, disc) @ vbar
    if kv is not None:
        f = f - kv * curvature_rate_form(scene, disc, qm, vbar)
    return jnp.concatenate([dx[:m] - h * vbar, dx[m:] + h * gbar[:m] - h * f])


def _jacobian(x1, args):
    """The midpoint rule's Jacobian for Newton, [[I, -h/2 M^-1], [h/2 Hess E, I + h/2 (c I
    + eta K M^-1)]] at x_m: the residual's own less the derivatives of M(q) in the kinetic
    terms and of the discrete gradient's correction (both vanish with the step). Newton
    converges to the same root, in 3-6 iterations against the exact Jacobian's 2, each
    5x cheaper (no derivatives of the mass matrix), where the motion is slow enough in a
    step."""
    x0, _, h, c, scene, disc = args
    m = x0.shape[0] // 2
    qm = 0.5 * (x0[:m] + x1[:m])
    Mi = jnp.linalg.solve(mass_matrix(scene, qm, disc), jnp.eye(m))
    drag, kv = c
    damp = drag * jnp.eye(m)
    if kv is not None:
        damp = damp + kv * jax.jacfwd(lambda v: curvature_rate_form(scene, disc, qm, v))(
            jnp.zeros(m)) @ Mi
    return jnp.block([[jnp.eye(m), -0.5 * h * Mi],
                      [0.5 * h * FIXED.hessian(qm, 0.0, (scene, disc)),
                       jnp.eye(m) + 0.5 * h * damp]])


def discrete_gradient_step(scene_mid, disc, q, p, h, c, guess):
    """One step from (q, p) with the loads of ``scene_mid`` (module docstring): the Newton
    result for x1 = (q1, p1): first with the midpoint rule's Jacobian (``_jacobian``), and
    where that does not converge in 15 iterations (fast motion in long steps), again with the
    exact Jacobian (forward-mode autodiff of the residual)."""
    x0 = jnp.concatenate([q, p])
    H0, _ = hamiltonian(scene_mid, disc, q, p)
    args = (x0, H0, h, c, scene_mid, disc)
    quick = newton(_residual, guess, args, tol=1e-12, jacobian=_jacobian, max_steps=15,
                   xtol=0.0, stall_xtol=0.0)
    return jax.lax.cond(quick.converged, lambda: quick,
                        lambda: newton(_residual, guess, args, tol=1e-12))


def _run(path, disc, q0, p0, h, steps, c, start, rate, budget=None):
    m = q0.shape[0]

    def step(carry, k):
        x, x_prev = carry
        t_mid = (k + 0.5) * h
        at = scene_at(path, start, rate, t_mid)
        guess = jnp.where(k == 0, x, 2.0 * x - x_prev)
        res = discrete_gradient_step(at, disc, x[:m], x[m:], h, c, guess)
        q1, p1 = res.x[:m], res.x[m:]
        end = scene_at(path, start, rate, t_mid + 0.5 * h)
        H1, v1 = hamiltonian(end, disc, q1, p1)
        kin = 0.5 * jnp.dot(p1, v1)
        angle, X = tip(end, q1, disc)
        out = (q1, kin, H1 - kin, angle, tip_tangent(end, q1, disc), X, res.converged,
               res.residual_norm)
        return (res.x, x), out

    x0 = jnp.concatenate([q0, p0])
    _, out = steps_loop(step, (x0, x0), steps, budget)
    return out


run_discrete_gradient = jit(_run, static_argnames=("budget",))
