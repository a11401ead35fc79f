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
    INPUTS,
    MULTIPLIER_UNIT,
    TwistedRod,
    _load_key,
    density,
    endpoint,
    energy,
    far_end,
    orbit_direction,
    tip,
)


def _apply(keys: tuple, data, lam):
    """(turns, inputs, loads) at the path parameter lam: each input of ``keys`` at
    origin + span lam, the others at the base's values."""
    disc, (turns, inputs, loads), origin, span = data
    loads = dict(loads)
    for i, key in enumerate(keys):
        value = origin[i] + span[i] * lam
        if key == "turns":
            turns = value
        elif key in INPUTS:
            inputs = inputs.at[INPUTS.index(key)].set(value)
        else:
            name, field, *index = key.split(".")
            t = loads[name]
            if index:
                value = jnp.asarray(getattr(t, field)).at[int(index[0])].set(value)
            loads[name] = dataclasses.replace(t, **{field: value})
    return turns, inputs, loads


def _lagrangian(w, aux, data, keys: tuple, count: int):
    """Lambda (module docstring): its derivatives are assembled by ``_linearise``."""
    disc = data[0]
    x_ref, c, on = aux
    size = disc.size
    x, mu, nu, lam = w[:size], w[size:size + count], w[size + count], w[-1]
    turns, inputs, loads = _apply(keys, data, lam)
    return (energy(x, turns, disc, inputs, loads)
            + MULTIPLIER_UNIT * jnp.dot(mu, far_end(x, disc, inputs, count))
            + nu * jnp.dot(c, x - x_ref) + 0.5 * (1.0 - on) * nu * nu)


def _node_terms(w, data, keys: tuple, count: int):
    """What the assembly needs at w: the jets, the per-node Lagrangian density phi(a, s)
    (the energy density + U mu . d3[:count] + grad Psi(X) . d3, Psi the end terms'
    potential at the far end X) and Psi's Hessian there."""
    disc = data[0]
    size = disc.size
    x, mu, lam = w[:size], w[size:size + count], w[-1]
    turns, inputs, loads = _apply(keys, data, lam)
    jets = disc.jets(x, turns)
    X = tip(x, turns, disc)
    grad_X = jax.grad(endpoint)(X, loads)
    hess_X = jax.hessian(endpoint)(X, loads)

    def phi(a, s):
        d3 = frame(a[0], a[1], a[2])[:, 2]
        return (density(a, s, inputs, loads) + MULTIPLIER_UNIT * jnp.dot(mu, d3[:count])
                + jnp.dot(grad_X, d3))

    return jets, phi, hess_X, inputs


def _residual(w, aux, data, keys: tuple, count: int):
    """grad_z Lambda, z = (x, mu, nu), assembled from the nodes."""
    disc = data[0]
    x_ref, c, on = aux
    size = disc.size
    x, nu = w[:size], w[size + count]
    jets, phi, _, inputs = _node_terms(w, data, keys, count)
    q = disc.field.quad_weights
    grad_a = jax.vmap(jax.grad(phi))(jets, disc.quad_nodes)
    d3 = jax.vmap(lambda a: frame(a[0], a[1], a[2])[:count, 2])(jets)
    held = jnp.zeros(count).at[2].set(1.0 - inputs[3]) if count == 3 else jnp.zeros(count)
    r_x = jnp.einsum("jrm,jr->m", disc.jet_matrix * q[:, None, None], grad_a) + nu * c
    r_mu = MULTIPLIER_UNIT * (q @ d3 - held)
    r_nu = jnp.dot(c, x - x_ref) + (1.0 - on) * nu
    return jnp.concatenate([r_x, r_mu, r_nu[None]])


