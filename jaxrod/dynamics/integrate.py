"""Time integration of any scene's rod: a variational midpoint integrator, implicit and
differentiable.

The inextensible rod's Lagrangian (``jaxrod.dynamics.modes``: lateral kinetic energy
T = 1/2 int |dr/dt|^2 ds, r(s) = int_0^s d3; time in units of L^2 sqrt(rho A_c / (E I)))
is discretised in time by

    L_d(q0, q1) = h [ 1/2 sum_j w_j |r_j(q1) - r_j(q0)|^2 / h^2  -  E((q0 + q1) / 2, t + h/2) ],

(positions at the quadrature nodes s_j with weights w_j; the potential at the midpoint,
which makes the scheme implicit: stable at any step for the stiff bending modes, whose
frequencies grow as N^2 on the Chebyshev grid). The discrete Euler-Lagrange equations with
the forcing of Lagrange-d'Alembert,

    p_k + D_1 L_d(q_k, q_{k+1}) + f^-(q_k, q_{k+1}) = 0,
    p_{k+1} = D_2 L_d(q_k, q_{k+1}) + f^+(q_k, q_{k+1}),

are solved for q_{k+1} by Newton (``jaxrod.solvers.newton``) at every step of a ``lax.scan``.
Damping is a linear drag c per unit length on the velocity, f^-+ = -(c / 2) J(q_mid)^T W
(r(q1) - r(q0)) (c in units of sqrt(rho A_c E I) / L^2), and internal Kelvin-Voigt damping,
a viscous bending moment eta dkappa/dt with the dissipation 1/2 eta int |dkappa/dt|^2 ds
(kappa = d3 x d3', ``Scene.curvatures``; eta = eta_KV / (E T), eta_KV the material's
viscosity in Pa s and T the time unit), discretised alike. Without damping the scheme is
symplectic: the energy oscillates at O(h^2) and does not drift. Loads may move in time: the
input ``vary`` follows value(t) = start + rate * t.
"""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np

from jaxrod.dynamics.lagrangian import curvature_rate_form, kinetic, scene_at
from jaxrod.dynamics.modes import positions
from jaxrod.equilibria.equilibrium import DEFAULT_N, FIXED, discretise, tip, tip_tangent
from jaxrod.params import ParameterError
from jaxrod.programs import bucket, jit, steps_loop
from jaxrod.scenes.path import scene_path, still_path
from jaxrod.scenes.scene import Scene
from jaxrod.solvers.newton import newton


def _action(q0, q1, h, scene, disc):
    """L_d(q0, q1): the kinetic term from the positions' differences, the potential at the
    midpoint."""
    dr = positions(scene, q1, disc) - positions(scene, q0, disc)
    kinetic = 0.5 * jnp.sum(disc.quad_weights[:, None] * dr**2) / h
    return kinetic - h * FIXED.energy(0.5 * (q0 + q1), 0.0, (scene, disc))


def _drag(q0, q1, c, scene, disc):
    """f^- = f^+ = -(c / 2) J_r(q_mid)^T W (r(q1) - r(q0)) - (eta / 2) J_k(q_mid)^T W
    (kappa(q1) - kappa(q0)), c = (drag c, Kelvin-Voigt eta or None: none)."""
    drag, kv = c
    mid = 0.5 * (q0 + q1)
    W = disc.quad_weights[:, None]
    dr = positions(scene, q1, disc) - positions(scene, q0, disc)
    _, pull_r = jax.vjp(lambda q: positions(scene, q, disc), mid)
    force = -0.5 * drag * pull_r(W * dr)[0]
    if kv is None:
        return force
    dk = scene.curvatures(q1, disc) - scene.curvatures(q0, disc)
    _, pull_k = jax.vjp(lambda q: scene.curvatures(q, disc), mid)
    return force - 0.5 * kv * pull_k(W * dk)[0]


