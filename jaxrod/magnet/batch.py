"""Fold pairs for many parameter sets at once (vmap over (G, M, D), CPU or GPU, float64 or
float32): the throughput path.

``fold_angles`` (magnet/diagram.py) finds each fold by a continuation from the straight rod,
~25 sequential corrector steps that dominate its cost and, under vmap, run in lock-step to
the slowest element. Here the continuation is replaced by the paper's one-mode
approximation (magnet/reduction.py): on a fixed (q, alpha) grid the one-mode function
F0(q, alpha) = e0'(q) and dF0/dq = e0''(q) of e0(q) = E_alpha(q psi) are evaluated in one
vectorised sweep (scalar derivatives of a quadrature, no Hessians), the grid cells where
both change sign bracket the one-mode folds (q0, alpha0), a 2 x 2 Newton refines them, and
each fold is then the Moore-Spence solution started from (q0 psi, psi, alpha0). Every step
has a fixed cost, so a batch costs the same for every element.

The one-mode folds lie within a few degrees of the true folds for the paper's parameters
(within 2 degrees for E in 80-250 GPa, where every batch element converges to the same folds
as ``fold_angles``); at small clearances (tips of 60-80 degrees at the upper fold) the
brackets are further off but the Moore-Spence solves still reach the folds of
``locate_folds`` (tests). The folds returned are those the solves reach, not checked to lie
on the branch through the straight rod: validate new parameter regions against
``locate_folds``. ``converged`` is False where the grid finds fewer than two one-mode
folds (beyond or very near the cusp where the folds merge), where the two Moore-Spence
solves land on the same fold or outside (0, 90] degrees, or where a solve fails: use
``locate_folds`` for those.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from jaxrod.discretise.planar import PlanarDiscretisation, planar_discretisation
from jaxrod.magnet.diagram import default_options
from jaxrod.magnet.folds import NEAR_SINGULAR, locate_folds, run_to_second_fold
from jaxrod.magnet.reduction import normalised_mode
from jaxrod.params import RANGES, ParameterError, check_degree
from jaxrod.programs import bucket, jit, padded, retry_size  # noqa: F401 (bucket: its old home)
from jaxrod.scenes.dipole import ALPHA_MODEL, DipoleMagnet
from jaxrod.solvers import dense
from jaxrod.solvers.continuation import REACHED_BOUND
from jaxrod.solvers.folds import (
    moore_spence_blocks,
    moore_spence_solve,
    moore_spence_step,
)
from jaxrod.solvers.newton import newton
from jaxrod.status import Status
from jaxrod.stored import StoredProgram

#: The (q, alpha) grid that brackets the one-mode folds: q in [0, Q_MAX], alpha in [0, 90] deg.
GRID_Q, GRID_ALPHA, Q_MAX = 32, 32, 1.6

#: Bracketing cells counted per parameter set: "the last cell" is the last of the first
#: CANDIDATES (at small clearances the grid's last crossed cells, near q = Q_MAX, lead the
#: one-mode solve back to the first fold).
CANDIDATES = 64

#: Newton's budgets in the batch (its loops run to the slowest element): the one-mode solve
#: (2 x 2, cheap) may halve its steps often; the Moore-Spence solve from the one-mode fold
#: converges in at most 4 steps at the paper's parameters, in 12 at a clearance D = 1.03
#: (the upper fold's tip at 80 degrees), and with at most 4 halvings wherever it converges
#: over E = 50-300 GPa, D = 1.1-1.6 and 0.3-3 times the magnet.
ONE_MODE_BUDGET = {"max_steps": 20, "max_halvings": 12}
FOLD_BUDGET = {"max_steps": 16, "max_halvings": 4}

#: Newton tolerances per precision: (tol on |residual|, xtol, stall_xtol).
TOLERANCES = {jnp.dtype("float64"): (1e-13, 1e-10, 1e-7),
              jnp.dtype("float32"): (1e-5, 1e-4, 1e-3)}


def _one_mode_moments(q, psi_quad, disc, S=None, C=None):
    """The q-dependent integrals of the one-mode state theta = q psi: X, dX/dq, d2X/dq2 (each
    an (e1, e3) pair of arrays), int (1 - s) sin(q psi) psi and int (1 - s) cos(q psi) psi^2,
    for q of any shape; S, C = sin, cos(q psi) at the nodes when already known."""
    if S is None:
        th = q[..., None] * psi_quad
        S, C = jnp.sin(th), jnp.cos(th)
    w = disc.quad_weights
    wp, wp2, lever = w * psi_quad, w * psi_quad**2, w * (1.0 - disc.quad_nodes) * psi_quad
    return ((S @ w, C @ w), (C @ wp, -(S @ wp)), (-(S @ wp2), -(C @ wp2)), S @ lever,
            C @ (lever * psi_quad))


def _grid_sines(h, count, psi_quad):
    """sin and cos of k h psi at the nodes for k = 0 .. count - 1 (count, nq), by the angle
    addition recurrence from one sine and cosine per node (the grid only brackets sign
    changes; the recurrence's round-off, a few ulp per step, does not matter there)."""
    s1, c1 = jnp.sin(h * psi_quad), jnp.cos(h * psi_quad)

    def step(sc, _):
        s, c = sc
        return (s * c1 + c * s1, c * c1 - s * s1), sc

    _, (S, C) = jax.lax.scan(step, (jnp.zeros_like(s1), jnp.ones_like(c1)), None, length=count)
    return S, C


def _dipole_terms(X, dX, d2X, p, D):
    """(grad Phi . X', X'^T Hess Phi X' + grad Phi . X'') of the dipole potential
    Phi(x) = p . r / |r|^3, r = x - D p (``dipole_potential``), in closed form:

        grad Phi = p / |r|^3 - 3 (p . r) r / |r|^5,
        v^T Hess Phi v = -3 (2 (r . v)(p . v) + (p . r) |v|^2) / |r|^5
                         + 15 (p . r)(r . v)^2 / |r|^7.

    Each vector is an (e1, e3) pair of arrays that broadcast."""
    dot = lambda a, b: a[0] * b[0] + a[1] * b[1]
    r = (X[0] - D * p[0], X[1] - D * p[1])
    inv2 = 1.0 / dot(r, r)
    inv3 = inv2 * jnp.sqrt(inv2)
    pr, rv, pv = dot(p, r), dot(r, dX), dot(p, dX)
    g_v = inv3 * (pv - 3.0 * pr * rv * inv2)
    g_a = inv3 * (dot(p, d2X) - 3.0 * pr * dot(r, d2X) * inv2)
    vHv = inv3 * inv2 * (-3.0 * (2.0 * rv * pv + pr * dot(dX, dX)) + 15.0 * pr * rv**2 * inv2)
    return g_v, vHv + g_a


def _one_mode_derivatives(q, moments, alpha, bend, scene: DipoleMagnet):
    """(F0, dF0/dq) at (q, alpha) in closed form, e0(q) = E_alpha(q psi):

        F0     = q int psi'^2 - G int (1-s) sin(q psi) psi + M grad Phi(X) . X'
        dF0/dq = int psi'^2 - G int (1-s) cos(q psi) psi^2
                 + M (X'^T Hess Phi(X) X' + grad Phi(X) . X'')

    with X(q) = int (sin q psi, cos q psi) and Phi the dipole potential; q (with its moments)
    and alpha broadcast against each other."""
    X, dX, d2X, gravity1, gravity2 = moments
    p = (jnp.sin(alpha), jnp.cos(alpha))
    g_v, second = _dipole_terms(X, dX, d2X, p, scene.D)
    return (q * bend - scene.G * gravity1 + scene.M * g_v,
            bend - scene.G * gravity2 + scene.M * second)


def _sign_change(X):
    corners = jnp.stack([X[:-1, :-1], X[1:, :-1], X[:-1, 1:], X[1:, 1:]])
    return (jnp.min(corners, 0) < 0) & (jnp.max(corners, 0) > 0)


#: A crossed cell brackets a one-mode fold when the linearised contours F0 = 0 and
#: dF0/dq = 0 meet within this many cell widths of its centre (0.5: inside the cell).
REACH = 1.0


def _cell_linearisation(F, Fq):
    """Each cell's centre values and cell-width differences of F0 and dF0/dq, and the
    crossing (dq, dalpha) of the two linearised contours from the centre, in cell widths:

        [F_q  F_a ] [dq]      [F ]
        [Fq_q Fq_a] [da]  = - [Fq]     (centre values, differences across the cell).

    Two contours that both cross a cell need not meet in it (they run side by side near
    q = 0 and near the cusp); the crossing's distance tells the cells that bracket a fold
    from those that only touch both contours."""
    def parts(X):
        centre = 0.25 * (X[:-1, :-1] + X[1:, :-1] + X[:-1, 1:] + X[1:, 1:])
        d_q = 0.5 * (X[:-1, 1:] + X[1:, 1:] - X[:-1, :-1] - X[1:, :-1])
        d_a = 0.5 * (X[1:, :-1] + X[1:, 1:] - X[:-1, :-1] - X[:-1, 1:])
        return centre, d_q, d_a

    f, f_q, f_a = parts(F)
    g, g_q, g_a = parts(Fq)
    det = f_q * g_a - f_a * g_q
    safe = jnp.where(det == 0.0, 1.0, det)
    dq = jnp.where(det == 0.0, jnp.inf, -(f * g_a - f_a * g) / safe)
    da = jnp.where(det == 0.0, jnp.inf, -(f_q * g - f * g_q) / safe)
    return dq, da


def _crossed_cell(crossed, rank):
    """(alpha row, q column) of the crossed cell of the given rank (row-major, from 0) in the
    boolean grid ``crossed``: counts per row and their running sums locate the row, the
    running sum within that row the column (small sums and masked reductions, which are
    cheap under vmap on a CPU; ``jnp.nonzero``'s scatter over the whole grid is not)."""
    rows = jnp.arange(crossed.shape[0])
    per_row = jnp.sum(crossed, axis=1)
    before_end = jnp.cumsum(per_row)
    r = jnp.minimum(jnp.sum(before_end <= rank), crossed.shape[0] - 1)
    row = jnp.sum(jnp.where(rows[:, None] == r, crossed, 0), axis=0)
    before = jnp.sum(jnp.where(rows < r, per_row, 0))
    c = jnp.minimum(jnp.sum(jnp.cumsum(row) <= rank - before), crossed.shape[1] - 1)
    return r, c


def _cell_starts(crossed, cells: int, end: str, dq, dalpha):
    """(cells, 2) one-mode starts (q, alpha) at the centres of the first or the last
    (``end``) ``cells`` crossed cells (row-major; the last among the first CANDIDATES); NaN
    for a slot without a cell (a batch runs its Newton loops until the slowest element is
    done: a NaN start ends its solve at the first pass)."""
    count = jnp.sum(crossed)
    k = jnp.arange(cells)
    slot = k if end == "first" else count - cells + k
    used = (slot >= 0) & (slot < count)
    ia, iq = jax.vmap(lambda rank: _crossed_cell(crossed, rank))(
        jnp.clip(slot, 0, CANDIDATES - 1))
    # the cells' centres (the grids are uniform from 0: no gather of the grid values)
    start = jnp.stack([(iq + 0.5).astype(dq.dtype) * dq, (ia + 0.5).astype(dq.dtype) * dalpha],
                      axis=1)
    return jnp.where(used[:, None], start, jnp.nan)


def _canonical(z, m):
    """The fold state z = (x, phi, alpha) mapped to alpha in [0, pi]: the energy is
    2 pi-periodic in alpha and symmetric under (theta, alpha) -> -(theta, alpha) (with the
    same Hessian), so a solve that lands on a fold's periodic or mirror image has found that
    fold."""
    alpha = jnp.mod(z[-1] + jnp.pi, 2.0 * jnp.pi) - jnp.pi
    sign = jnp.where(alpha < 0.0, -1.0, 1.0).astype(z.dtype)
    return jnp.concatenate([sign * z[:m], z[m:2 * m], jnp.atleast_1d(sign * alpha)])


def fold_pair_states(G, M, D, disc: PlanarDiscretisation, cells: int = 1):
    """The two Moore-Spence fold states z = (theta, phi, alpha) (2, 2m + 1), lower fold
    first, reached from the one-mode brackets (module docstring), with converged and the
    Moore-Spence iteration count (one parameter set; vmap it). The dtype of ``disc``
    (float64 or float32) sets the precision. A state is a warm start for the same fold at
    nearby parameters (``jaxrod.inverse.fit``).

    ``cells`` (static): how many of the first and of the last bracketing cells start a
    one-mode solve. One each is the fast default; more cost more (a batch's loops run to its
    slowest solve) and rescue the small clearances, where the straight rod is nearly
    critical at alpha = 0 and the first cells, near q = 0, lead the solve to the upper fold
    (``jaxrod.bistability.design_map`` retries its failures with 4)."""
    dtype = disc.quad_weights.dtype
    tol, xtol, stall = TOLERANCES[jnp.dtype(dtype)]
    scene = DipoleMagnet(G, M, D, jnp.zeros((), dtype))
    psi, _, _ = normalised_mode(G, M, D, disc)
    psi_q, dpsi_q = disc.at_quadrature(psi)
    bend = disc.integrate(dpsi_q**2)
    qs = jnp.linspace(0.0, Q_MAX, GRID_Q, dtype=dtype)
    al = jnp.linspace(0.0, 0.5 * jnp.pi, GRID_ALPHA, dtype=dtype)
    moments = _one_mode_moments(qs, psi_q, disc, *_grid_sines(qs[1], GRID_Q, psi_q))
    F0, F0q = _one_mode_derivatives(qs, moments, al[:, None], bend, scene)
    dq, da = _cell_linearisation(F0, F0q)
    touched = _sign_change(F0) & _sign_change(F0q)
    bracketing = touched & (jnp.abs(dq) <= REACH) & (jnp.abs(da) <= REACH)
    # one-mode Newton solves start from the first ``cells`` cells where the two contours
    # meet (row-major: alpha first; where there is none, the first cells that both cross)
    # and from the last ``cells`` cells that both cross; the converged one-mode folds of
    # smallest and largest alpha are the lower and the upper fold
    first = jnp.where(jnp.any(bracketing), bracketing, touched)
    start = jnp.concatenate([_cell_starts(first, cells, "first", qs[1], al[1]),
                             _cell_starts(touched, cells, "last", qs[1], al[1])])

    def one_mode(x0):
        residual = lambda x, _: jnp.stack(_one_mode_derivatives(
            x[0], _one_mode_moments(x[0], psi_q, disc), x[1], bend, scene))
        return newton(residual, x0, None, tol=tol, xtol=xtol, stall_xtol=stall,
                      solve=dense.solve, **ONE_MODE_BUDGET)

    solves = jax.vmap(one_mode)(start)
    # a solve may land on a periodic or mirror image of a fold (as in ``_canonical``)
    a = jnp.mod(solves.x[:, 1] + jnp.pi, 2.0 * jnp.pi) - jnp.pi
    sign = jnp.where(a < 0.0, -1.0, 1.0).astype(dtype)
    q, a = sign * solves.x[:, 0], sign * a
    # (the one-mode folds may lie a little beyond 90 degrees where the Moore-Spence solves
    # reach folds inside: only the final folds are held to (0, 90])
    usable = solves.converged & (a > 0.0)
    pick = jnp.stack([jnp.argmin(jnp.where(usable, a, jnp.inf)),
                      jnp.argmax(jnp.where(usable, a, -jnp.inf))])
    one_x = jnp.stack([q[pick], a[pick]], axis=1)
    found = (jnp.sum(usable) >= 2) & (a[pick[1]] - a[pick[0]] > 1e3 * xtol)

    ell = psi / jnp.dot(psi, psi)

    def fold(x):
        z0 = jnp.where(found, jnp.concatenate([x[0] * psi, psi, x[1:2]]), jnp.nan)
        data = (ALPHA_MODEL, ell, (scene, disc))
        res = newton(None, z0, data, tol=tol, xtol=xtol, stall_xtol=stall,
                     linearise=moore_spence_blocks,
                     solve=lambda blocks, rhs: moore_spence_step(blocks, rhs, data),
                     **FOLD_BUDGET)
        return res.x, res

    states, ms = jax.vmap(fold)(one_x)
    z = jax.vmap(lambda z: _canonical(z, disc.size))(states)
    z = z[jnp.argsort(z[:, -1])]
    alphas = z[:, -1]
    in_range = jnp.all((alphas > 0.0) & (alphas <= 0.5 * jnp.pi))
    converged = found & jnp.all(ms.converged) & in_range & (alphas[1] - alphas[0] > 1e3 * xtol)
    return z, converged, jnp.max(ms.iterations)


def cast(disc: PlanarDiscretisation, dtype) -> PlanarDiscretisation:
    """The discretisation with its arrays in ``dtype`` (float32 for the fast GPU path)."""
    return jax.tree_util.tree_map(lambda a: a.astype(dtype), disc)


DTYPES = ("float64", "float32")


# --- what a parameter set's answer is ------------------------------------------------------

#: A parameter set's answer: its two folds, a certificate that there are none, or that no
#: solver converged. "Not converged" is never "not bistable".
#: Codes of ``jaxrod.Status`` (one code space for every result and store).
BISTABLE, NOT_BISTABLE, FOLD_BEYOND_90, INVALID_INPUT, NOT_CONVERGED = (
    int(Status.SUCCESS), int(Status.NO_FOLD_PAIR), int(Status.FOLD_OUT_OF_RANGE),
    int(Status.INVALID_INPUT), int(Status.NOT_CONVERGED))
STATUS = {BISTABLE: "bistable: both folds in (0, 90] degrees",
          NOT_BISTABLE: "not bistable: fewer than two folds on the branch through the "
          "straight rod (continuation to 180 degrees)",
          FOLD_BEYOND_90: "a fold lies beyond 90 degrees (outside the magnet's sweep)",
          INVALID_INPUT: "invalid input: the magnet would touch the rod, or an input is not "
          "positive",
          NOT_CONVERGED: "no solver converged (one-mode brackets, wider brackets, batched "
          "continuation and locate_folds): not known whether the set is bistable"}

#: Bracketing cells per end that the second tier solves from (``fold_pair_states``).
RETRY_CELLS = 4
#: Capacity of the continuation tier (alpha up to 180 degrees, two folds).
RETRY_CAPACITY = 160


class FoldPairs(NamedTuple):
    """Fold pairs of K parameter sets.

    alpha_deg: (K, 2) lower and upper fold (magnet angles, degrees), NaN unless bistable;
    bistable: (K,) status == BISTABLE; status: (K,) codes of ``STATUS``; tier: (K,) the
    tier that answered (1 the one-mode brackets, 2 wider brackets, 3 the batched
    continuation, 4 ``locate_folds``); iterations: (K,) Moore-Spence iterations of tier 1.

    Paper: the two folds of Proposition ``thm:planar_fold`` of each parameter set.
    """

    alpha_deg: np.ndarray
    bistable: np.ndarray
    status: np.ndarray
    tier: np.ndarray
    iterations: np.ndarray

    def messages(self) -> list[str]:
        """The status of each set in words."""
        return [STATUS[int(c)] for c in self.status]


def continuation_pair(G, M, D, disc: PlanarDiscretisation):
    """(fold states (2, 2m + 1), status) of one parameter set by the ``locate_folds``
    algorithm (vmap it): the continuation in alpha from the straight rod up to 180 degrees
    that stops after two folds (``run_to_second_fold``), then Moore-Spence at both. Fewer
    than two folds when the run reaches its bound certifies NOT_BISTABLE, unless the
    Hessian's smallest eigenvalue came within ``NEAR_SINGULAR`` of zero on the way: two
    folds near a cusp can hide within one step (a loop of 1e-3 degrees), and such a set is
    left NOT_CONVERGED for ``locate_folds``, which re-traces with a finer step."""
    scene = DipoleMagnet(G, M, D, 0.0)
    args = (scene, disc)
    raw, theta, alpha, phi, folds = run_to_second_fold(scene, disc, jnp.pi, RETRY_CAPACITY)
    started = raw.residual_norm[0] <= default_options().tol

    def refine(theta, alpha, phi):
        fp = moore_spence_solve(ALPHA_MODEL, theta, alpha, phi, args)
        z = jnp.concatenate([fp.x, fp.null_vector, jnp.atleast_1d(fp.lam)])
        return z, fp.newton.converged

    z, ok = jax.vmap(refine)(theta, alpha, phi)
    z = z[jnp.argsort(z[:, -1])]
    alphas = z[:, -1]
    two = started & (folds >= 2)
    solved = two & jnp.all(ok) & (alphas[0] > 0.0) & (alphas[1] - alphas[0] > 1e-9)
    beyond = solved & (alphas[1] > 0.5 * jnp.pi)
    recorded = jnp.arange(raw.lam.shape[0]) < raw.num_points
    nearest_zero = jax.vmap(lambda x, lam: dense.smallest_eigenvalue_magnitude(
        ALPHA_MODEL.hessian(x, lam, args)))(raw.x, raw.lam)
    clear = jnp.min(jnp.where(recorded, nearest_zero, jnp.inf)) >= NEAR_SINGULAR
    # the run went to its bound, clear of singular Hessians: its fold count is final
    ended = (raw.status == REACHED_BOUND) & clear
    status = jnp.where(solved, jnp.where(beyond, FOLD_BEYOND_90, BISTABLE),
                       jnp.where(started & ~two & ended, NOT_BISTABLE, NOT_CONVERGED))
    return z, status


def batch_fold_angles(G, M, D, n: int, cells: int = 1):
    """(alphas (K, 2) radians, converged (K,)) of ``fold_pair_states`` over arrays G, M, D,
    float64 (tier 1 of a map's chunk with ``cells`` = 1, tier 2 with ``RETRY_CELLS``)."""
    disc = planar_discretisation(n, "clamped")
    z, converged, _ = jax.vmap(lambda g, m, d: fold_pair_states(g, m, d, disc, cells))(G, M, D)
    return z[:, :, -1], converged


#: ``batch_fold_angles`` compiled (tiers 1 and 2 of a map's chunk on one device); kept in the
#: command line's store, so that a later process does not trace it again.
batch_fold_angles_program = StoredProgram("batch-fold-angles", batch_fold_angles,
                                          static_argnames=("n", "cells"))


def _continuation_batch(G, M, D, n: int):
    disc = planar_discretisation(n, "clamped")
    return jax.vmap(lambda g, m, d: continuation_pair(g, m, d, disc))(G, M, D)


_continuation_program = StoredProgram("batch-continuation", _continuation_batch,
                                      static_argnames=("n",))


def resolve_failures(G, M, D, alphas, status, tier, n: int = 12):
    """Tiers 2 to 4 for the sets whose ``status`` is NOT_CONVERGED (arrays on the host,
    updated in place; alphas (K, 2) the folds in radians): the one-mode brackets from
    RETRY_CELLS cells per end, then the batched continuation from the straight rod (which
    also certifies NOT_BISTABLE and FOLD_BEYOND_90), then ``locate_folds`` one by one. The
    batched tiers run in float64 on padded batches (``retry_size``)."""
    retry = np.nonzero(status == NOT_CONVERGED)[0]
    if retry.size:  # tier 2
        a2, ok2 = jax.device_get(batch_fold_angles_program(
            *padded([G[retry], M[retry], D[retry]], retry_size(retry.size)), n=n,
            cells=RETRY_CELLS))
        a2, ok2 = np.asarray(a2)[:retry.size], np.asarray(ok2)[:retry.size]
        alphas[retry[ok2]], status[retry[ok2]], tier[retry] = a2[ok2], BISTABLE, 2
        retry = retry[~ok2]
    if retry.size:  # tier 3
        z3, code = jax.device_get(_continuation_program(
            *padded([G[retry], M[retry], D[retry]], retry_size(retry.size)), n=n))
        a3, code = np.asarray(z3)[:retry.size, :, -1], np.asarray(code)[:retry.size]
        alphas[retry], status[retry], tier[retry] = a3, code, 3
        retry = retry[code == NOT_CONVERGED]
    if retry.size:  # tier 4: one by one
        for i in retry:
            rep = locate_folds(DipoleMagnet(G[i], M[i], D[i], 0.0), n=n, throw=False)
            tier[i] = 4
            kinds = {f.kind: f for f in rep.folds}
            if rep.converged and "lower" in kinds and "upper" in kinds:
                alphas[i] = np.radians([kinds["lower"].alpha_deg, kinds["upper"].alpha_deg])
                status[i] = FOLD_BEYOND_90 if alphas[i, 1] > 0.5 * math.pi else BISTABLE
            elif rep.branch.complete and not rep.problems and len(rep.folds) < 2:
                status[i] = NOT_BISTABLE
    return alphas, status, tier


def fold_pairs(G, M, D, n: int = 12, dtype: str = "float64") -> FoldPairs:
    """Fold pairs for arrays G, M, D (same shape K), in degrees, each with its status
    (``FoldPairs``): no parameter set is left without an answer that says what it is.

    Tier 1 is the fixed-cost batched path (one-mode brackets and Moore-Spence, module
    docstring; ``fold_pairs_program``, in ``dtype``); the sets it does not converge go
    through ``resolve_failures`` (wider brackets, the batched continuation from the straight
    rod, ``locate_folds``), which either finds their folds or certifies that there are no two
    (NOT_BISTABLE) or that one lies beyond 90 degrees. NOT_CONVERGED remains only where every
    solver failed. Batches are padded to a few sizes (``jaxrod.programs.bucket``), so that a
    new K rarely compiles a new program.

    The rows are validated first: a row outside ``jaxrod.params.RANGES`` (or NaN) raises
    ParameterError naming it. Matrix products run at full precision of ``dtype`` (GPUs
    otherwise multiply float32 matrices in TF32, which costs float32 three digits and
    Newton its convergence).

    Paper: the two folds of Proposition ``thm:planar_fold`` (Moore-Spence: grad E = 0, H phi
    = 0, l . phi = 1), one pair per row.
    """
    if dtype not in DTYPES:
        raise ParameterError(f"dtype must be one of {DTYPES}, got {dtype!r}")
    n = check_degree(n, "N-magnet")
    G, M, D = (RANGES[k].check_rows(v) for k, v in (("G-magnet", G), ("M", M), ("D", D)))
    if not G.ndim == 1 or G.shape != M.shape or G.shape != D.shape:
        raise ParameterError(f"G, M, D must be 1-d arrays of one length, got shapes "
                             f"{G.shape}, {M.shape}, {D.shape}")
    G, M, D = (np.asarray(v, np.float64) for v in (G, M, D))
    k = G.shape[0]
    if k == 0:
        empty = np.zeros(0, np.int8)
        return FoldPairs(np.zeros((0, 2)), np.zeros(0, bool), empty, empty, empty)
    alphas, ok, iterations = (np.asarray(a)[:k] for a in fold_pairs_program(
        *padded([G, M, D]), n=n, dtype=dtype))
    alphas = alphas.astype(np.float64)  # (a copy: the fallback tiers write into it)
    status = np.where(ok, BISTABLE, NOT_CONVERGED).astype(np.int8)
    tier = np.ones(k, np.int8)
    if not ok.all():
        resolve_failures(G, M, D, alphas, status, tier, n)
    bistable = status == BISTABLE
    return FoldPairs(np.where(bistable[:, None], np.degrees(alphas), np.nan), bistable, status,
                     tier, iterations)


@jit(static_argnames=("n", "dtype"))
def fold_pairs_program(G, M, D, n: int = 12, dtype: str = "float64"):
    """Tier 1 of ``fold_pairs`` alone, without the input checks and the fallback tiers: the
    compiled program itself (``.lower``). Returns (alphas (K, 2) radians, NaN where not
    converged; converged (K,); Moore-Spence iterations (K,)). ``converged`` False means that
    this path found no pair, not that there is none (``fold_pairs`` says which)."""
    disc = cast(planar_discretisation(n, "clamped"), dtype)
    G, M, D = (jnp.asarray(v, dtype) for v in (G, M, D))
    with jax.default_matmul_precision("highest"):
        z, converged, iterations = jax.vmap(
            lambda g, m, d: fold_pair_states(g, m, d, disc))(G, M, D)
    return jnp.where(converged[:, None], z[:, :, -1], jnp.nan), converged, iterations