def _linearise(w, aux, data, keys: tuple, count: int):
    """(grad_z Lambda, [Hess_z Lambda | d grad_z Lambda / d lam]) assembled from the
    nodes: Lambda = sum_j q_j phi(a_j) + Psi(X) - U mu_z (1 - e) + nu c . (x - x_ref),
    the jets a_j = L_j x + l_j turns; the Hessian is sum_j q_j L_j^T phi_aa L_j + D^T
    Psi_XX D (D = dX/dx), bordered by the constraints' gradients and c; the column is the
    residual's derivative along the path (forward mode). The same numbers as autodiff of
    ``_lagrangian``, without its cost."""
    disc = data[0]
    _, c, on = aux
    L, q = disc.jet_matrix, disc.field.quad_weights
    jets, phi, hess_X, _ = _node_terms(w, data, keys, count)
    hess_a = jax.vmap(jax.hessian(phi))(jets, disc.quad_nodes)
    d3_a = jax.vmap(jax.jacfwd(lambda a: frame(a[0], a[1], a[2])[:, 2]))(jets)
    Lq = L * q[:, None, None]
    D = jnp.einsum("jrm,jkr->km", Lq, d3_a)
    H_xx = jnp.einsum("jrm,jrs,jsn->mn", Lq, hess_a, L) + D.T @ hess_X @ D
    H_xmu = MULTIPLIER_UNIT * D[:count].T
    R, column = jax.jvp(lambda lam: _residual(w.at[-1].set(lam), aux, data, keys, count),
                        (w[-1],), (jnp.ones_like(w[-1]),))
    top = jnp.hstack([H_xx, H_xmu, c[:, None]])
    middle = jnp.hstack([H_xmu.T, jnp.zeros((count, count + 1))])
    bottom = jnp.concatenate([c, jnp.zeros(count), (1.0 - on)[None]])[None, :]
    return R, jnp.hstack([jnp.vstack([top, middle, bottom]), column[:, None]])


def _phase(x, disc, phase: bool):
    """(x_ref, c, on): the phase condition's reference and unit direction, ``on`` = 1 where
    the symmetry's orbit is a circle (a symmetric rod, bent); else c = 0 and the phase
    multiplier is pinned to 0."""
    c = orbit_direction(x, disc)
    norm = jnp.sqrt(jnp.dot(c, c))
    on = jnp.where(phase & (norm > 1e-10), 1.0, 0.0)
    return x, jnp.where(on > 0, c / jnp.where(norm > 0, norm, 1.0), 0.0), on


@dataclasses.dataclass(frozen=True)
class _TwistSystem:
    """The stationarity of Lambda (module docstring) as a curve system of
    ``jaxrod.solvers.arclength``; built inside the traced run, holding its data. After each
    accepted point the phase reference moves there and the Jacobian is formed again with
    the new phase direction (for the tangent)."""

    size: int
    count: int
    keys: tuple
    phase: bool
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
        return _linearise(w, aux, data, self.keys, self.count)

    def accepted(self, w, aux, J):
        new = _phase(w[:self.size], self.data[0], self.phase)
        return new, self.linearise(w, new, self.data)[1]

    def record(self, out, k, w, t, J, res):
        return _record(out, k, w, t, J[:, :self.m], res.iterations, res.residual_norm, True)

    def event(self, w, t, t_old, J, out, k_old):
        return t[-1] * t_old[-1] < 0

    def outside(self, w, bounds):
        return (w[-1] > bounds[1]) | (w[-1] < bounds[0])


def _run(size: int, count: int, keys: tuple, phase: bool, capacity: int, data, w0, orient,
         bounds, control):
    system = _TwistSystem(size, count, keys, phase, data)
    out = empty_branch(capacity, system.m)
    out, num, status, rejected = arclength_run(system, data, w0, orient,
                                               _phase(w0[:size], data[0], phase), out,
                                               control, bounds, capacity, FOLDS_FOUND)
    return out._replace(num_points=num, status=status, rejected_steps=rejected)


_run_program = jit(_run, static_argnums=(0, 1, 2, 3, 4))


def _solve_at(size: int, count: int, keys: tuple, phase: bool, data, w0):
    """Newton on the stationarity at w0's path parameter, the phase at w0; the bordered
    Hessian's eigenvalues and eigenvectors at the solution."""
    aux = _phase(w0[:size], data[0], phase)
    m = size + count + 1

    def linearise(z, _):
        R, J = _linearise(jnp.append(z, w0[-1]), aux, data, keys, count)
        return R, J[:, :m]

    res = newton(None, w0[:m], None, tol=1e-10, linearise=linearise, keep_jacobian=True,
                 max_steps=60)
    eig, vec = jnp.linalg.eigh(0.5 * (res.jacobian + res.jacobian.T))
    return res, eig, vec, _phase(res.x[:size], data[0], phase)[2]


