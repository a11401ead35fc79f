"""The branch of a twisted rod in its end rotation, and its equilibrium at given turns.

Unknowns w = (x, mu, nu, turns): the fields, the far end's multipliers (in units of
``MULTIPLIER_UNIT``), the phase multiplier and the far end's turns. The equations are the
stationarity of

    Lambda = E(x; turns) + U mu . g(x) + nu c . (x - x_ref),

c = ``orbit_direction(x_ref)`` / |.|, x_ref the last accepted point: the phase condition
that picks one of the circle of equilibria the isotropic rod's symmetry makes (at a solution
nu = 0, since both E and g are invariant). Its Hessian in z = (x, mu, nu) is a bordered
matrix whose inertia is that of the second variation on the constraints' tangent space plus
(k + 1, k + 1, 0) (Haynsworth; k + 1 bordering rows of full rank): the count of the
equilibrium's unstable directions is its number of negative eigenvalues minus k + 1.

The branch is followed by the pseudo-arclength driver (``jaxrod.solvers.arclength``): one
``lax.while_loop``, compiled once per (degree, control); a fold in turns is a sign change of
d(turns)/ds. A run starts from a bent state: under shortening control, by default, the
Euler-buckled rod (no turns), which the first corrector converges.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from jaxrod import spectral
from jaxrod.discretise.framed import (
    FramedDiscretisation,
    frame,
    framed_jet,
    twist_and_writhe,
)
from jaxrod.equilibria.resolution import TOLERANCE
from jaxrod.params import ParameterError
from jaxrod.programs import jit
from jaxrod.solvers.arclength import StepControl, arclength_run
from jaxrod.solvers.continuation import (
    FOLDS_FOUND,
    STATUS_MESSAGES,
    _record,
    empty_branch,
)
from jaxrod.solvers.newton import newton
from jaxrod.status import Status
from jaxrod.twisted.rod import (
    MULTIPLIER_UNIT,
    TwistedRod,
    energy,
    far_end,
    orbit_direction,
)


def _lagrangian(w, aux, data, count: int):
    """Lambda (module docstring): its derivatives are assembled by ``_linearise``."""
    disc, inputs = data
    x_ref, c = aux
    size = disc.size
    x, mu, nu, turns = w[:size], w[size:size + count], w[size + count], w[-1]
    return (energy(x, turns, disc, inputs)
            + MULTIPLIER_UNIT * jnp.dot(mu, far_end(x, disc, inputs, count))
            + nu * jnp.dot(c, x - x_ref))


def _linearise(w, aux, data, count: int):
    """(grad_z Lambda, [Hess_z Lambda | d grad_z Lambda / d turns]) assembled from the
    nodes: Lambda = sum_j q_j phi(a_j, mu) - U mu_z (1 - e) + nu c . (x - x_ref), the jets
    a_j = L_j x + l_j turns, phi = the energy density + U mu . d3(a)[:count]; so the
    Hessian is sum_j q_j L_j^T phi_aa L_j, bordered by the constraints' gradients and c
    (the same numbers as autodiff of ``_lagrangian``, without its cost)."""
    disc, inputs = data
    x_ref, c = aux
    size = disc.size
    x, mu, nu, turns = w[:size], w[size:size + count], w[size + count], w[-1]
    L, q = disc.jet_matrix, disc.field.quad_weights
    jets = disc.jets(x, turns)
    per_turn = disc.lift(1.0)  # d a_j / d turns

    def phi(a, mu):
        gamma, beta, tension = inputs[0], inputs[1], inputs[2]
        F, u = framed_jet(a)
        return (0.5 * (u[0] ** 2 + beta * u[1] ** 2 + gamma * u[2] ** 2) - tension * F[2, 2]
                + MULTIPLIER_UNIT * jnp.dot(mu, F[:count, 2]))

    grad_a = jax.vmap(jax.grad(phi), in_axes=(0, None))(jets, mu)
    hess_a = jax.vmap(jax.hessian(phi), in_axes=(0, None))(jets, mu)
    d3_a = jax.vmap(jax.jacfwd(lambda a: frame(a[0], a[1], a[2])[:count, 2]))(jets)
    d3 = jax.vmap(lambda a: frame(a[0], a[1], a[2])[:count, 2])(jets)
    held = jnp.zeros(count).at[2].set(1.0 - inputs[3]) if count == 3 else jnp.zeros(count)
    Lq = L * q[:, None, None]
    r_x = jnp.einsum("jrm,jr->m", Lq, grad_a) + nu * c
    r_mu = MULTIPLIER_UNIT * (q @ d3 - held)
    r_nu = jnp.dot(c, x - x_ref)
    H_xx = jnp.einsum("jrm,jrs,jsn->mn", Lq, hess_a, L)
    H_xmu = MULTIPLIER_UNIT * jnp.einsum("jrm,jkr->mk", Lq, d3_a)
    col_x = jnp.einsum("jrm,jrs,js->m", Lq, hess_a, per_turn)
    col_mu = MULTIPLIER_UNIT * jnp.einsum("j,jkr,jr->k", q, d3_a, per_turn)
    top = jnp.hstack([H_xx, H_xmu, c[:, None], col_x[:, None]])
    middle = jnp.hstack([H_xmu.T, jnp.zeros((count, count + 1)), col_mu[:, None]])
    bottom = jnp.concatenate([c, jnp.zeros(count + 2)])[None, :]
    return jnp.concatenate([r_x, r_mu, r_nu[None]]), jnp.vstack([top, middle, bottom])


def _phase(x, disc):
    c = orbit_direction(x, disc)
    return x, c / jnp.sqrt(jnp.dot(c, c))


@dataclasses.dataclass(frozen=True)
class _TwistSystem:
    """The stationarity of Lambda (module docstring) as a curve system of
    ``jaxrod.solvers.arclength``; built inside the traced run, holding its data. After each
    accepted point the phase reference moves there and the Jacobian is formed again with
    the new phase direction (for the tangent)."""

    size: int
    count: int
    data: Any

    @property
    def m(self) -> int:
        return self.size + self.count + 1

    @property
    def weights(self):
        return jnp.append(jnp.full(self.m, 1.0 / self.m), 1.0)

    def inner(self, a, b):
        return jnp.dot(self.weights * a, b)

    def linearise(self, w, aux, data):
        return _linearise(w, aux, data, self.count)

    def accepted(self, w, aux, J):
        new = _phase(w[:self.size], self.data[0])
        return new, self.linearise(w, new, self.data)[1]

    def record(self, out, k, w, t, J, res):
        return _record(out, k, w, t, J[:, :self.m], res.iterations, res.residual_norm, True)

    def event(self, w, t, t_old, J, out, k_old):
        return t[-1] * t_old[-1] < 0

    def outside(self, w, bounds):
        return (w[-1] > bounds[1]) | (w[-1] < bounds[0])


def _run(size: int, count: int, capacity: int, data, w0, bounds, control):
    system = _TwistSystem(size, count, data)
    m = system.m
    out = empty_branch(capacity, m)
    orient = jnp.zeros(m + 1).at[-1].set(jnp.sign(bounds[1] + bounds[0] - 2 * w0[-1]))
    out, num, status, rejected = arclength_run(system, data, w0, orient,
                                               _phase(w0[:size], data[0]), out, control,
                                               bounds, capacity, FOLDS_FOUND)
    return out._replace(num_points=num, status=status, rejected_steps=rejected)


_run_program = jit(_run, static_argnums=(0, 1, 2))


def _solve_at(size: int, count: int, data, w0):
    """Newton on the stationarity at w0's turns, the phase at w0."""
    aux = _phase(w0[:size], data[0])
    m = size + count + 1

    def linearise(z, _):
        R, J = _linearise(jnp.append(z, w0[-1]), aux, data, count)
        return R, J[:, :m]

    res = newton(None, w0[:m], None, tol=1e-10, linearise=linearise, keep_jacobian=True,
                 max_steps=60)
    return res, jnp.linalg.eigvalsh(0.5 * (res.jacobian + res.jacobian.T))


