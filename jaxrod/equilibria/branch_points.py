"""Branch points of any scene along any input: where stability changes without a fold, and
the branch that bifurcates there.

On a branch of grad E(x; v) = 0 the Morse index (the number of negative Hessian eigenvalues)
changes where an eigenvalue crosses zero. Where the branch also turns back in v that is a
fold (``jaxrod.equilibria.folds``); where it goes on, it is a branch point: a symmetry-
breaking pitchfork (the straight rod under an opposed field, or the paper's uniform field).
Each is refined by Moore's augmented system for a simple bifurcation point (Moore, SIAM J.
Numer. Anal. 1980), with the Hessian symmetric,

    grad E(x; v) + mu phi = 0,   H phi = 0,   l . phi = 1,   phi . d(grad E)/dv = 0,

in (x, v, phi, mu): regular at simple branch points (pitchforks and transcritical points),
where the fold's Moore-Spence system is singular along the bifurcating direction; mu = 0 at
the solution (reported as ``unfolding``). A stability change that is a fold (the last
equation cannot hold: ``jaxrod.equilibria.folds``) does not converge and is left out.

The bifurcating branch starts at x* + eps phi: (x, v) solves grad E = 0 with
phi . (x - x*) = eps |phi|^2 (Newton in n + 1 unknowns), and pseudo-arclength continuation
goes on from there, away from the branch point (``bifurcated_branch``; AUTO-07p's and
BifurcationKit's branch switching, here by the bordered corrector).
"""

from __future__ import annotations

import dataclasses
import math

import jax
import jax.numpy as jnp
import numpy as np

from jaxrod.discretise.tail import tail_estimate
from jaxrod.equilibria.equilibrium import (
    DEFAULT_N,
    MODEL,
    NO_REST,
    discretise,
    mean_functional,
    observe,
    tip,
)
from jaxrod.equilibria.folds import _span
from jaxrod.equilibria.record import Branch, SpecialPoint, branch_from_runs, checked
from jaxrod.equilibria.trace import branch_options, check_range, path_of, trace
from jaxrod.params import ParameterError
from jaxrod.programs import jit, padded
from jaxrod.scenes.path import ALONG, along
from jaxrod.scenes.scene import Scene
from jaxrod.solvers.continuation import continuation_run
from jaxrod.solvers.newton import newton
from jaxrod.status import SolverError, Status


@dataclasses.dataclass(frozen=True)
class BranchPoint(SpecialPoint):
    """A branch point of a scene's branch in the input ``vary``, refined by Moore's system
    (``SpecialPoint``'s fields; ``null_vector``, the bifurcating branch's direction,
    normalised by int phi = 1 where that is not zero), with ``unfolding``: mu of the
    augmented system (zero at the solution, to round-off), and ``morse_index``: the index
    before and after it along the branch."""

    unfolding: float
    morse_index: tuple[int, int]

    kind = "branch_point"


def stability_changes(b: Branch) -> np.ndarray:
    """i such that the Morse index changes between points i and i + 1 with no fold there."""
    change = np.nonzero(b.morse_index[1:] != b.morse_index[:-1])[0]
    return np.setdiff1d(change, b.fold_indices)


def _bp_residual(z, args):
    model, margs, ell = args
    m = ell.shape[0]
    x, phi, lam, mu = z[:m], z[m:2 * m], z[2 * m], z[2 * m + 1]
    F, H, F_lam = model.linearisation(x, lam, margs)
    return jnp.concatenate([F + mu * phi, H @ phi, jnp.stack([jnp.dot(ell, phi) - 1.0,
                                                              jnp.dot(phi, F_lam)])])


