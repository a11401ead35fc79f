"""Folds of a twisted rod's branch: where the path parameter lam turns back.

Near a fold the branch is a smooth curve in (z, lam) and lam is extremal along it. The
points of the curve on the hyperplanes normal to the chord between the two points that
bracket the turn, <W chord, w - (w_a + sigma chord)> = 0 (the continuation's own corrector),
are a smooth family in sigma; at the fold the curve's unit tangent there has no component
in lam. That component changes sign between the two points and is driven to zero by the
Illinois variant of false position in sigma: the fold to the corrector's tolerance, without
the third derivatives that an extended system would need.

A fold moves with every other input p: at the fold the bordered Hessian J_z of R(z; v, p)
= 0 is singular with a null vector phi (J_z is symmetric: the left null vector too), and
along the fold curve

    dv_fold / dp = -(phi . R_p) / (phi . R_v)        (``fold_sensitivity``),

R_v and R_p the residual's forward-mode derivatives: the exact gradient of a fold that a
fit needs (``jaxrod.inverse.twist_fit``).
"""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np

from jaxrod.params import ParameterError
from jaxrod.programs import jit
from jaxrod.solvers.arclength import _corrector, unit_tangent
from jaxrod.solvers.newton import newton
from jaxrod.twisted.branch_points import illinois
from jaxrod.twisted.equations import (
    FLOOR_TOL,
    _Path,
    _phase,
    _residual,
    _solve_program,
    _TwistSystem,
)
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


#: The fold's null direction must stand apart: the next eigenvalue of the bordered Hessian
#: at least this many times the smallest (else the fold is degenerate, a cusp or a nearly
#: free slide, and its sensitivity not defined by one null vector).
NULL_GAP = 1e3


def _column(size: int, count: int, keys: tuple, phase: bool, data, w):
    """dR/d(lam) at w (lam = w[-1]; the path's input at origin + span lam)."""
    aux = _phase(w[:size], data[0], phase)
    return jax.jvp(lambda lam: _residual(w.at[-1].set(lam), aux, data, keys, count),
                   (w[-1],), (jnp.ones_like(w[-1]),))[1]


_column_program = jit(_column, static_argnums=(0, 1, 2, 3))


def _local(rod: TwistedRod, key: str, turns: float) -> tuple[_Path, float]:
    """The path of ``key`` through its value on ``rod`` (span 1: lam in the key's units)
    and lam there."""
    if key == "turns":
        return _Path(("turns",), (0.0,), (1.0,)), float(turns)
    return _Path((key,), (rod.value(key),), (1.0,)), 0.0


def fold_sensitivity(fold: TwistFold, vary: str, keys) -> np.ndarray:
    """d(fold's value of ``vary``)/d(key) for each of ``keys`` (module docstring):
    ``vary`` the input the fold's branch was followed in, each key an input of the rod
    ("turns" where ``vary`` is another). Raises ParameterError where the fold's null
    direction is not isolated (``NULL_GAP``) or the path crosses it (phi . R_v about 0: a
    branch point)."""
    state = fold.state
    rod, disc = state.rod, state.rod.discretisation()
    size, count = disc.size, rod.constraints
    path, lam = _local(rod, vary, state.turns)
    phase = path.phase(rod)
    w = np.array(state.w)
    w[-1] = lam
    data = path.data(rod, state.turns, disc)
    _, eig, vec, _ = _solve_program(size, count, path.keys, phase, data, jnp.asarray(w))
    eig, vec = np.asarray(eig), np.asarray(vec)
    order = np.argsort(np.abs(eig))
    if not abs(eig[order[1]]) >= NULL_GAP * abs(eig[order[0]]):
        raise ParameterError(f"fold at {vary} = {fold.value:.10g}: its null direction is not "
                             f"isolated (eigenvalues {eig[order[0]]:.2e}, "
                             f"{eig[order[1]]:.2e}): a degenerate fold, or a localised "
                             "state's slide (give the rod centred=True)")
    phi = vec[:, order[0]]
    r_v = np.asarray(_column_program(size, count, path.keys, phase, data, jnp.asarray(w)))
    across = np.dot(phi, r_v[:len(phi)])
    if not abs(across) > 1e-8 * np.linalg.norm(r_v):
        raise ParameterError(f"fold at {vary} = {fold.value:.10g}: the path's derivative is "
                             "orthogonal to the null direction (a branch point, not a fold): "
                             "no sensitivity")
    out = []
    for key in keys:
        p_path, p_lam = _local(rod, key, state.turns)
        wp = np.array(state.w)
        wp[-1] = p_lam
        r_p = np.asarray(_column_program(size, count, p_path.keys, phase,
                                         p_path.data(rod, state.turns, disc),
                                         jnp.asarray(wp)))
        out.append(-np.dot(phi, r_p[:len(phi)]) / across)
    return np.array(out)