_solve_program = jit(_solve_at, static_argnums=(0, 1))


@dataclasses.dataclass(frozen=True)
class TwistState:
    """One equilibrium of a twisted rod (``twisted_equilibrium`` or a branch's point).

    turns: the far end's rotation; twist_moment: M L / B1 about the axis at the far end;
    tension: T L^2 / B1 there; twist, writhe: Tw and Wr (their sum is ``turns``, the
    linking number); unstable: how many directions lower the energy (0: stable);
    converged, residual, iterations: Newton's report; tail: the largest of the three
    fields' last two Chebyshev coefficients (the resolution: small against the fields)."""

    rod: TwistedRod
    w: np.ndarray
    turns: float
    twist_moment: float
    tension: float
    twist: float
    writhe: float
    unstable: int
    converged: bool
    residual: float
    iterations: int
    tail: float

    @property
    def x(self) -> np.ndarray:
        return self.w[:3 * (self.rod.n - 1)]

    @property
    def status(self) -> Status:
        """NOT_CONVERGED, UNDER_RESOLVED (converged, but the fields' Chebyshev tail is above
        ``jaxrod.equilibria.resolution.TOLERANCE``: raise n, e.g. by ``twisted_equilibrium``
        with this state as its start; its stability count may be spurious) or SUCCESS."""
        if not self.converged:
            return Status.NOT_CONVERGED
        return Status.UNDER_RESOLVED if self.tail > TOLERANCE else Status.SUCCESS

    def centreline(self) -> tuple[np.ndarray, np.ndarray]:
        """(s, r): the Chebyshev nodes and the centreline r(s) = int_0^s d3 there, (n + 1, 3)."""
        from jaxrod.twisted.rod import centreline

        disc = self.rod.discretisation()
        return np.asarray(disc.field.nodes), centreline(disc, self.x)

    def as_dict(self) -> dict:
        return {"turns": self.turns, "twist_moment": self.twist_moment,
                "tension": self.tension, "twist": self.twist, "writhe": self.writhe,
                "unstable": self.unstable, "converged": self.converged,
                "residual": self.residual, "iterations": self.iterations,
                "chebyshev_tail": self.tail, "n": self.rod.n,
                "status": self.status.name.lower()}