def _step_residual(q1, args):
    """p_k + D_1 L_d(q_k, q_{k+1}) + f^-(q_k, q_{k+1})."""
    q0, p0, h, c, scene_mid, disc = args
    return p0 + jax.grad(_action, argnums=0)(q0, q1, h, scene_mid, disc) \
        + _drag(q0, q1, c, scene_mid, disc)


def _momentum(q0, q1, h, c, scene_mid, disc):
    """p_{k+1} = D_2 L_d(q_k, q_{k+1}) + f^+(q_k, q_{k+1})."""
    return jax.grad(_action, argnums=1)(q0, q1, h, scene_mid, disc) \
        + _drag(q0, q1, c, scene_mid, disc)


def _run(path, disc, q0, p0, h, steps, c, start, rate, budget=None):
    W = disc.quad_weights[:, None]

    def step(carry, k):
        q, q_prev, p = carry
        t_mid = (k + 0.5) * h
        at = scene_at(path, start, rate, t_mid)
        guess = 2.0 * q - q_prev
        res = newton(_step_residual, guess, (q, p, h, c, at, disc), tol=1e-12)
        q1 = res.x
        p1 = _momentum(q, q1, h, c, at, disc)
        dr = positions(at, q1, disc) - positions(at, q, disc)
        kinetic = 0.5 * jnp.sum(W * dr**2) / h**2
        potential = FIXED.energy(0.5 * (q + q1), 0.0, (at, disc))
        end = scene_at(path, start, rate, t_mid + 0.5 * h)
        angle, X = tip(end, q1, disc)
        out = (q1, kinetic, potential, angle, tip_tangent(end, q1, disc), X, res.converged,
               res.residual_norm)
        return (q1, q, p1), out

    _, out = steps_loop(step, (q0, q0, p0), steps, budget)
    return out


def bdf_coefficients(ratio):
    """(a1, a2, b) of variable-step BDF2, y1 - a1 y0 + a2 y_-1 = b h f(y1), for the step
    ratio omega = h / h_prev (omega = 1: 4/3, 1/3, 2/3; omega = 0: backward Euler)."""
    d = 1.0 + 2.0 * ratio
    return (1.0 + ratio) ** 2 / d, ratio**2 / d, (1.0 + ratio) / d


def _bdf_residual(q1, args):
    """BDF2 on Lagrange's equations d/dt (M v) - dT/dq + grad E + c M v = 0, p = M(q) v:
    p1 - a1 p0 + a2 p_-1 = b h [dT/dq(q1, v1) - grad E(q1) - c p1],
    v1 = (q1 - a1 q0 + a2 q_-1) / (b h) (``bdf_coefficients``)."""
    q0, qm, p0, pm, h, c, coef, scene1, disc = args
    a1, a2, b = coef
    v1 = (q1 - a1 * q0 + a2 * qm) / (b * h)
    p1 = jax.grad(lambda v: kinetic(scene1, disc, q1, v))(v1)
    dTdq = jax.grad(lambda q: kinetic(scene1, disc, q, v1))(q1)
    drag, kv = c
    force = dTdq - FIXED.gradient(q1, 0.0, (scene1, disc)) - drag * p1
    if kv is not None:
        force = force - kv * curvature_rate_form(scene1, disc, q1, v1)
    return p1 - a1 * p0 + a2 * pm - b * h * force


def bdf_step(scene1, disc, q, qm, p, pm, h, ratio, c, guess):
    """One BDF2 step to q1 (step ratio ``ratio``, 0 for backward Euler): the Newton result,
    the velocity and momentum at q1."""
    coef = bdf_coefficients(ratio)
    res = newton(_bdf_residual, guess, (q, qm, p, pm, h, c, coef, scene1, disc), tol=1e-12)
    a1, a2, b = coef
    v1 = (res.x - a1 * q + a2 * qm) / (b * h)
    return res, v1, jax.grad(lambda v: kinetic(scene1, disc, res.x, v))(v1)


