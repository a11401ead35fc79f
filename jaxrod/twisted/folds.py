"""Folds of a twisted rod's branch: where the path parameter lam turns back.

Near a fold the branch is a smooth curve in (z, lam) and lam is extremal along it. The
points of the curve on the hyperplanes normal to the chord between the two points that
bracket the turn, <W chord, w - (w_a + sigma chord)> = 0 (the continuation's own corrector),
are a smooth family in sigma; at the fold the curve's unit tangent there has no component
in lam. That component changes sign between the two points and is driven to zero by the
Illinois variant of false position in sigma: the fold to the corrector's tolerance, without
the third derivatives that an extended system would need.
"""

from __future__ import annotations

import dataclasses

import jax.numpy as jnp
import numpy as np

from jaxrod.programs import jit
from jaxrod.solvers.arclength import _corrector, unit_tangent
from jaxrod.solvers.newton import newton
from jaxrod.twisted.branch_points import illinois
from jaxrod.twisted.equations import FLOOR_TOL, _Path, _phase, _solve_program, _TwistSystem
from jaxrod.twisted.rod import TwistedRod
from jaxrod.twisted.state import TwistState, _states


def _on_plane(size: int, count: int, keys: tuple, phase: bool, data, w_pred, normal):
    """The curve's point on the hyperplane through w_pred normal to ``normal``, and the
    lam component of its unit tangent (oriented along ``normal``)."""
    system = _TwistSystem(size, count, keys, phase, data)
    aux = _phase(w_pred[:size], data[0], phase)
    res = newton(None, w_pred, (system, w_pred, normal, aux, data), linearise=_corrector,
                 keep_jacobian=True, max_steps=60, floor_tol=FLOOR_TOL)
    t = unit_tangent(system, res.jacobian[:-1], normal)
    return res, t[-1]


_plane_program = jit(_on_plane, static_argnums=(0, 1, 2, 3))


@dataclasses.dataclass(frozen=True)
class TwistFold:
    """A refined fold: ``state`` (its ``value`` the varied input there) and ``converged``
    (the refinement's report: the tangent's lam component below 1e-9 at a converged
    point)."""

    state: TwistState
    converged: bool

    @property
    def value(self) -> float:
        return self.state.value


def refine_fold(rod: TwistedRod, path: _Path, data, a: TwistState, b: TwistState
                ) -> TwistFold:
    """The fold between the branch's neighbours a and b (module docstring)."""
    disc = data[0]
    size, count = disc.size, rod.constraints
    system = _TwistSystem(size, count, path.keys, path.phase(rod), data)
    chord = np.asarray(b.w) - np.asarray(a.w)
    normal = chord / np.sqrt(float(system.inner(chord, chord)))
    found = {}

    def at(sigma):
        res, t_lam = _plane_program(size, count, path.keys, path.phase(rod), data,
                                    jnp.asarray(a.w + sigma * chord), jnp.asarray(normal))
        found[sigma] = res
        return float(t_lam)

    sigma, g = illinois(at, 0.0, 1.0, ftol=1e-12, xtol=1e-14)
    res = found[sigma]
    w = np.asarray(res.x)
    _, eig, _, _ = _solve_program(size, count, path.keys, path.phase(rod), data,
                                       jnp.asarray(w))
    state = _states(rod, path, data, w[None], [res.converged], [res.residual_norm],
                    [res.iterations], [np.sum(np.asarray(eig) < 0)])[0]
    return TwistFold(state, bool(res.converged) and abs(g) <= 1e-9)