_solve_program = jit(_solve_at, static_argnums=(0, 1, 2, 3))


@dataclasses.dataclass(frozen=True)
class _Path:
    """A straight path through the rod's inputs: each of ``keys`` at origin + span lam."""

    keys: tuple
    origin: tuple
    span: tuple

    def data(self, rod: TwistedRod, turns: float, disc):
        return (disc, (jnp.asarray(float(turns)), rod.inputs(), rod.loads),
                jnp.asarray(self.origin, float), jnp.asarray(self.span, float))

    def rod_at(self, rod: TwistedRod, lam: float) -> tuple[float | None, TwistedRod]:
        """(turns or None, the rod) at lam, host side."""
        turns = None
        for key, o, s in zip(self.keys, self.origin, self.span):
            value = o + s * lam
            if key == "turns":
                turns = value
            else:
                rod = rod.replace(key, value)
        return turns, rod

    def lam(self, value: float) -> float:
        return (value - self.origin[0]) / self.span[0]


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
    value: float = float("nan")

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


def _twist_measures(x, lam, keys: tuple, data):
    """(twist moment, Tw, Wr, turns, tension under tension control) of one state."""
    turns, inputs, loads = _apply(keys, data, lam)
    disc = data[0]
    moment = jax.grad(energy, argnums=1)(x, turns, disc, inputs, loads) / (2.0 * math.pi)
    return (moment, *twist_and_writhe(disc, x, turns), turns, inputs[2])


_measures_program = jit(jax.vmap(_twist_measures, in_axes=(0, 0, None, None)),
                        static_argnums=(2,))


def _states(rod: TwistedRod, path: _Path, data, W, converged, residual, iterations,
            index) -> list[TwistState]:
    """The records of the states W (one per row: x, mu, nu, lam) with Newton's report and
    the bordered Hessian's negative count ``index`` (less the bordering rows' k + 1 or k:
    the phase multiplier's row counts where the orbit is a circle)."""
    W = np.atleast_2d(np.asarray(W))
    disc = data[0]
    size = disc.size
    moment, tw, wr, turns, pull = (np.asarray(a) for a in _measures_program(
        jnp.asarray(W[:, :size]), jnp.asarray(W[:, -1]), path.keys, data))
    tension = pull if rod.constraints == 2 else -MULTIPLIER_UNIT * W[:, size + 2]
    fields = np.asarray(disc.field.to_full) @ W[:, :size].reshape(len(W), 3, disc.free) \
        .transpose(0, 2, 1)
    tail = np.abs(np.einsum("kj,pjf->pkf", spectral.values_to_coefficients_matrix(rod.n),
                            fields)[:, -2:]).max(axis=(1, 2))
    orbit = np.linalg.norm(np.concatenate([W[:, :disc.free], W[:, disc.free:2 * disc.free]],
                                          axis=1), axis=1) > 1e-10
    bordering = rod.constraints + (orbit & rod.symmetric)
    states = []
    for i in range(len(W)):
        lam = float(W[i, -1])
        _, at = path.rod_at(rod, lam) if np.isfinite(lam) else (None, rod)
        states.append(TwistState(
            at, W[i], float(turns[i]), float(moment[i]), float(tension[i]), float(tw[i]),
            float(wr[i]), int(index[i]) - int(bordering[i]), bool(converged[i]),
            float(residual[i]), int(iterations[i]), float(tail[i]),
            path.origin[0] + path.span[0] * lam))
    return states


@dataclasses.dataclass(frozen=True)
class TwistBranchPoint:
    """Where a branch's count of unstable directions changes without a fold: ``state``
    (refined: the point where the bordered Hessian's eigenvalue crosses zero), ``unstable``
    (the count before and after; a jump of 2 at a straight rod: the rotational symmetry's
    two-dimensional kernel), ``converged`` (the refinement's report), ``kernel`` (the
    x part of the crossing eigenvector, for ``switch_branch``)."""

    state: TwistState
    unstable: tuple[int, int]
    converged: bool
    kernel: np.ndarray
    path: _Path

    @property
    def value(self) -> float:
        return self.state.value

    def as_dict(self) -> dict:
        return {"value": self.value, **self.state.as_dict(), "unstable": list(self.unstable),
                "kernel_dimension": abs(self.unstable[1] - self.unstable[0]),
                "converged": self.converged}


