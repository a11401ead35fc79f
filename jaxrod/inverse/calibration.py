"""The switching angles of a design point as a differentiable model, and the one
least-squares program that both calibrates (``jaxrod.inverse.fit``) and designs
(``jaxrod.inverse.design``) with it.

The experiment's four switching angles, in the order of its protocol,

    cw_capture = -alpha_lower + delta,   cw_release = alpha_upper + delta,
    ccw_capture = alpha_lower + delta,   ccw_release = -alpha_upper + delta,

are the folds alpha_lower < alpha_upper of the planar branch at the groups (G, M, D) of a
design point (``jaxrod.design_point.DesignPoint``: the groups themselves, or the nine
physical inputs through ``groups_of``) and an angular offset delta of the track (degrees).

The parameters are p = (log(v / v0), delta): relative log changes of the point's values v
from the start v0 (every value is positive, and relative changes are scale-free) and the
offset. Which entries are free, the priors, the bounds and the data are arrays of one
``Problem``: one compiled program per kind of point serves every subset of free
parameters, every prior and every data set. The residuals are

    r = [ (model_i - measured_i) / sigma   for the measured angles,
          (value_j - mean_j) / sd_j        for the free entries with a Gaussian prior ],

minimised by ``jaxrod.solvers.least_squares.least_squares_run`` (optax L-BFGS, Armijo
line search, Gauss-Newton scaling). Each evaluation solves the two folds' Moore-Spence
systems from the fold states of the last accepted point (the folds move smoothly with the
parameters; no continuation), implicitly differentiated (``differentiable_fold``); the
first from the guesses of a continuation from the straight rod (``start_states``). A trial
point outside the bounds, with groups outside their ranges (``jaxrod.params.RANGES``), with
a magnet the rod could touch, or without two folds, is rejected by the line search.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from jaxrod.design_point import groups_of
from jaxrod.discretise.planar import planar_discretisation
from jaxrod.magnet.folds import fold_guesses, valid_groups
from jaxrod.params import GROUP_NAMES, PHYSICAL_NAMES, RANGES, ParameterError, check
from jaxrod.programs import jit
from jaxrod.scenes.dipole import ALPHA_MODEL, DipoleMagnet
from jaxrod.solvers.folds import differentiable_fold
from jaxrod.solvers.least_squares import LeastSquaresResult, least_squares_run
from jaxrod.stored import StoredProgram

ANGLE_NAMES = ("cw_capture", "cw_release", "ccw_capture", "ccw_release")
SIGNS = jnp.array([-1.0, 1.0, 1.0, -1.0])  # fold angle sign per measured angle
FOLD = jnp.array([0, 1, 0, 1])  # lower / upper fold per measured angle


def sign_hint(measured, mask) -> str | None:
    """A hint when the measured angles' signs are the opposite of the convention (every
    measured angle beyond 2 degrees with the other sign): the clockwise sweep captures at
    -alpha_lower and releases at +alpha_upper, the counter-clockwise sweep the reverse
    (magnet angles positive towards e1)."""
    m = np.asarray(measured, float)[np.asarray(mask, bool)]
    expected = np.asarray(SIGNS)[np.asarray(mask, bool)]
    big = np.abs(m) > 2.0
    if big.sum() >= 2 and np.all(np.sign(m[big]) == -expected[big]):
        return ("the angles' signs are the opposite of the convention: in the order "
                f"{', '.join(ANGLE_NAMES)} they are -, +, +, - (capture at -alpha_lower in "
                "the clockwise sweep, magnet angles positive towards e1): change the signs")
    return None


def parse_angles(measured, sigma_deg):
    """The four measured angles as an array (nan where not measured) and which were
    measured; ParameterError names what is wrong (count, infinities, none measured, an
    angle outside (-90, 90) degrees, sigma)."""
    try:
        measured = np.asarray(measured, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        raise ParameterError(f"angles: give 4 numbers ({', '.join(ANGLE_NAMES)}), got "
                             f"{measured!r:.60}") from None
    if measured.size != 4:
        raise ParameterError(f"angles: give 4 values ({', '.join(ANGLE_NAMES)}), with nan for "
                             f"a missing one; got {measured.size}")
    if np.any(np.isinf(measured)):
        raise ParameterError(f"angles: must be finite, or nan for one not measured; got "
                             f"{measured.tolist()}")
    mask = ~np.isnan(measured)
    if mask.sum() == 0:
        raise ParameterError("angles: at least one measured angle is needed")
    check("sigma-deg", sigma_deg)
    angle = RANGES["angle"]
    bad = [name for name, v, m in zip(ANGLE_NAMES, measured, mask) if m and not angle.contains(v)]
    if bad:
        raise ParameterError(f"angles: switching angles must lie in {angle.interval()}; "
                             f"{', '.join(bad)} do not")
    return measured, mask


#: Moore-Spence discretisation of the model (the fold angles reach round-off by N = 12).
MODEL_N = 12
OFFSET = "offset"


def parameter_names(kind: str) -> tuple[str, ...]:
    """The entries of p for a kind of point: its values, then the offset."""
    return (GROUP_NAMES if kind == "groups" else PHYSICAL_NAMES) + (OFFSET,)


class Problem(NamedTuple):
    """One fit or design, as arrays (K values of the point, K + 1 parameters).

    v0: the point's values (start, and the values of the fixed inputs); radius: magnet
    radius / rod length (groups points; physical points take it from their values);
    measured, mask (4,): the angles (degrees) and which were measured; sigma: their
    standard deviation (degrees); free (K + 1,): which parameters vary; prior_mean,
    prior_sd, has_prior (K + 1,): Gaussian priors in the values' units (offset: degrees);
    lower, upper (K + 1,): bounds in the same units; p_start (K + 1,): the start.
    """

    v0: jax.Array
    radius: jax.Array
    measured: jax.Array
    mask: jax.Array
    sigma: jax.Array
    free: jax.Array
    prior_mean: jax.Array
    prior_sd: jax.Array
    has_prior: jax.Array
    lower: jax.Array
    upper: jax.Array
    p_start: jax.Array


def values_of(problem: Problem, p):
    """The point's values and the offset at p: (v0 exp(p[:K]), p[K])."""
    return problem.v0 * jnp.exp(p[:-1]), p[-1]