def observe(scene1, disc, q1, v1):
    """What a trajectory records at a step: kinetic and potential energy, the tip's
    direction, rotation and position."""
    angle, X = tip(scene1, q1, disc)
    return (kinetic(scene1, disc, q1, v1), FIXED.energy(q1, 0.0, (scene1, disc)), angle,
            tip_tangent(scene1, q1, disc), X)


def _run_bdf(path, disc, q0, p0, h, steps, c, start, rate, budget=None):
    def step(carry, k):
        q, qm, p, pm = carry
        at = scene_at(path, start, rate, (k + 1.0) * h)
        first = k == 0
        guess = jnp.where(first, q, 2.0 * q - qm)
        res, v1, p1 = bdf_step(at, disc, q, qm, p, pm, h, jnp.where(first, 0.0, 1.0), c,
                               guess)
        out = (res.x, *observe(at, disc, res.x, v1), res.converged, res.residual_norm)
        return (res.x, q, p1, p), out

    _, out = steps_loop(step, (q0, q0, p0, p0), steps, budget)
    return out


#: The fixed-step programs: ``steps`` traced within a static budget (``bucket(steps)``), so
#: that a new t_end or dt compiles nothing new within its bucket.
_program = jit(_run, static_argnames=("budget",))
_program_bdf = jit(_run_bdf, static_argnames=("budget",))
SCHEMES = ("midpoint", "bdf2", "discrete-gradient")


@dataclasses.dataclass(frozen=True)
class Trajectory:
    """A simulated motion: ``time`` (the end of each step, from h), the states, the tip's
    direction and rotation (degrees from +z toward +x) and position, the ``kinetic`` and
    ``potential`` energies at each step's midpoint and their sum ``energy``; ``converged``:
    every step's Newton solve converged (``residual_norm`` the largest)."""

    time: np.ndarray
    states: np.ndarray
    tip_angle_deg: np.ndarray
    tip_tangent_deg: np.ndarray
    tip_position: np.ndarray
    kinetic: np.ndarray
    potential: np.ndarray
    converged: bool
    residual_norm: float

    @property
    def energy(self) -> np.ndarray:
        return self.kinetic + self.potential

    def as_dict(self) -> dict:
        return {"time": self.time.tolist(), "tip_angle_deg": self.tip_angle_deg.tolist(),
                "tip_tangent_deg": self.tip_tangent_deg.tolist(),
                "energy": self.energy.tolist(), "kinetic": self.kinetic.tolist(),
                "converged": self.converged}


