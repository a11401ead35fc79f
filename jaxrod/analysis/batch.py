"""Fold pairs for many parameter sets at once (vmap over (G, M, D), CPU or GPU, float64 or
float32): the throughput path.

``fold_angles`` (analysis/magnet.py) finds each fold by a continuation from the straight rod,
~25 sequential corrector steps that dominate its cost and, under vmap, run in lock-step to
the slowest element. Here the continuation is replaced by the paper's one-mode
approximation (analysis/reduction.py): on a fixed (q, alpha) grid the one-mode function
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

import jax
import jax.numpy as jnp

from jaxrod.analysis.reduction import normalised_mode
from jaxrod.discretise.planar import PlanarDiscretisation, planar_discretisation
from jaxrod.params import RANGES, ParameterError, check_degree
from jaxrod.programs import jit
from jaxrod.scenes.dipole import ALPHA_MODEL, DipoleMagnet
from jaxrod.solvers import dense
from jaxrod.solvers.folds import moore_spence_blocks, moore_spence_step
from jaxrod.solvers.newton import newton

#: The (q, alpha) grid that brackets the one-mode folds: q in [0, Q_MAX], alpha in [0, 90] deg.
GRID_Q, GRID_ALPHA, Q_MAX = 40, 40, 1.6

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
    nearby parameters (``jaxrod.analysis.fit``).

    ``cells`` (static): how many of the first and of the last bracketing cells start a
    one-mode solve. One each is the fast default; more cost more (a batch's loops run to its
    slowest solve) and rescue the small clearances, where the straight rod is nearly
    critical at alpha = 0 and the first cells, near q = 0, lead the solve to the upper fold
    (``jaxrod.analysis.design_map`` retries its failures with 4)."""
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
    cells_crossed = _sign_change(F0) & _sign_change(F0q)
    # the first and the last ``cells`` of the grid cells that both contours cross
    # (row-major: alpha first) start one-mode Newton solves; the converged one-mode folds of
    # smallest and largest alpha are the lower and the upper one
    count = jnp.sum(cells_crossed)
    k = jnp.arange(cells)
    slot = jnp.concatenate([k, count - cells + k])
    used = (slot >= 0) & (slot < count)
    ia, iq = jax.vmap(lambda rank: _crossed_cell(cells_crossed, rank))(
        jnp.clip(slot, 0, CANDIDATES - 1))
    # the cells' centres (the grids are uniform from 0: no gather of qs and al)
    start = jnp.stack([(iq + 0.5).astype(dtype) * qs[1], (ia + 0.5).astype(dtype) * al[1]],
                      axis=1)
    # a batch runs its Newton loops until the slowest element is done: unused slots (and an
    # element without brackets) start from NaN, which ends their solves at the first pass
    start = jnp.where(used[:, None], start, jnp.nan)

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


def fold_pair_one(G, M, D, disc: PlanarDiscretisation):
    """(alpha_lower, alpha_upper) in radians, converged, Moore-Spence iterations (one
    parameter set; vmap it): the angles of ``fold_pair_states``."""
    z, converged, iterations = fold_pair_states(G, M, D, disc)
    return z[:, -1], converged, iterations


def cast(disc: PlanarDiscretisation, dtype) -> PlanarDiscretisation:
    """The discretisation with its arrays in ``dtype`` (float32 for the fast GPU path)."""
    return jax.tree_util.tree_map(lambda a: a.astype(dtype), disc)


DTYPES = ("float64", "float32")


def fold_pairs(G, M, D, n: int = 12, dtype: str = "float64"):
    """Fold pairs for arrays G, M, D (same shape K): (alphas (K, 2) radians, NaN where not
    converged; converged (K,); max Moore-Spence iterations (K,)). Compiled once per
    (n, dtype, K) (``fold_pairs_program``, which skips the checks).

    The rows are validated first: a row outside ``jaxrod.params.RANGES`` (or NaN) raises
    ParameterError naming it. Matrix products run at full precision of ``dtype`` (GPUs
    otherwise multiply float32 matrices in TF32, which costs float32 three digits and
    Newton its convergence).

    Paper: the two folds of Proposition ``thm:planar_fold`` (Moore-Spence: grad E = 0, H phi
    = 0, l . phi = 1), one pair per row.
    """
    if dtype not in DTYPES:
        raise ParameterError(f"dtype must be one of {DTYPES}, got {dtype!r}")
    check_degree(n, "N-magnet")
    G, M, D = (RANGES[k].check_rows(v) for k, v in (("G-magnet", G), ("M", M), ("D", D)))
    if not G.ndim == 1 or G.shape != M.shape or G.shape != D.shape:
        raise ParameterError(f"G, M, D must be 1-d arrays of one length, got shapes "
                             f"{G.shape}, {M.shape}, {D.shape}")
    return fold_pairs_program(G, M, D, n=n, dtype=dtype)


@jit(static_argnames=("n", "dtype"))
def fold_pairs_program(G, M, D, n: int = 12, dtype: str = "float64"):
    """``fold_pairs`` without the input checks: the compiled program itself (``.lower``)."""
    disc = cast(planar_discretisation(n, "clamped"), dtype)
    G, M, D = (jnp.asarray(v, dtype) for v in (G, M, D))
    with jax.default_matmul_precision("highest"):
        alphas, converged, iterations = jax.vmap(
            lambda g, m, d: fold_pair_one(g, m, d, disc))(G, M, D)
    return jnp.where(converged[:, None], alphas, jnp.nan), converged, iterations