@dataclasses.dataclass(frozen=True)
class TwistBranch:
    """A branch of a twisted rod along one of its inputs (``vary``; the end rotation in
    turns by default): ``points`` (TwistState, in order), ``folds`` (the indices where the
    input's direction along the branch changes sign: the point after the turn, located to
    the step, not refined), ``branch_points`` (TwistBranchPoint, refined), ``status`` and
    its message."""

    rod: TwistedRod
    points: list[TwistState]
    folds: list[int]
    status: int
    vary: str = "turns"
    branch_points: list = dataclasses.field(default_factory=list)

    @property
    def message(self) -> str:
        return STATUS_MESSAGES.get(self.status, Status(self.status).message)

    @property
    def complete(self) -> bool:
        from jaxrod.solvers.continuation import REACHED_BOUND

        return self.status == int(REACHED_BOUND)

    def column(self, name: str) -> np.ndarray:
        return np.array([getattr(p, name) for p in self.points])


def _seed(rod: TwistedRod, disc: FramedDiscretisation, turns: float, lam: float
          ) -> np.ndarray:
    """The start w = (x, mu, nu, lam) of a rod without one: under shortening control its
    first Euler mode, v1 = 2 sqrt(e) sin(2 pi s) (height 1 - e to first order), thrust
    4 pi^2; under tension control the straight rod."""
    x = np.zeros(disc.size)
    if rod.shortening is None:
        return np.concatenate([x, [0.0, 0.0, 0.0, lam]])
    nodes = np.asarray(disc.field.nodes)[1:rod.n]
    x[:disc.free] = 2.0 * math.sqrt(rod.shortening) * np.sin(2.0 * math.pi * nodes)
    return np.concatenate([x, [0.0, 0.0, 1.0, 0.0, lam]])


def _regrid(rod: TwistedRod, state: TwistState, lam: float) -> np.ndarray:
    """The start ``state`` on ``rod``'s grid (barycentric interpolation of each field), its
    path parameter ``lam``."""
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
    w[-1] = lam
    return w


def _path(rod: TwistedRod, vary: str, turns: float, to: float) -> _Path:
    """The path of ``vary`` from its value on ``rod`` (or ``turns``) to ``to``: lam is the
    turns themselves, or another input scaled to lam in [0, 1]."""
    if vary == "turns":
        return _Path(("turns",), (0.0,), (1.0,))
    if vary in INPUTS:
        value = getattr(rod, vary)
        if value is None:
            raise ParameterError(f"vary: {vary} is not this rod's control (it has "
                                 f"{rod.control})")
    else:
        name, field, index = _load_key(rod, vary)
        value = np.asarray(getattr(rod.loads[name], field))
        value = float(value if index is None else value[index])
    if to == value:
        raise ParameterError(f"to: must differ from {vary}'s value on the rod ({value:g})")
    return _Path((vary,), (float(value),), (float(to) - float(value),))


def _follow(rod: TwistedRod, path: _Path, turns: float, w0, lam_to: float, orient,
            ds, ds_max, ds_min, max_points, max_folds, vary: str) -> TwistBranch:
    disc = rod.discretisation()
    data = path.data(rod, turns, disc)
    lo, hi = sorted((float(w0[-1]), float(lam_to)))
    control = StepControl(ds, ds_min, ds_max, 1.5, 1e-10, max_folds)
    out = _run_program(disc.size, rod.constraints, path.keys, rod.symmetric, max_points,
                       data, jnp.asarray(w0), jnp.asarray(orient),
                       jnp.array([lo - 1e-12, hi + 1e-12]), control)
    num = int(out.num_points)
    # the whole fixed-capacity record (NaN beyond num): one measuring program per capacity
    W = np.column_stack([np.asarray(out.x), np.asarray(out.lam)])
    index = np.asarray(out.morse_index)
    points = _states(rod, path, data, W, np.ones(max_points, bool),
                     np.asarray(out.residual_norm), np.asarray(out.newton_iterations),
                     index)[:num]
    dlam = np.asarray(out.tangent_lam[:num])
    folds = [i for i in range(1, num) if dlam[i] * dlam[i - 1] < 0]
    found = [_refine(rod, path, data, points[i - 1], points[i]) for i in range(1, num)
             if points[i].unstable != points[i - 1].unstable and i not in folds
             and points[i].converged and points[i - 1].converged]
    return TwistBranch(rod, points, folds, int(out.status), vary, found)


