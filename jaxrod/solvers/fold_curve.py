"""Folds in two parameters: pseudo-arclength continuation of the Moore-Spence system, and
the cusp where a fold curve's quadratic coefficient vanishes.

A fold of the equilibria F(x, lam; u) = grad_x E = 0 solves the Moore-Spence system
(``jaxrod.solvers.folds``) R(z; u) = [F; H phi; l . phi - 1] = 0, z = (x, phi, lam): 2m + 1
equations. With the second parameter u free, the folds form a curve w(s) = (z(s), u(s)),
followed by pseudo-arclength (Keller) with the weighted inner product
<a, b> = (a_x . b_x + a_phi . b_phi) / m + a_lam b_lam + a_u b_u:

    predictor   w_p = w_k + ds t_k
    corrector   R(w) = 0,  <t_k, w - w_p> = 0                    (Newton, exact Jacobian)
    tangent     [R_z  R_u; t_k^T W] t = [0; 1],   t_{k+1} = t / |t|

R_z is the Moore-Spence Jacobian (from the energy's assembled derivatives), R_u one forward-
mode tangent of R in u. The normalisation vector l is re-set to phi_k / |phi_k|^2 at every
accepted point (phi_k still satisfies l . phi = 1, so the curve stays continuous while the
null vector rotates). Turning points of the curve in u are regular points of this system,
so the curve is followed round them.

Along the curve, with phi scaled to c . phi = 1 (c the linear functional of the reduced
coordinate, q = c . x), the reduced function F(q, lam; u) of the Lyapunov-Schmidt reduction
has F_q = 0 and the quadratic coefficient

    F_qq = D^3E[phi, phi, phi].

At a cusp F_qq = 0: the two fold curves of one parameter meet and the hysteresis between
them closes. The cusp is a regular solution of the square system (2m + 2 unknowns w)

    R(z; u) = 0,      C(w) = D^3E[phi, phi, phi] = 0,

(``event_residual`` with ``quadratic_coefficient``), refined by Newton from the recorded
point next to the sign change of F_qq, differentiable in the remaining parameters
(``differentiable_cusp``). The same Newton locates where a fold curve reaches a given lam
(``event_solve`` with ``parameter_lam``), or a given u (``parameter_u``). The cusp's normal form is
F = F_lam (lam - lam_c) + F_qu (u - u_c) q + F_qqq q^3 / 6 + ..., with the cubic
coefficient (``cubic_coefficient``)

    F_qqq = D^4E[phi, phi, phi, phi] + 3 D^3E[phi, phi, w2],
    [H c; c^T 0] [w2; s] = [-D^3E[phi, phi]; 0]

(the reduced function is the multiplier in grad E(x(q)) = F(q) c, c . x(q) = q, at fixed
(lam, u); three q-derivatives dotted with phi give F_qqq, and D^3E[phi, phi] . phi = 0 at
the cusp makes the bordered system for w2 = x''(q) solvable).

The run is one ``lax.while_loop`` over fixed-capacity arrays (NaN padded), compiled once per
(energy model, args map, problem size, capacity). It stops at the bounds of u or lam, when
full, or when the step collapses.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp

from jaxrod.derivatives import EnergyModel
from jaxrod.solvers.arclength import StepControl, arclength_run
from jaxrod.solvers.continuation import (
    RUNNING,
    STATUS_MESSAGES,
)
from jaxrod.solvers.folds import moore_spence_residual, moore_spence_system
from jaxrod.solvers.newton import implicit_newton, newton
from jaxrod.status import Status

CUSP_PASSED = Status.CUSP_PASSED
#: The messages of a fold-curve run's codes (``jaxrod.status.Status``).
CURVE_STATUS = STATUS_MESSAGES | {int(CUSP_PASSED): CUSP_PASSED.message}

#: ``args_at(u, args) -> model args``: how the second parameter enters the energy (a
#: hashable, module-level function or frozen dataclass, so compiled programs are reused).
ArgsMap = Callable[[jax.Array, Any], Any]


class FoldCurveOptions(NamedTuple):
    """Step control and bounds (all traced; ``capacity`` is passed separately, static)."""

    ds: float = 0.02
    ds_min: float = 1e-8
    ds_max: float = 0.05
    growth: float = 1.5
    u_min: float = -jnp.inf
    u_max: float = jnp.inf
    lam_min: float = -jnp.inf
    lam_max: float = jnp.inf
    tol: float = 1e-12
    max_cusps: float = jnp.inf


class RawFoldCurve(NamedTuple):
    """Device arrays of one fold-curve run (first ``num_points`` rows valid, NaN beyond)."""

    w: jax.Array  # (capacity, 2m + 2): (x, phi, lam, u)
    tangent: jax.Array  # (capacity, 2m + 2)
    cusp_test: jax.Array  # (capacity,): D^3E[phi, phi, phi] / |phi|^3
    lam_derivative: jax.Array  # (capacity,): F_lam . phi
    cubic_form: jax.Array  # (capacity,): D^3E[phi, phi, phi]
    smallest_eigenvalues: jax.Array  # (capacity, 2): of the Hessian H
    newton_iterations: jax.Array
    residual_norm: jax.Array
    num_points: jax.Array
    status: jax.Array
    rejected_steps: jax.Array


def split(w, m):
    """(x, phi, lam, u) of a fold-curve point."""
    return w[:m], w[m:2 * m], w[2 * m], w[2 * m + 1]


def _weights(m, dtype):
    return jnp.concatenate([jnp.full(2 * m, 1.0 / m, dtype), jnp.ones(2, dtype)])


def fold_linearisation(w, ell, model: EnergyModel, args_at: ArgsMap, args):
    """(R(w), [R_z R_u]) at w = (x, phi, lam, u): the Moore-Spence residual and its Jacobian
    in all 2m + 2 unknowns,

        [ H          0    F_lam         F_u        ]
        [ D^3E[phi]  H    (H phi)_lam   (H phi)_u  ]
        [ 0          l^T  0             0          ],

    from one assembly of the Hessian and gradient and three tangents of them, along
    (phi, 0, 0), (0, 1, 0) and (0, 0, 1) in (x, lam, u) (``EnergyModel.fold_blocks`` with
    the second parameter, laid out by ``moore_spence_system``)."""
    m = ell.shape[0]
    x, phi, lam, u = split(w, m)
    return moore_spence_system(model.fold_blocks(x, lam, args, phi, second=(args_at, u)), phi,
                               ell)


def _ell_row(ell):
    """The normalisation's row [0 l^T 0 0] of the fold Jacobian."""
    m = ell.shape[0]
    return jnp.concatenate([jnp.zeros(m, ell.dtype), ell, jnp.zeros(2, ell.dtype)])