def _refine_one(x_a, lam_a, x_b, lam_b, k, path, disc, origin, span):
    """Moore's system from the bracket (a, b) of a Morse index change k -> k + 1 (or back):
    the start is the secant zero of the k-th eigenvalue (ascending, the one that crosses)
    between a and b, phi its eigenvector there, so that the refinement meets this crossing
    and not the kernel of an earlier one (whose eigenvalue is negative here)."""
    model = MODEL
    margs = (path, disc, origin, span, NO_REST)
    mu_a = jnp.linalg.eigvalsh(model.hessian(x_a, lam_a, margs))[k]
    mu_b = jnp.linalg.eigvalsh(model.hessian(x_b, lam_b, margs))[k]
    t = jnp.clip(jnp.where(mu_a != mu_b, mu_a / (mu_a - mu_b), 0.5), 0.0, 1.0)
    x0, lam0 = x_a + t * (x_b - x_a), lam_a + t * (lam_b - lam_a)
    phi0 = jnp.linalg.eigh(model.hessian(x0, lam0, margs))[1][:, k]
    ell = phi0 / jnp.dot(phi0, phi0)
    z0 = jnp.concatenate([x0, phi0, jnp.stack([lam0, jnp.zeros_like(lam0)])])
    res = newton(_bp_residual, z0, (model, margs, ell), tol=1e-12)
    m = x0.shape[0]
    x, phi, lam = res.x[:m], res.x[m:2 * m], res.x[2 * m]
    # the kernel found must be the k-th eigenvalue's: the others stay clear of zero
    eig = jnp.linalg.eigvalsh(model.hessian(x, lam, margs))
    others = jnp.where(jnp.arange(m) == k, jnp.inf, jnp.abs(eig))
    own = jnp.abs(eig[k]) < jnp.min(others)
    scale = mean_functional(disc)(phi)
    phi = jnp.where(jnp.abs(scale) > 1e-8, phi / scale, phi)
    angle, X = tip(ALONG(lam, margs)[0], x, disc)
    return res, own, (x, phi, lam, res.x[2 * m + 1], angle, X)


_refine = jit(jax.vmap(_refine_one, in_axes=(0, 0, 0, 0, 0, None, None, None, None)))


def refine_branch_points(scene: Scene, b: Branch, n: int = DEFAULT_N) -> list[BranchPoint]:
    """The branch points detected on ``b`` (``stability_changes``), refined in the order met
    (module docstring). Each bracket (points i, i + 1 where the Morse index changes from k
    to k' = k +- 1) is refined to the kernel of the eigenvalue that crosses there (the
    min(k, k')-th, ascending), and counts as converged only if Moore's system converged,
    that eigenvalue is the one nearest zero at the answer, and the answer lies in the
    bracket (widened by its own width on each side): a refinement that slid to another
    crossing is reported with ``converged`` False, never as a second copy of the first.
    A change where the augmented system does not converge (a fold the branch's sampling did
    not show as a turn) is reported with ``converged`` False."""
    idx = stability_changes(b)
    if len(idx) == 0:
        return []
    path = along(scene, (b.vary,))
    disc = discretise(path.template, n)
    origin, span = float(b.value[0]), _span(b)
    k = np.minimum(b.morse_index[idx], b.morse_index[idx + 1]).astype(np.int32)
    lam = (b.value - origin) / span
    # padded to a power of two (at least 2): one program for every count up to it
    brackets = padded([np.asarray(b.theta[idx]), lam[idx], np.asarray(b.theta[idx + 1]),
                       lam[idx + 1], k], max(2, 1 << (len(idx) - 1).bit_length()))
    res, own, (x, phi, lam_star, mu, angle, X) = jax.device_get(_refine(
        *(jnp.asarray(a) for a in brackets), path, disc, origin, span))
    points = []
    for i, j in enumerate(idx):
        lo, hi = sorted((float(lam[j]), float(lam[j + 1])))
        width = hi - lo
        inside = lo - width <= float(lam_star[i]) <= hi + width
        conv = bool(res.converged[i]) and bool(own[i]) and inside
        points.append(BranchPoint(
            vary=b.vary, value=float(origin + span * lam_star[i]),
            tip_angle_deg=math.degrees(float(angle[i])), tip_position=np.asarray(X[i]),
            state=np.asarray(x[i]), null_vector=np.asarray(phi[i]), unfolding=float(mu[i]),
            morse_index=(int(b.morse_index[j]), int(b.morse_index[j + 1])), converged=conv,
            residual_norm=float(res.residual_norm[i]), iterations=int(res.iterations[i]),
            status=Status.of(conv), error_estimate=tail_estimate(disc, x[i])))
    return points