def simulate(scene: Scene, state, t_end: float, dt: float, damping: float = 0.0,
             n: int = DEFAULT_N, velocity=None, vary: str | None = None,
             rate: float = 0.0, scheme: str = "midpoint", tol: float | None = None,
             dt_max: float | None = None, max_steps: int = 20000,
             kelvin_voigt: float = 0.0) -> Trajectory:
    """The rod's motion from ``state`` (and ``velocity``, default at rest) until ``t_end``
    with steps ``dt`` (module docstring). ``damping``: the linear drag coefficient c >= 0;
    ``kelvin_voigt``: the internal damping eta >= 0.
    ``vary``/``rate``: an input moving at a constant rate from the scene's value (a magnet
    on its path at a finite speed). ``scheme``: "midpoint" (variational, symplectic: the
    energy of an undamped motion oscillates at O(dt^2) without drift; the modes that dt does
    not resolve are not damped and ring), or "bdf2" (BDF2 on Lagrange's equations,
    L-stable: those modes die out, the resolved motion is second order; for settling
    times).
    "discrete-gradient" (``jaxrod.dynamics.discrete_gradient``: the energy of an undamped
    motion conserved to round-off, a damped one's falling by exactly the dissipation).
    ``tol``: BDF2 with adaptive steps (``jaxrod.dynamics.adaptive``) at this local accuracy,
    from the step ``dt``, no longer than ``dt_max``, at most ``max_steps`` kept
    (``converged`` is False if they did not reach t_end)."""
    if scheme not in SCHEMES:
        raise ParameterError(f"scheme must be one of {', '.join(SCHEMES)}, got {scheme!r}")
    disc = discretise(scene, n)
    q0 = jnp.asarray(state, jnp.float64)
    if q0.shape != (disc.size,):
        raise ParameterError(f"state has shape {q0.shape}; degree {n} needs ({disc.size},)")
    for name, v in (("t_end", t_end), ("dt", dt)):
        if not (np.isfinite(v) and v > 0):
            raise ParameterError(f"{name} must be a finite number > 0, got {v!r}")
    for name, v in (("damping", damping), ("kelvin_voigt", kelvin_voigt)):
        if not (np.isfinite(v) and v >= 0):
            raise ParameterError(f"{name} must be a finite number >= 0, got {v!r}")
    # no Kelvin-Voigt damping: None, so that its terms are not compiled in
    c = (float(damping), float(kelvin_voigt) if kelvin_voigt > 0 else None)
    steps = int(np.ceil(t_end / dt - 1e-9))  # t_end / dt may round up past an integer
    path = still_path(scene) if vary is None else scene_path(scene, (vary,))
    start = 0.0 if vary is None else path.start[0]
    if velocity is None:
        p0 = jnp.zeros_like(q0)
    else:  # p0 = M(q0) v0, the Legendre transform at the start
        from jaxrod.dynamics.modes import mass_matrix

        p0 = mass_matrix(scene, q0, disc) @ jnp.asarray(velocity, jnp.float64)
    if tol is not None:
        return _adaptive(path, disc, q0, p0, t_end, dt, c, start, rate, scheme, tol,
                         dt_max, max_steps)
    program = {"midpoint": _program, "bdf2": _program_bdf}.get(scheme)
    if program is None:
        from jaxrod.dynamics.discrete_gradient import run_discrete_gradient as program
    q, kin, pot, angle, tangent, X, conv, res = (np.asarray(v)[:steps] for v in jax.device_get(
        program(path, disc, q0, p0, float(dt), steps, c, start, float(rate),
                budget=bucket(steps))))
    return Trajectory(time=dt * np.arange(1, steps + 1), states=np.asarray(q),
                      tip_angle_deg=np.degrees(angle), tip_tangent_deg=np.degrees(tangent),
                      tip_position=np.asarray(X), kinetic=np.asarray(kin),
                      potential=np.asarray(pot), converged=bool(np.all(conv)),
                      residual_norm=float(np.max(res)))


def _adaptive(path, disc, q0, p0, t_end, dt, c, start, rate, scheme, tol, dt_max,
              max_steps):
    from jaxrod.dynamics.adaptive import run_adaptive

    if scheme != "bdf2":
        raise ParameterError(f"tol: adaptive steps are BDF2's; scheme {scheme!r} has fixed "
                             "steps")
    dt_max = t_end if dt_max is None else dt_max
    for name, v in (("tol", tol), ("dt_max", dt_max)):
        if not (np.isfinite(v) and v > 0):
            raise ParameterError(f"{name} must be a finite number > 0, got {v!r}")
    if not (isinstance(max_steps, int) and max_steps >= 3):
        raise ParameterError(f"max_steps must be an integer >= 3, got {max_steps!r}")
    t, k, bufs = jax.device_get(run_adaptive(
        path, disc, q0, p0, float(t_end), float(dt), float(dt_max), float(tol), max_steps, c,
        start, float(rate)))
    time, q, kin, pot, angle, tangent, X, conv, res = (np.asarray(b)[:int(k)] for b in bufs)
    reached = float(t) >= float(t_end) * (1.0 - 1e-12)
    return Trajectory(time=time, states=q, tip_angle_deg=np.degrees(angle),
                      tip_tangent_deg=np.degrees(tangent), tip_position=X, kinetic=kin,
                      potential=pot, converged=bool(reached and np.all(conv)),
                      residual_norm=float(np.max(res, initial=0.0)))