def _unit_ell(phi):
    return phi / jnp.dot(phi, phi)


def _cusp_test(J, phi):
    """D^3E[phi, phi, phi] / |phi|^3 from the Moore-Spence Jacobian's D^3E[phi] block."""
    m = phi.shape[0]
    return phi @ J[m:2 * m, :m] @ phi / jnp.dot(phi, phi) ** 1.5  # = quadratic_coefficient


def _point_data(J, phi):
    """(cusp test, F_lam . phi, D^3E[phi, phi, phi], two smallest eigenvalues of H) from the
    fold Jacobian's blocks [H 0 F_lam; D^3E[phi] H (H phi)_lam; ...] at a point."""
    m = phi.shape[0]
    cubic = phi @ J[m:2 * m, :m] @ phi
    eigs = jnp.linalg.eigvalsh(J[:m, :m])[:2]
    return cubic / jnp.dot(phi, phi) ** 1.5, J[:m, 2 * m] @ phi, cubic, eigs


@dataclasses.dataclass(frozen=True)
class _FoldCurve:
    """The folds in two parameters as a system of ``jaxrod.solvers.arclength``: w = (x, phi,
    lam, u), <a, b> = (a_x . b_x + a_phi . b_phi) / m + a_lam b_lam + a_u b_u; aux = l, the
    normalisation vector, re-set to phi / |phi|^2 at every accepted point; an event is a sign
    change of the cusp test."""

    model: EnergyModel
    args_at: ArgsMap
    m: int
    dtype: Any

    @property
    def weights(self):
        return _weights(self.m, self.dtype)

    def inner(self, a, b):
        return jnp.dot(self.weights * a, b)

    def linearise(self, w, ell, args):
        return fold_linearisation(w, ell, self.model, self.args_at, args)

    def accepted(self, w, ell, J):
        # the fold Jacobian at the new point: the corrector's, with the row of the new l
        ell = _unit_ell(w[self.m:2 * self.m])
        return ell, J.at[2 * self.m].set(_ell_row(ell))

    def record(self, o: RawFoldCurve, k, w, t, J, res):
        o = o._replace(w=o.w.at[k].set(w), tangent=o.tangent.at[k].set(t),
                       newton_iterations=o.newton_iterations.at[k].set(res.iterations),
                       residual_norm=o.residual_norm.at[k].set(res.residual_norm))
        return _record_data(o, k, J, w[self.m:2 * self.m])

    def event(self, w, t, t_old, J, out, k_old):
        return _cusp_test(J, w[self.m:2 * self.m]) * out.cusp_test[k_old] < 0

    def outside(self, w, opts):
        lam, u = w[2 * self.m], w[2 * self.m + 1]
        return (u > opts.u_max) | (u < opts.u_min) | (lam > opts.lam_max) | (lam < opts.lam_min)