def _twist_measures(x, turns, disc, inputs):
    """(twist moment, Tw, Wr) of one state."""
    moment = jax.grad(energy, argnums=1)(x, turns, disc, inputs) / (2.0 * math.pi)
    return (moment, *twist_and_writhe(disc, x, turns))


_measures_program = jit(jax.vmap(_twist_measures, in_axes=(0, 0, None, None)))


def _states(rod: TwistedRod, disc: FramedDiscretisation, W, converged, residual, iterations,
            index) -> list[TwistState]:
    """The records of the states W (one per row: x, mu, nu, turns) with Newton's report and
    the bordered Hessian's negative count ``index``."""
    W = np.atleast_2d(np.asarray(W))
    size = disc.size
    moment, tw, wr = (np.asarray(a) for a in _measures_program(
        jnp.asarray(W[:, :size]), jnp.asarray(W[:, -1]), disc, rod.inputs()))
    tension = np.full(len(W), rod.tension) if rod.constraints == 2 \
        else -MULTIPLIER_UNIT * W[:, size + 2]
    fields = np.asarray(disc.field.to_full) @ W[:, :size].reshape(len(W), 3, disc.free) \
        .transpose(0, 2, 1)
    tail = np.abs(np.einsum("kj,pjf->pkf", spectral.values_to_coefficients_matrix(rod.n),
                            fields)[:, -2:]).max(axis=(1, 2))
    return [TwistState(rod, W[i], float(W[i, -1]), float(moment[i]), float(tension[i]),
                       float(tw[i]), float(wr[i]), int(index[i]) - (rod.constraints + 1),
                       bool(converged[i]), float(residual[i]), int(iterations[i]),
                       float(tail[i])) for i in range(len(W))]


@dataclasses.dataclass(frozen=True)
class TwistBranch:
    """A branch of a twisted rod in its end rotation: ``points`` (TwistState, in order),
    ``folds`` (the indices where d(turns)/ds changes sign: the point after the turn, located
    to the step, not refined; a branch that reaches the straight rod, whose phase condition
    degenerates there, may show its branch point as such a turn), ``status`` and its
    message."""

    rod: TwistedRod
    points: list[TwistState]
    folds: list[int]
    status: int

    @property
    def message(self) -> str:
        return STATUS_MESSAGES.get(self.status, Status(self.status).message)

    def column(self, name: str) -> np.ndarray:
        return np.array([getattr(p, name) for p in self.points])


def _seed(rod: TwistedRod, disc: FramedDiscretisation) -> np.ndarray:
    """The first Euler mode of the clamped-clamped rod, v1 = 2 sqrt(e) sin(2 pi s) (its
    height is 1 - e to first order), no turns, thrust 4 pi^2."""
    if rod.shortening is None:
        raise ParameterError("start: a rod under tension control needs a bent start (a "
                             "state of a branch under shortening control, say)")
    nodes = np.asarray(disc.field.nodes)[1:rod.n]
    x = np.zeros(disc.size)
    x[:disc.free] = 2.0 * math.sqrt(rod.shortening) * np.sin(2.0 * math.pi * nodes)
    return np.concatenate([x, [0.0, 0.0, 1.0, 0.0, 0.0]])


