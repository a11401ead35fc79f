"""Folds of any scene along any input: detected on the branch, refined by Moore-Spence.

A fold (saddle-node) of grad E(x; v) = 0 is where the branch turns back in v: the Hessian
H has a one-dimensional kernel phi and dv/ds changes sign. Each is refined by the
Moore-Spence system [grad E; H phi; l . phi - 1] = 0 (``jaxrod.solvers.folds``) in the input's
scaled coordinate, and reported with its normal form: with phi normalised to int phi = 1
(q = int theta the reduced coordinate),

    dF/dv = phi . d(grad E)/dv,   d2F/dq2 = D^3E[phi, phi, phi],
    v - v* ~ c (q - q*)^2,   c = -d2F/dq2 / (2 dF/dv),
    v - v* ~ c_tip (tip - tip*)^2,   c_tip = c / T^2,   T = d(tip angle)/dq along phi

(the paper's Proposition "Planar saddle-node bifurcation" and its Corollary "Fold in the
experimental tip displacement angle", for any scene and input).
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
    path_program,
    tip,
)
from jaxrod.equilibria.record import Branch, SpecialPoint, checked
from jaxrod.equilibria.trace import branch_options, check_range, path_of, trace
from jaxrod.params import ParameterError
from jaxrod.programs import jit, padded
from jaxrod.scenes.files import FileScene
from jaxrod.scenes.path import ALONG, along
from jaxrod.scenes.scene import Scene
from jaxrod.solvers.folds import differentiable_fold, fold_coefficients, moore_spence_solve
from jaxrod.status import SolverError, Status
from jaxrod.stored import StoredProgram


@dataclasses.dataclass(frozen=True)
class Fold(SpecialPoint):
    """A fold of a scene's branch in the input ``vary``, refined by Moore-Spence
    (``SpecialPoint``'s fields), with ``q`` = int theta there and its normal form:
    ``dF_dvalue``, ``d2F_dq2``, ``normal_form_c``, ``tip_parabola_c`` (module docstring; NaN
    where the tip angle does not move along phi, T = 0) in the input's units, and the two
    smallest eigenvalues of the Hessian there (``hessian_smallest``: one is zero; the
    other's sign tells whether the fold joins a stable branch to an index-1 one).
    """

    q: float
    dF_dvalue: float
    d2F_dq2: float
    normal_form_c: float
    tip_parabola_c: float = dataclasses.field(default=math.nan, kw_only=True)
    hessian_smallest: tuple[float, float] = dataclasses.field(default=(math.nan, math.nan),
                                                              kw_only=True)

    kind = "fold"


def _refine_one(x0, lam0, path, disc, origin, span):
    args = (path, disc, origin, span, NO_REST)
    phi0 = jnp.linalg.eigh(MODEL.hessian(x0, lam0, args))[1][:, 0]
    fp = moore_spence_solve(MODEL, x0, lam0, phi0, args)
    d_lam, d_qq, phi_q = fold_coefficients(None, fp.x, fp.lam, fp.null_vector, args,
                                           mean_functional(disc), jacobian=fp.newton.jacobian)
    at = ALONG(fp.lam, args)[0]
    (angle, X), (slope, _) = jax.jvp(lambda x: tip(at, x, disc), (fp.x,), (phi_q,))
    eigs = jnp.linalg.eigvalsh(fp.newton.jacobian[:x0.size, :x0.size])[:2]
    return fp, (d_lam / span, d_qq, mean_functional(disc)(fp.x), angle, X, phi_q, slope, eigs)


def _refine_rows(x0, lam0, path, disc, origin, span):
    return jax.vmap(_refine_one, in_axes=(0, 0, None, None, None, None))(x0, lam0, path, disc,
                                                                      origin, span)


_refine = StoredProgram("fold-refine", _refine_rows)


def refine(scene: Scene | FileScene, b: Branch, n: int = DEFAULT_N) -> list[Fold]:
    """The folds detected on the branch ``b`` of ``scene``, refined (in the order met)."""
    idx = b.fold_indices
    if len(idx) == 0:
        return []
    path = along(scene, (b.vary,))
    disc = discretise(path.template, n)
    origin = float(b.value[0])
    # start from the point of the pair with the smaller |dv/ds| (nearer the fold)
    pick = np.where(np.abs(b.tangent_value[idx]) <= np.abs(b.tangent_value[idx + 1]), idx,
                    idx + 1)
    span = _span(b)
    lam0 = (b.value[pick] - origin) / span
    # padded to a power of two (at least 2): one program for every count up to it
    size = max(2, 1 << (len(pick) - 1).bit_length())
    x0, lam0 = padded([np.asarray(b.theta[pick]), np.asarray(lam0)], size)
    fp, rep = jax.device_get(_refine(jnp.asarray(x0), jnp.asarray(lam0), path, disc, origin,
                                     span))
    # a refinement that left the branch's range (by a tenth of it) found another fold, or
    # none: not converged
    lo, hi = float(np.nanmin(b.value)), float(np.nanmax(b.value))
    folds = []
    for i in range(len(pick)):
        d_v, d_qq, q, angle, X, phi, slope, eigs = (np.asarray(r[i]) for r in rep)
        value = float(origin + span * fp.lam[i])
        c = float(-d_qq / (2 * d_v))
        conv = bool(fp.newton.converged[i]) and lo - 0.1 * span <= value <= hi + 0.1 * span
        folds.append(Fold(
            vary=b.vary, value=value,
            tip_angle_deg=math.degrees(float(angle)), tip_position=X, q=float(q),
            dF_dvalue=float(d_v), d2F_dq2=float(d_qq), normal_form_c=c,
            tip_parabola_c=c / float(slope) ** 2 if slope != 0.0 else math.nan,
            hessian_smallest=(float(eigs[0]), float(eigs[1])),
            state=np.asarray(fp.x[i]), null_vector=phi, converged=conv,
            residual_norm=float(fp.newton.residual_norm[i]),
            iterations=int(fp.newton.iterations[i]),
            status=Status.of(conv), error_estimate=tail_estimate(disc, fp.x[i])))
    return folds


def _span(b: Branch) -> float:
    """The scale of the branch's input (its range), so that lam stays O(1)."""
    span = float(np.nanmax(b.value) - np.nanmin(b.value))
    return span if span > 0 else 1.0


#: With no fold found, a point of the branch whose smallest Hessian eigenvalue comes within
#: this fraction of the branch's largest (away from a change of stability) may hide two
#: folds within one step (near a cusp): the branch is traced again with finer steps.
NEAR_SINGULAR = 1e-2
#: Finer steps per re-trace, and how many re-traces at most.
REFINE_STEP, RETRACES = 0.2, 2


def _distinct(found: list[Fold], b: Branch) -> tuple[list[Fold], list[int]]:
    """The folds with each listed once (two starts can converge to one fold when two folds
    lie within one step), and the branch index where each kept one was detected."""
    span = _span(b)
    out, met = [], []
    for f, i in zip(found, b.fold_indices):
        if not any(abs(f.value - g.value) < 1e-7 * span and abs(f.q - g.q) < 1e-7
                   for g in out):
            out.append(f)
            met.append(int(i))
    return out, met


def _folds_may_hide(b: Branch, found: list[Fold]) -> bool:
    """No fold found, but the branch comes near singular away from a change of stability
    (``NEAR_SINGULAR``)."""
    e = np.asarray(b.min_eig, float)
    if found or e.size < 3 or not np.isfinite(e).any():
        return False
    near_change = np.zeros(e.size, bool)
    flips = np.nonzero(np.sign(e[:-1]) * np.sign(e[1:]) <= 0)[0]
    near_change[flips] = near_change[flips + 1] = True
    small = np.abs(e) < NEAR_SINGULAR * np.nanmax(np.abs(e))
    return bool(np.any(small & ~near_change & np.isfinite(e)))


def traced_with_folds(scene, vary: str, start: float, stop: float, n: int = DEFAULT_N,
                      state=None, options=None, margins: dict | None = None):
    """(the branch, its folds refined and listed once, the branch index where each was
    detected), traced again with finer steps where folds may hide within a step
    (``folds``)."""
    options = options or branch_options()
    for _ in range(RETRACES + 1):
        b = trace(scene, vary, start, stop, n, state, options, margins=margins)
        refined = refine(scene, b, n)
        found, met = _distinct(refined, b)
        if not (len(found) < len(refined) or _folds_may_hide(b, found)):
            break
        options = options._replace(ds_max=REFINE_STEP * options.ds_max,
                                   max_points=2 * options.max_points)
    return b, found, met


def folds(scene: Scene | FileScene, vary: str, start: float, stop: float, n: int = DEFAULT_N,
          state=None, throw: bool = True, margins: dict | None = None) -> list[Fold]:
    """The folds met along the branch of ``scene`` as ``vary`` goes from ``start`` to
    ``stop`` (in the order met), each refined by Moore-Spence with its normal form. Near a
    cusp two folds can lie within one continuation step (the branch's S too small to be
    seen): where two refinements reach one fold, or none is found but the branch comes near
    singular (``NEAR_SINGULAR``), the branch is traced again with steps ``REFINE_STEP``
    times finer (up to ``RETRACES`` times).

    ``throw``: raise ``SolverError`` if a fold's refinement does not converge, or if the
    branch ended before ``stop`` (folds beyond would be missing: ``Branch.status`` says
    why; ``jaxrod.equilibria.branch`` gives the branch with its folds).
    ``margins``: the magnets' radii by term name (``jaxrod.equilibria.trace.reach_along``).
    """
    start, stop = check_range(scene, vary, start, stop)
    b, found, _ = traced_with_folds(scene, vary, start, stop, n, state, margins=margins)
    if throw and not b.complete:
        raise SolverError(next((s for s in b.status if not s.ok), Status.NOT_CONVERGED),
                          f"the branch along {vary} ended at {b.value[-1]:.6g}")
    return checked(found, "fold", throw)


def fold_guesses(scene: Scene | FileScene, vary: str, start: float, stop: float, count: int,
                 n: int = DEFAULT_N) -> tuple[np.ndarray, Status]:
    """Approximate first ``count`` folds met along ``vary`` from ``start`` to ``stop``, as
    the rows z = (state, null-vector guess, lam) that a Moore-Spence solve starts from
    (lam = (v - start) / (stop - start)): the branch from the ramped equilibrium at
    ``start``, continued until ``count`` folds are passed; at the recorded point nearest
    each the state part of the branch's tangent is the guess of the Hessian's kernel (the
    branch's own program, ``path_program``: nothing new to compile after a branch or the
    folds of the scene). Returns the rows and why the run ended (``NOT_CONVERGED`` where the
    start or the loads' ramp to it did not converge: no rows then); fewer rows where fewer
    folds were met. The cheap start of fits and designs: ``folds`` refines and reports them.
    Unlike ``trace`` the run does not stop where a varied magnet enters the rod's reach: a
    fit rejects a fold there (its clearance check), and says so."""
    start, stop = check_range(scene, vary, start, stop)
    path, _ = path_of(scene, vary, start, stop)
    disc = discretise(path.template, n)
    opts = branch_options()
    run, _, _, at_start = jax.device_get(path_program(
        path, disc, start, stop - start, np.zeros(disc.size), False,
        opts._replace(max_points=0, max_folds=float(count)), opts.max_points))
    t = run.tangent_lam[:int(run.num_points)]
    i = np.nonzero(t[:-1] * t[1:] < 0.0)[0][:count]
    j = np.where(np.abs(t[i]) <= np.abs(t[i + 1]), i, i + 1)
    z = np.concatenate([run.x[j], run.tangent_x[j], run.lam[j][:, None]], axis=1)
    ramp = Status(int(at_start[3]))
    status = Status(int(run.status)) if run.residual_norm[0] <= opts.tol and ramp.ok \
        else Status.NOT_CONVERGED
    return (z if status.ok else z[:0]), status


def fold_values(path, disc, origin, span, p, z):
    """The folds' values at the path's inputs p (after ``vary``) from fold states z
    (K, 2m + 1) = (x, phi, lam) at nearby inputs: (values, new states, each solve
    converged); implicitly differentiable in p (``differentiable_fold``)."""
    m = disc.size
    z_new, stats = jax.vmap(lambda zi: differentiable_fold(
        MODEL, zi[:m], zi[-1], zi[m:2 * m], (path, disc, origin, span, p)))(z)
    return origin + span * z_new[:, -1], z_new, jnp.all(stats[:, 0] == 1.0)


_fold_values_program = jit(fold_values)


def fold_function(scene: Scene | FileScene, vary: str, vary_range: tuple[float, float],
                  inputs, count: int = 2, n: int = DEFAULT_N):
    """The first ``count`` folds met along ``vary`` over ``vary_range`` as a differentiable
    function of the scene's ``inputs`` (keys; a rig's numbers too, such as
    ``rod.youngs_modulus``): returns ``(f, p0)``, p0 the scene's values of the inputs and
    ``f(p) -> (the folds' values of vary, converged)``.

    Each call solves the Moore-Spence system [grad E; H phi; l . phi - 1] = 0 at p by
    Newton from the folds at p0 (found once, on the branch: ``fold_guesses``); the values
    are implicitly differentiable (d lam / dp = -(dR/dz)^-1 dR/dp at the solution), so
    ``jax.grad``, ``jax.jacfwd`` and ``jax.vmap`` apply; one compiled program for every
    function of a scene's structure and N. ``converged`` is False where Newton did not reach
    a fold from p0's or reached one outside ``vary_range`` (p too far from p0: take steps);
    far from p0 Newton may also land on another of the scene's folds inside the range,
    which nothing here detects. The generic form of the paper's ``fold_angles``."""
    start, stop = check_range(scene, vary, *vary_range)
    inputs = tuple(inputs)
    if not inputs or vary in inputs or len(set(inputs)) != len(inputs):
        raise ParameterError(f"inputs: one or more distinct inputs other than vary ({vary}), "
                             f"got {inputs}")
    path = along(scene, (vary, *inputs))
    z0, status = fold_guesses(scene, vary, start, stop, count, n)
    if len(z0) < count:
        why = "" if status.ok else f" (the branch stopped: {status})"
        raise ParameterError(f"count: the branch along {vary} from {start:g} to {stop:g} "
                             f"meets {len(z0)} fold(s){why}, not {count}")
    disc = discretise(path.template, n)
    z0, p0 = jnp.asarray(z0), np.asarray(path.start[1:], float)

    def f(p):
        values, z, converged = _fold_values_program(path, disc, start, stop - start,
                                                    jnp.asarray(p, jnp.float64), z0)
        inside = jnp.all((z[:, -1] >= 0.0) & (z[:, -1] <= 1.0))
        return values, converged & inside

    return f, p0