def physical_parameters(problem: Problem, p):
    """All K + 1 parameters in their own units (values, then the offset in degrees)."""
    values, offset = values_of(problem, p)
    return jnp.concatenate([values, offset[None]])


def _scene(kind: str, problem: Problem, values):
    G, M, D = groups_of(kind, values)
    radius = problem.radius if kind == "groups" else 0.5 * values[7] / values[4]
    valid = valid_groups(G, M, D) & (D > 1.0 + radius)
    return DipoleMagnet(G, M, D, jnp.zeros_like(G)), valid


def angles_from_folds(alphas, offset):
    """The four switching angles (degrees) from the folds (radians, lower first)."""
    return SIGNS * jnp.degrees(alphas[FOLD]) + offset


def _in_bounds(problem: Problem, p):
    q = physical_parameters(problem, p)
    return jnp.all(~problem.free | ((q >= problem.lower) & (q <= problem.upper)))


def fold_states_at(scene: DipoleMagnet, z, disc):
    """The two folds' Moore-Spence solutions from states z (2, 2m + 1) at nearby
    parameters, implicitly differentiable in the scene, lower fold first: (z_new, ok); ok is
    False when a solve fails or the folds leave 0 < lower < upper <= 90 degrees."""
    m = disc.size
    z_new, stats = jax.vmap(lambda zi: differentiable_fold(
        ALPHA_MODEL, zi[:m], zi[-1], zi[m:2 * m], (scene, disc)))(z)
    z_new = jnp.where(z_new[0, -1] <= z_new[1, -1], z_new, z_new[::-1])  # lower fold first
    alphas = z_new[:, -1]
    ok = jnp.all(stats[:, 0] == 1.0) & (alphas[0] > 0.0) & (alphas[1] - alphas[0] > 1e-9) \
        & (alphas[1] <= 0.5 * jnp.pi)
    return z_new, ok


def tracked_angles(kind: str, problem: Problem, p, z, disc):
    """The four switching angles (degrees) at p from fold states z at nearby parameters:
    (angles, z_new, ok); ok also requires the point within its valid ranges and bounds."""
    values, offset = values_of(problem, p)
    scene, valid = _scene(kind, problem, values)
    z_new, ok = fold_states_at(scene, z, disc)
    return angles_from_folds(z_new[:, -1], offset), z_new, ok & valid & _in_bounds(problem, p)


def _prior_residuals(problem: Problem, q):
    """(q - mean) / sd for the free parameters with a prior (0 elsewhere), and 1 / sd there
    (0 elsewhere): the residuals and their derivative in q."""
    use = problem.has_prior & problem.free
    scale = jnp.where(use, 1.0 / jnp.where(use, problem.prior_sd, 1.0), 0.0)
    return (q - problem.prior_mean) * scale, scale