def _refine(rod: TwistedRod, path: _Path, data, a: TwistState, b: TwistState
            ) -> TwistBranchPoint:
    """The branch point between the neighbours a and b: the path parameter where the
    bordered Hessian's eigenvalue number q (q = a's negative count, a the side with fewer)
    crosses zero, by the Illinois variant of false position on Newton's states at fixed
    lam (from the chord between a and b)."""
    disc = data[0]
    lo, hi = (a, b) if a.unstable < b.unstable else (b, a)
    bordering = rod.constraints + int(rod.symmetric and np.linalg.norm(
        lo.w[:2 * disc.free]) > 1e-10)
    q = lo.unstable + bordering

    def at(lam):
        f = (lam - a.w[-1]) / (b.w[-1] - a.w[-1])
        w = (1 - f) * a.w + f * b.w
        w[-1] = lam
        res, eig, vec, _ = _solve_program(disc.size, rod.constraints, path.keys,
                                          rod.symmetric, data, jnp.asarray(w))
        return res, float(eig[q]), np.asarray(vec[:, q]), lam

    (_, ga, _, la), (_, gb, _, lb) = at(lo.w[-1]), at(hi.w[-1])
    best = None
    side = 0
    for _ in range(60):
        lam = (la * gb - lb * ga) / (gb - ga)
        res, g, vec, _ = at(lam)
        best = (res, g, vec, lam)
        if abs(g) <= 1e-12 or abs(lb - la) <= 1e-13 * max(1.0, abs(lam)):
            break
        if g * ga > 0:
            la, ga = lam, g
            gb = gb * 0.5 if side == -1 else gb
            side = -1
        else:
            lb, gb = lam, g
            ga = ga * 0.5 if side == 1 else ga
            side = 1
    res, g, vec, lam = best
    eig_count = np.sum(np.asarray(_solve_program(
        disc.size, rod.constraints, path.keys, rod.symmetric, data,
        jnp.asarray(np.append(np.asarray(res.x), lam)))[1]) < 0)
    state = _states(rod, path, data, np.append(np.asarray(res.x), lam)[None], [res.converged],
                    [res.residual_norm], [res.iterations], [eig_count])[0]
    converged = bool(res.converged) and abs(g) <= 1e-8
    return TwistBranchPoint(state, (a.unstable, b.unstable), converged, vec[:disc.size],
                            path)


def twist_branch(rod: TwistedRod, to: float, *, vary: str = "turns",
                 start: TwistState | None = None, turns: float | None = None,
                 ds: float = 0.05, ds_max: float = 0.5, ds_min: float = 1e-6,
                 max_points: int = 400, max_folds: int = 10) -> TwistBranch:
    """Follow the equilibria of ``rod`` along ``vary`` (the far end's turns, or an input of
    the rod: "tension" or "shortening" (its control), "twist_ratio", "bending_ratio", or a
    load's "term.field[.i]") from ``start`` to ``to``, through folds (module docstring);
    the other inputs are the rod's, the turns ``turns`` (default: the start's, or 0).
    Without a start: under shortening control the Euler-buckled rod, under tension control
    the straight rod. The arclength is measured by the RMS change of the unknowns plus the
    change of lam (the turns, or the input scaled to [0, 1]); ``ds``, ``ds_max``,
    ``ds_min`` bound its steps. The count of unstable directions is read at every point;
    where it changes without a fold the branch point is refined (``branch_points``)."""
    if not math.isfinite(to):
        raise ParameterError(f"to: a finite number, got {to!r}")
    turns = (start.turns if start is not None else 0.0) if turns is None else float(turns)
    path = _path(rod, vary, turns, to)
    disc = rod.discretisation()
    lam0 = turns if vary == "turns" else 0.0
    w0 = _seed(rod, disc, turns, lam0) if start is None else _regrid(rod, start, lam0)
    lam_to = path.lam(to)
    orient = np.zeros(len(w0))
    orient[-1] = 1.0 if lam_to > lam0 else -1.0
    return _follow(rod, path, turns, w0, lam_to, orient, ds, ds_max, ds_min, max_points,
                   max_folds, vary)