def _regrid(rod: TwistedRod, state: TwistState) -> np.ndarray:
    """The start ``state`` on ``rod``'s grid (barycentric interpolation of each field)."""
    old = state.rod
    if old.n == rod.n:
        w = np.array(state.w)
    else:
        disc_old = old.discretisation()
        full = np.asarray(disc_old.field.to_full) @ state.x.reshape(3, -1).T
        values = spectral.interpolation_matrix(old.n, np.asarray(
            rod.discretisation().field.nodes)) @ full
        x = values[1:rod.n].T.ravel()
        w = np.concatenate([x, state.w[3 * (old.n - 1):]])
    if rod.constraints == 2 and old.constraints == 3:
        # held at its height -> pulled by the tension that held it there: the same state
        w = np.concatenate([w[:3 * (rod.n - 1) + 2], w[-2:]])
    elif rod.constraints != old.constraints:
        raise ParameterError("start: a state under tension control cannot start a rod "
                             "under shortening control (give a state of the same rod)")
    return w


def twist_branch(rod: TwistedRod, to_turns: float, *, start: TwistState | None = None,
                 ds: float = 0.05, ds_max: float = 0.5, ds_min: float = 1e-6,
                 max_points: int = 400, max_folds: int = 10) -> TwistBranch:
    """Follow the equilibria of ``rod`` in the far end's turns from ``start`` (default: the
    Euler-buckled rod without turns, under shortening control) to ``to_turns``, through
    folds (module docstring). The arclength is measured by the RMS change of the unknowns
    plus the change of turns; ``ds``, ``ds_max``, ``ds_min`` bound its steps."""
    if not math.isfinite(to_turns):
        raise ParameterError(f"to_turns: a finite number, got {to_turns!r}")
    disc = rod.discretisation()
    w0 = _seed(rod, disc) if start is None else _regrid(rod, start)
    lo, hi = sorted((float(w0[-1]), float(to_turns)))
    control = StepControl(ds, ds_min, ds_max, 1.5, 1e-10, max_folds)
    out = _run_program(disc.size, rod.constraints, max_points, (disc, rod.inputs()),
                       jnp.asarray(w0), jnp.array([lo - 1e-12, hi + 1e-12]), control)
    num = int(out.num_points)
    # the whole fixed-capacity record (NaN beyond num): one measuring program per capacity
    W = np.column_stack([np.asarray(out.x), np.asarray(out.lam)])
    points = _states(rod, disc, W, np.ones(max_points, bool), np.asarray(out.residual_norm),
                     np.asarray(out.newton_iterations), np.asarray(out.morse_index))[:num]
    dturns = np.asarray(out.tangent_lam[:num])
    folds = [i for i in range(1, num) if dturns[i] * dturns[i - 1] < 0]
    status = int(out.status)
    return TwistBranch(rod, points, folds, status)


def twisted_equilibrium(rod: TwistedRod, turns: float, *, start: TwistState | None = None,
                        **options: Any) -> TwistState:
    """The equilibrium at ``turns`` reached from ``start`` (default: the Euler-buckled rod,
    under shortening control) by turning the far end (``twist_branch``; its ``options``),
    then solved there by Newton: the first point of the branch at ``turns``. With a
    ``start`` at the same turns (another degree n, say) Newton alone."""
    disc = rod.discretisation()
    if start is not None and abs(start.turns - turns) <= 1e-12:
        w = _regrid(rod, start)
    else:
        branch = twist_branch(rod, turns, start=start, **options)
        values = branch.column("turns")
        sign = np.sign(turns - values[0])
        past = np.nonzero(sign * (values - turns) >= 0)[0]
        if not len(past):
            raise _not_reached(branch, turns)
        i = int(past[0])
        a, b = branch.points[i - 1], branch.points[i]
        f = (turns - a.turns) / (b.turns - a.turns)
        w = (1 - f) * a.w + f * b.w
        w[-1] = turns
    res, eig = _solve_program(disc.size, rod.constraints, (disc, rod.inputs()),
                              jnp.asarray(w))
    full = np.append(np.asarray(res.x), turns)
    return _states(rod, disc, full, [res.converged], [res.residual_norm], [res.iterations],
                   [np.sum(np.asarray(eig) < 0)])[0]


def _not_reached(branch: TwistBranch, turns: float) -> Exception:
    from jaxrod.status import SolverError

    last = branch.points[-1].turns if branch.points else float("nan")
    return SolverError(f"turns: the branch stopped at {last:.6g} turns before {turns:.6g} "
                       f"({branch.message})")