def branch_points(scene: Scene, vary: str, start: float, stop: float, n: int = DEFAULT_N,
                  state=None, throw: bool = True, margins: dict | None = None
                  ) -> list[BranchPoint]:
    """The branch points met along the branch of ``scene`` as ``vary`` goes from ``start``
    to ``stop`` (in the order met), each refined by Moore's augmented system (module
    docstring).

    ``throw``: raise ``SolverError`` if a refinement does not converge.
    """
    start, stop = check_range(scene, vary, start, stop)
    b = trace(scene, vary, start, stop, n, state, margins=margins)
    return checked(refine_branch_points(scene, b, n), "branch point", throw)


def _switch_residual(y, args):
    model, margs, x_star, phi, eps = args
    x, lam = y[:-1], y[-1]
    return jnp.append(model.gradient(x, lam, margs),
                      jnp.dot(phi, x - x_star) / jnp.dot(phi, phi) - eps)


def _switch_jacobian(y, args):
    model, margs, x_star, phi, _ = args
    _, H, g_lam = model.linearisation(y[:-1], y[-1], margs)
    top = jnp.hstack([H, g_lam[:, None]])
    return jnp.vstack([top, jnp.append(phi / jnp.dot(phi, phi), 0.0)[None, :]])


def _bifurcated_program(path, disc, origin, span, x_star, phi, eps, opts, capacity):
    model = MODEL
    margs = (path, disc, origin, span, NO_REST)
    y0 = jnp.append(x_star + eps * phi, 0.0)
    start = newton(_switch_residual, y0, (model, margs, x_star, phi, eps), tol=1e-12,
                   jacobian=_switch_jacobian)
    x1, lam1 = start.x[:-1], start.x[-1]
    # continue away from the branch point: lam grows on a supercritical side, falls on a
    # subcritical one
    direction = jnp.where(lam1 >= 0.0, 1.0, -1.0)
    run = continuation_run(model, x1, lam1, margs, opts, capacity, direction)
    q, angle, energy, X = jax.vmap(
        lambda x, lam: observe(path, disc, x, lam, origin, span))(run.x, run.lam)
    return run, (q, angle, energy), X, start.converged


_bifurcated = jit(_bifurcated_program, static_argnames=("capacity",))


def bifurcated_branch(scene: Scene, point: BranchPoint, stop: float, n: int = DEFAULT_N,
                      side: int = 1, amplitude: float = 1e-3) -> Branch:
    """The branch bifurcating at ``point``, on the ``side`` (+1 or -1: along or against the
    null vector) of the branch it crosses, followed until ``vary`` reaches ``stop`` (or
    turns back past the branch point's value). ``amplitude``: the first step along the null
    vector, in its units (int phi = 1)."""
    if side not in (1, -1):
        raise ParameterError(f"side must be +1 or -1, got {side!r}")
    start, stop = check_range(scene, point.vary, point.value, stop)
    path, _ = path_of(scene, point.vary, start, stop)
    disc = discretise(path.template, n)
    opts = branch_options()
    # lam in [0, 1] spans the point's value to stop; the run may start on either side
    opts = opts._replace(lam_min=-1.0, lam_max=1.0, max_points=0)
    phi = jnp.asarray(point.null_vector)
    run, observed, X, ok = jax.device_get(_bifurcated(
        path, disc, start, stop - start, jnp.asarray(point.state), phi, side * amplitude,
        opts, 400))
    if not bool(ok):
        raise SolverError(Status.NOT_CONVERGED, f"the first point of the branch bifurcating "
                          f"at {point.vary} = {point.value:.6g}")
    run = run._replace(lam=start + (stop - start) * run.lam,
                       tangent_lam=(stop - start) * run.tangent_lam)
    b = branch_from_runs([(run, False, observed)])
    return dataclasses.replace(b, vary=point.vary,
                               tip_position=np.asarray(X)[:int(run.num_points)])