def switch_branch(point: TwistBranchPoint, to: float, *, amplitude: float = 0.02,
                  ds: float = 0.05, ds_max: float = 0.5, ds_min: float = 1e-6,
                  max_points: int = 400, max_folds: int = 10) -> TwistBranch:
    """The branch that leaves ``point`` along its kernel: started at the branch point's
    state displaced by ``amplitude`` (RMS of the fields, radians) along the crossing
    eigenvector, its first point solved in the hyperplane through there normal to that
    direction (any one of the kernel's directions, where the symmetry makes it a circle),
    then followed toward ``to`` (in the branch's input) as ``twist_branch`` does."""
    state, path = point.state, point.path
    rod = state.rod
    base_rod = path.rod_at(rod, -path.origin[0] / path.span[0])[1] if path.keys[0] != "turns" \
        else rod
    phi = point.kernel / np.sqrt(np.mean(point.kernel ** 2))
    w0 = np.array(state.w)
    w0[:len(phi)] += amplitude * phi
    orient = np.zeros(len(w0))
    orient[:len(phi)] = phi
    lam_to = path.lam(to)
    return _follow(base_rod if path.keys[0] != "turns" else rod, path, state.turns, w0,
                   lam_to, orient, ds, ds_max, ds_min, max_points, max_folds, path.keys[0])


def twisted_equilibrium(rod: TwistedRod, turns: float, *, start: TwistState | None = None,
                        **options: Any) -> TwistState:
    """The equilibrium at ``turns``. Without ``start``: under shortening control the one
    reached by turning the far end while it approaches (turns and shortening raised
    together from 5% of theirs, from the Euler-buckled rod: how PyElastica loads its
    helical buckling case); under tension control by turning the straight rod. With a
    ``start``, by turning its far end from there (``twist_branch``; its ``options``), or at
    the same turns (another n, say) by Newton alone."""
    if not math.isfinite(turns):
        raise ParameterError(f"turns: a finite number, got {turns!r}")
    disc = rod.discretisation()
    if start is not None and abs(start.turns - turns) <= 1e-12:
        path = _Path(("turns",), (0.0,), (1.0,))
        w = _regrid(rod, start, turns)
        lam = turns
    else:
        if start is None and rod.shortening is not None:
            first = 0.05
            path = _Path(("turns", "shortening"), (0.0, 0.0), (float(turns), rod.shortening))
            seed = dataclasses.replace(rod, shortening=first * rod.shortening)
            w0 = _seed(seed, disc, first * turns, first)
            orient = np.zeros(len(w0))
            orient[-1] = 1.0
            branch = _follow(rod, path, 0.0, w0, 1.0, orient, options.get("ds", 0.05),
                             options.get("ds_max", 0.5), options.get("ds_min", 1e-6),
                             options.get("max_points", 400), options.get("max_folds", 10),
                             "approach")
            lam = 1.0
        else:
            branch = twist_branch(rod, turns, start=start, **options)
            path = _Path(("turns",), (0.0,), (1.0,))
            lam = turns
        values = np.array([p.w[-1] for p in branch.points])
        sign = np.sign(lam - values[0])
        past = np.nonzero(sign * (values - lam) >= 0)[0]
        if not len(past):
            raise _not_reached(branch, turns)
        i = int(past[0])
        a, b = branch.points[i - 1], branch.points[i]
        f = (lam - a.w[-1]) / (b.w[-1] - a.w[-1])
        w = (1 - f) * a.w + f * b.w
        w[-1] = lam
    data = path.data(rod, turns, disc)
    res, eig, _, _ = _solve_program(disc.size, rod.constraints, path.keys, rod.symmetric,
                                    data, jnp.asarray(w))
    full = np.append(np.asarray(res.x), lam)
    return _states(rod, path, data, full, [res.converged], [res.residual_norm],
                   [res.iterations], [np.sum(np.asarray(eig) < 0)])[0]


def _not_reached(branch: TwistBranch, turns: float) -> Exception:
    from jaxrod.status import SolverError

    last = branch.points[-1].turns if branch.points else float("nan")
    return SolverError(f"turns: the branch stopped at {last:.6g} turns before {turns:.6g} "
                       f"({branch.message})")
