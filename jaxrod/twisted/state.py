"""One equilibrium of a twisted rod and its report: the end reactions, twist and writhe, the
count of unstable directions, Newton's report and the resolution."""

from __future__ import annotations

import dataclasses
import math

import jax
import jax.numpy as jnp
import numpy as np

from jaxrod import spectral
from jaxrod.discretise.framed import twist_and_writhe
from jaxrod.equilibria.resolution import TOLERANCE
from jaxrod.programs import jit
from jaxrod.status import Status
from jaxrod.twisted.equations import FLOOR_TOL, _apply, _Path
from jaxrod.twisted.rod import (
    CONTACT_KEY,
    MULTIPLIER_UNIT,
    TwistedRod,
    centre_of_bending,
    energy,
)
from jaxrod.twisted.self_contact import self_distance


@dataclasses.dataclass(frozen=True)
class TwistState:
    """One equilibrium of a twisted rod (``twisted_equilibrium`` or a branch's point).

    turns: the far end's rotation; twist_moment: M L / B1 about the axis at the far end;
    tension: T L^2 / B1 there; twist, writhe: Tw and Wr (their sum is ``turns``, the
    linking number); unstable: how many directions lower the energy (0: stable);
    converged, residual, iterations: Newton's report; tail: the largest of the three
    fields' last two Chebyshev coefficients (the resolution: small against the fields);
    path_tail: for ``twisted_equilibrium``, the largest tail along the path that reached it
    (0 for Newton alone; above ``TOLERANCE`` the path was under-resolved and may have
    reached another equilibrium than a resolved path would)."""

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
    path_tail: float = float("nan")
    self_distance: float = float("nan")

    @property
    def x(self) -> np.ndarray:
        return self.w[:3 * self.rod.free_values]

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

    def tip_position(self) -> np.ndarray:
        """X = int_0^1 d3 ds, by the energy's quadrature (rod lengths)."""
        from jaxrod.twisted.rod import tip

        return np.asarray(tip(jnp.asarray(self.x), self.turns, self.rod.discretisation()))

    def tip_tangent(self) -> np.ndarray:
        """d3 at s = 1."""
        from jaxrod.discretise.framed import frame

        field = self.rod.discretisation().field
        v = np.asarray(field.to_full)[-1] @ self.x.reshape(3, -1).T
        return np.asarray(frame(*v)[:, 2])

    def as_dict(self) -> dict:
        return {"turns": self.turns, "twist_moment": self.twist_moment,
                "tension": self.tension, "twist": self.twist, "writhe": self.writhe,
                "unstable": self.unstable, "converged": self.converged,
                "residual": self.residual, "iterations": self.iterations,
                "chebyshev_tail": self.tail, "n": self.rod.n,
                "status": self.status.name.lower(),
                **({} if math.isnan(self.self_distance) else
                   {"self_distance": self.self_distance})}


def _twist_measures(x, lam, keys: tuple, data):
    """(twist moment, Tw, Wr, turns, tension under tension control, the centring's force
    on the state: the largest entry of sigma H dH/dx, the self-distance or NaN) of one
    state."""
    turns, inputs, loads = _apply(keys, data, lam)
    disc = data[0]
    moment = jax.grad(energy, argnums=1)(x, turns, disc, inputs, loads) / (2.0 * math.pi)
    H, G = jax.value_and_grad(centre_of_bending)(x, turns, disc)
    contact = loads.get(CONTACT_KEY)
    apart = jnp.nan if contact is None else self_distance(x, contact)
    return (moment, *twist_and_writhe(disc, x, turns), turns, inputs[2],
            jnp.abs(inputs[5] * H) * jnp.max(jnp.abs(G)), apart)


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
    moment, tw, wr, turns, pull, held, apart = (np.asarray(a) for a in _measures_program(
        jnp.asarray(W[:, :size]), jnp.asarray(W[:, -1]), path.keys, data))
    # a state the centring or the phase condition holds away from the rod's own
    # equilibrium (their forces sigma H dH/dx and nu c, c a unit vector) is not one of them
    off = np.maximum(held, np.abs(W[:, size + rod.constraints]))
    residual = np.maximum(np.asarray(residual, float), off)
    converged = np.asarray(converged, bool) & (off <= FLOOR_TOL)
    tension = -MULTIPLIER_UNIT * W[:, size + 2] if rod.constraints == 3 else pull
    fields = np.asarray(disc.field.to_full) @ W[:, :size].reshape(len(W), 3, disc.free) \
        .transpose(0, 2, 1)
    tail = np.abs(np.einsum("kj,pjf->pkf", spectral.values_to_coefficients_matrix(rod.n),
                            fields)[:, -2:]).max(axis=(1, 2))
    orbit = np.linalg.norm(np.concatenate([W[:, :disc.free], W[:, disc.free:2 * disc.free]],
                                          axis=1), axis=1) > 1e-10
    bordering = rod.constraints + (orbit & path.phase(rod))
    states = []
    for i in range(len(W)):
        lam = float(W[i, -1])
        _, at = path.rod_at(rod, lam) if np.isfinite(lam) else (None, rod)
        states.append(TwistState(
            at, W[i], float(turns[i]), float(moment[i]), float(tension[i]), float(tw[i]),
            float(wr[i]), int(index[i]) - int(bordering[i]), bool(converged[i]),
            float(residual[i]), int(iterations[i]), float(tail[i]),
            path.origin[0] + path.span[0] * lam, self_distance=float(apart[i])))
    return states