def _record_data(o: RawFoldCurve, k, J, phi):
    test, lam_d, cubic, eigs = _point_data(J, phi)
    return o._replace(cusp_test=o.cusp_test.at[k].set(test),
                      lam_derivative=o.lam_derivative.at[k].set(lam_d),
                      cubic_form=o.cubic_form.at[k].set(cubic),
                      smallest_eigenvalues=o.smallest_eigenvalues.at[k].set(eigs))


def fold_curve_run(model: EnergyModel, args_at: ArgsMap, w0, args, opts: FoldCurveOptions,
                   capacity: int, direction) -> RawFoldCurve:
    """Follow the fold curve through the fold w0 = (x, phi, lam, u) (traceable; ``capacity``
    static; vmappable over w0 and ``direction``, the sign of du on the first step).

    w0 must be a converged fold (its phi any nonzero null vector). The steps are those of
    ``jaxrod.solvers.arclength`` with the fold system.
    """
    m = (w0.shape[0] - 2) // 2
    system = _FoldCurve(model, args_at, m, w0.dtype)
    ell0 = _unit_ell(w0[m:2 * m])
    # the first tangent is oriented so that du has the sign of direction
    orient = jnp.zeros_like(w0).at[-1].set(jnp.sign(direction))
    nan = jnp.full(capacity, jnp.nan, w0.dtype)
    out = RawFoldCurve(
        w=jnp.full((capacity, w0.shape[0]), jnp.nan, w0.dtype),
        tangent=jnp.full((capacity, w0.shape[0]), jnp.nan, w0.dtype),
        cusp_test=nan, lam_derivative=nan, cubic_form=nan,
        smallest_eigenvalues=jnp.full((capacity, 2), jnp.nan, w0.dtype),
        newton_iterations=jnp.full(capacity, -1), residual_norm=nan,
        num_points=jnp.asarray(0), status=jnp.asarray(int(RUNNING)),
        rejected_steps=jnp.asarray(0))
    control = StepControl(opts.ds, opts.ds_min, opts.ds_max, opts.growth, opts.tol,
                          opts.max_cusps)
    out, num, status, rejected = arclength_run(system, args, w0, orient, ell0, out, control,
                                               opts, capacity, CUSP_PASSED)
    return out._replace(num_points=num, status=status, rejected_steps=rejected)


