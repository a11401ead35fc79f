"""The equations of a twisted rod's equilibria along a path through its inputs, and their
compiled programs.

Unknowns w = (x, mu, nu, lam): the fields, the far end's multipliers (in units of
``MULTIPLIER_UNIT``), the phase multiplier and the path parameter (``_Path``: each varied
input at origin + span lam; the turns by default, lam = turns). The equations are the
stationarity of

    Lambda = E(x; lam) + U mu . g(x) + nu c . (x - x_ref),

c = ``orbit_direction(x_ref)`` / |.|, x_ref the last accepted point: the phase condition
that picks one of the circle of equilibria a symmetric rod's bent states make (at a
solution nu = 0, since both E and g are invariant). Where the orbit is no circle (the
straight rod, or loads that break the symmetry) c = 0 and nu is pinned to 0 instead. The
Hessian in z = (x, mu, nu) is a bordered matrix whose inertia is that of the second
variation on the constraints' tangent space plus (k + 1, k + 1, 0) (Haynsworth; k + 1
bordering rows of full rank; k and one positive where nu is pinned): the count of the
equilibrium's unstable directions is its number of negative eigenvalues minus k + 1 (or k).

The branch is followed by the pseudo-arclength driver (``jaxrod.solvers.arclength``): one
``lax.while_loop``, compiled once per (degree, control, path keys, symmetry); a fold is a
sign change of d(lam)/ds.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import jax
import jax.numpy as jnp

from jaxrod.discretise.framed import frame
from jaxrod.programs import jit
from jaxrod.solvers.arclength import arclength_run
from jaxrod.solvers.continuation import FOLDS_FOUND, _record, empty_branch
from jaxrod.solvers.newton import newton
from jaxrod.twisted.distributed import POSITIONS_KEY, distributed_energy
from jaxrod.twisted.rod import (
    CONTACT_KEY,
    INPUTS,
    MULTIPLIER_UNIT,
    TwistedRod,
    centre_of_bending,
    density,
    endpoint,
    energy,
    far_end,
    orbit_direction,
    tip,
)
from jaxrod.twisted.self_contact import contact_energy, contact_terms


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
    grad_X = jax.grad(endpoint)(X, inputs, loads)
    hess_X = jax.hessian(endpoint)(X, inputs, loads)
    pull = inputs[5] * centre_of_bending(x, turns, disc)  # the centring's dE/dH

    def phi(a, s):
        d3 = frame(a[0], a[1], a[2])[:, 2]
        return (density(a, s, inputs, loads) + MULTIPLIER_UNIT * jnp.dot(mu, d3[:count])
                + jnp.dot(grad_X, d3) + pull * (s - 0.5) * (a[0] ** 2 + a[1] ** 2))

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
    contact = data[1][2].get(CONTACT_KEY)
    if contact is not None:
        r_x = r_x + jax.grad(contact_energy)(x, contact)
    if POSITIONS_KEY in data[1][2]:
        turns, _, loads = _apply(keys, data, w[-1])
        r_x = r_x + jax.grad(distributed_energy)(x, turns, disc, inputs, loads)
    r_mu = MULTIPLIER_UNIT * (q @ d3 - held)
    r_nu = jnp.dot(c, x - x_ref) + (1.0 - on) * nu
    return jnp.concatenate([r_x, r_mu, r_nu[None]])


def _linearise(w, aux, data, keys: tuple, count: int):
    """(grad_z Lambda, [Hess_z Lambda | d grad_z Lambda / d lam]) assembled from the
    nodes: Lambda = sum_j q_j phi(a_j) + Psi(X) - U mu_z (1 - e) + nu c . (x - x_ref),
    the jets a_j = L_j x + l_j turns; the Hessian is sum_j q_j L_j^T phi_aa L_j + D^T
    Psi_XX D (D = dX/dx) + sigma G G^T (the centring, G = dH/dx: ``TwistedRod.centred``)
    + the self-contact's (``jaxrod.twisted.self_contact.contact_terms``) + the Hessian of
    the loads that act on the positions along the rod (autodiff,
    ``jaxrod.twisted.distributed``), bordered by the constraints' gradients and c; the
    column is the residual's derivative along the path (forward mode). The same numbers
    as autodiff of ``_lagrangian``, without its cost."""
    disc = data[0]
    _, c, on = aux
    L, q = disc.jet_matrix, disc.field.quad_weights
    jets, phi, hess_X, inputs = _node_terms(w, data, keys, count)
    hess_a = jax.vmap(jax.hessian(phi))(jets, disc.quad_nodes)
    d3_a = jax.vmap(jax.jacfwd(lambda a: frame(a[0], a[1], a[2])[:, 2]))(jets)
    Lq = L * q[:, None, None]
    D = jnp.einsum("jrm,jkr->km", Lq, d3_a)
    turns = _apply(keys, data, w[-1])[0]
    G = jax.grad(centre_of_bending)(w[:disc.size], turns, disc)
    H_xx = (jnp.einsum("jrm,jrs,jsn->mn", Lq, hess_a, L) + D.T @ hess_X @ D
            + inputs[5] * jnp.outer(G, G))
    contact = data[1][2].get(CONTACT_KEY)
    if contact is not None:
        H_xx = H_xx + contact_terms(w[:disc.size], contact, disc.size)[1]
    if POSITIONS_KEY in data[1][2]:
        loads = _apply(keys, data, w[-1])[2]
        H_xx = H_xx + jax.hessian(distributed_energy)(w[:disc.size], turns, disc, inputs,
                                                      loads)
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


#: A residual that no step length reduces counts as converged at or below this, the
#: continuation corrector's own tolerance: a localised state's slide along the rod is a
#: nearly singular direction (its eigenvalue falls like exp(-k)), where the residual's
#: round-off floor (about 1e-11 at t = 3000) makes Newton's step large but no better.
FLOOR_TOL = 1e-10


def _solve_at(size: int, count: int, keys: tuple, phase: bool, data, w0):
    """Newton on the stationarity at w0's path parameter, the phase at w0; the bordered
    Hessian's eigenvalues and eigenvectors at the solution."""
    aux = _phase(w0[:size], data[0], phase)
    m = size + count + 1

    def linearise(z, _):
        R, J = _linearise(jnp.append(z, w0[-1]), aux, data, keys, count)
        return R, J[:, :m]

    res = newton(None, w0[:m], None, linearise=linearise, keep_jacobian=True,
                 max_steps=60, floor_tol=FLOOR_TOL)
    eig, vec = jnp.linalg.eigh(0.5 * (res.jacobian + res.jacobian.T))
    return res, eig, vec, _phase(res.x[:size], data[0], phase)[2]