def residuals(kind: str, problem: Problem, p, z, disc):
    """(r, z_new, ok): the angle residuals (4) and the prior residuals (K + 1) at p."""
    model, z_new, ok = tracked_angles(kind, problem, p, z, disc)
    target = jnp.where(problem.mask, problem.measured, 0.0)
    r_data = jnp.where(problem.mask, (model - target) / problem.sigma, 0.0)
    q = physical_parameters(problem, p)
    r_prior, _ = _prior_residuals(problem, q)
    return jnp.concatenate([r_data, r_prior]), z_new, ok


def evaluate(kind: str, problem: Problem, p, z, disc):
    """(r, J, z_new, ok) for ``least_squares_run``: r = the angle residuals (4) and the
    prior residuals (K + 1), J = dr/dp by the chain rule through the groups: the folds are
    differentiated in (G, M, D) only (three tangents, whatever the number of parameters),
    the groups in p by forward mode (arithmetic), the offset and the priors in closed form.
    """
    values, offset = values_of(problem, p)
    groups_p = lambda q: jnp.stack(groups_of(kind, values_of(problem, q)[0]))
    g, dg_dp = groups_p(p), jax.jacfwd(groups_p)(p)  # (3,), (3, K + 1)
    radius = problem.radius if kind == "groups" else 0.5 * values[7] / values[4]
    valid = valid_groups(*g) & (g[2] > 1.0 + radius)

    def folds(gv):
        z_new, ok = fold_states_at(DipoleMagnet(gv[0], gv[1], gv[2], jnp.zeros_like(gv[0])),
                                   z, disc)
        return jnp.degrees(z_new[:, -1]), (z_new, ok)

    dalpha_dg, (z_new, ok) = jax.jacfwd(folds, has_aux=True)(g)  # (2, 3)
    alphas_deg = jnp.degrees(z_new[:, -1])
    model = SIGNS * alphas_deg[FOLD] + offset
    d_model = (SIGNS[:, None] * dalpha_dg[FOLD]) @ dg_dp  # (4, K + 1)
    d_model = d_model.at[:, -1].add(1.0)
    target = jnp.where(problem.mask, problem.measured, 0.0)
    m = problem.mask[:, None]
    r_data = jnp.where(problem.mask, (model - target) / problem.sigma, 0.0)
    J_data = jnp.where(m, d_model / problem.sigma, 0.0)
    q = jnp.concatenate([values, offset[None]])
    dq = jnp.concatenate([values, jnp.ones(1)])  # dq_i / dp_i (diagonal)
    r_prior, scale = _prior_residuals(problem, q)
    J_prior = jnp.diag(dq * scale)
    ok = ok & valid & _in_bounds(problem, p)
    return (jnp.concatenate([r_data, r_prior]), jnp.concatenate([J_data, J_prior]), z_new, ok)


def start_states(scene: DipoleMagnet, disc):
    """Guesses of the two fold states (2, 2m + 1) at the start, and whether both exist:
    the continuation from the straight rod (``jaxrod.magnet.folds.fold_guesses``, which
    finds narrow loops too). The first evaluation of the fit solves their Moore-Spence
    systems (``fold_states_at``), as every later one does from the last accepted states.
    (Starting from the one-mode brackets where they succeed saves ~2 ms per fit and costs
    ~1.8 s more compilation; under vmap both would run.)"""
    x0, lam0, phi0, found = fold_guesses(scene, disc)
    return jnp.concatenate([x0, phi0, lam0[:, None]], axis=1), found


class Solution(NamedTuple):
    """A solved problem: the least-squares result, whether the start states existed, and
    the model angles at the answer (degrees)."""

    result: LeastSquaresResult
    found: jax.Array
    angles: jax.Array


def _solve(kind: str, problem: Problem, max_iter: int = 60, n: int = MODEL_N) -> Solution:
    disc = planar_discretisation(n, "clamped")
    values, _ = values_of(problem, problem.p_start)
    scene, valid = _scene(kind, problem, values)
    z0, found = start_states(scene, disc)
    found = found & valid
    n_res = 4 + problem.free.shape[0]
    res = least_squares_run(lambda p, z: evaluate(kind, problem, p, z, disc),
                            problem.p_start, z0, problem.free, n_res, found, max_iter)
    # the carried states are the folds at the accepted point
    angles = angles_from_folds(res.aux[:, -1], values_of(problem, res.p)[1])
    return Solution(res, found, angles)


#: One program per kind of point ("groups", "physical"), kept between processes.
solve_program = StoredProgram("calibration", _solve, static_argnames=("kind", "max_iter", "n"))


@jit(static_argnames=("kind", "max_iter"))
def solve_batch(kind: str, problems: Problem, max_iter: int = 60) -> Solution:
    """Many problems of one kind at once (vmapped; the leading axis of every array)."""
    return jax.vmap(lambda pr: _solve(kind, pr, max_iter))(problems)