def quadratic_coefficient(w, model: EnergyModel, args_at: ArgsMap, args):
    """D^3E[phi, phi, phi] / |phi|^3 at w (F_qq up to a positive factor; its zero is the
    cusp)."""
    m = (w.shape[0] - 2) // 2
    x, phi, lam, u = split(w, m)
    return (phi @ model.third(x, lam, args_at(u, args), phi) @ phi
            / jnp.dot(phi, phi) ** 1.5)


def parameter_lam(w, model, args_at, args):
    """lam at w (the event of a fold curve reaching a given lam)."""
    return w[(w.shape[0] - 2) // 2 * 2]


def parameter_u(w, model, args_at, args):
    """u at w (the event of a fold curve reaching a given value of the second parameter)."""
    return w[-1]


def event_residual(w, data):
    """[R(z; u); event(w) - target] for w = (x, phi, lam, u), data = (ell, model, args_at,
    args, event, target): a point of the fold curve where ``event`` (a scalar function of
    (w, model, args_at, args)) takes the value ``target``. With ``quadratic_coefficient`` and
    target 0 it is the cusp system (module docstring)."""
    ell, model, args_at, args, event, target = data
    R = moore_spence_residual(w[:-1], (model, ell, args_at(w[-1], args)))
    return jnp.append(R, event(w, model, args_at, args) - target)


def _event_linearisation(w, data):
    ell, model, args_at, args, event, target = data
    R, J = fold_linearisation(w, ell, model, args_at, args)
    g, dg = jax.value_and_grad(event)(w, model, args_at, args)
    return jnp.append(R, g - target), jnp.vstack([J, dg[None, :]])


def event_solve(model: EnergyModel, args_at: ArgsMap, w0, args, event=quadratic_coefficient,
                target=0.0, tol: float = 1e-13):
    """Newton on ``event_residual`` from the fold-curve point w0 (traceable); the default is
    the cusp."""
    m = (w0.shape[0] - 2) // 2
    ell = _unit_ell(w0[m:2 * m])
    return newton(None, w0, (ell, model, args_at, args, event, target), tol=tol,
                  linearise=_event_linearisation)


def differentiable_cusp(model: EnergyModel, args_at: ArgsMap, w0, args, tol: float = 1e-13):
    """(w, stats): the cusp, differentiable in ``args`` by implicit differentiation of the cusp
    system (one solve with its Jacobian per tangent), and the Newton statistics (converged
    as 0/1, residual norm, iterations)."""
    m = (w0.shape[0] - 2) // 2
    ell = jax.lax.stop_gradient(_unit_ell(w0[m:2 * m]))
    data = lambda p: (ell, model, args_at, p, quadratic_coefficient, 0.0)
    return implicit_newton(lambda w, p: event_residual(w, data(p)), jax.lax.stop_gradient(w0),
                           args, tol, linearise=lambda w, p: _event_linearisation(w, data(p)))


def cubic_coefficient(w, c, model: EnergyModel, args_at: ArgsMap, args):
    """F_qqq at a cusp w, with phi scaled to c . phi = 1 (module docstring)."""
    m = c.shape[0]
    x, phi, lam, u = split(w, m)
    phi = phi / jnp.dot(c, phi)
    a = args_at(u, args)
    H = model.hessian(x, lam, a)
    g2 = model.third(x, lam, a, phi) @ phi
    bordered = jnp.block([[H, c[:, None]], [c[None, :], jnp.zeros((1, 1), H.dtype)]])
    w2 = jnp.linalg.solve(bordered, jnp.append(-g2, 0.0))[:m]
    d4 = jax.jvp(lambda y: phi @ model.third(y, lam, a, phi) @ phi, (x,), (phi,))[1]
    return d4 + 3.0 * jnp.dot(g2, w2)