_solve_program = jit(_solve_at, static_argnums=(0, 1, 2, 3))


#: A load's inputs that scale it without turning it (``_Path.phase``).
_STRENGTHS = ("load", "A", "G", "M")


@dataclasses.dataclass(frozen=True)
class _Path:
    """A straight path through the rod's inputs: each of ``keys`` at origin + span lam."""

    keys: tuple
    origin: tuple
    span: tuple

    def data(self, rod: TwistedRod, turns: float, disc):
        return (disc, (jnp.asarray(float(turns)), rod.inputs(), rod.program_loads()),
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

    def phase(self, rod: TwistedRod) -> bool:
        """Whether the phase condition is on along the whole path: a symmetric rod
        (``TwistedRod.symmetric``) and a path that keeps it (the turns, the end's control,
        the twist ratio, the load scale, a load's strength or a taper's coefficients; a
        field's angle or the bending ratio would break it part way, where a phase
        condition would force states that are no equilibria)."""
        keeps = ("turns", "tension", "shortening", "twist_ratio", "load_scale")
        return rod.symmetric and all(
            k in keeps or (k.count(".") == 1 and k.split(".")[1] in _STRENGTHS)
            or getattr(rod.loads.get(k.split(".")[0]), "elastic", False)
            for k in self.keys)


