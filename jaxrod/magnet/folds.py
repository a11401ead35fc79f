"""Folds of the permanent magnet's diagram: refined by Moore-Spence with their normal form
(``locate_folds``), the two fold angles in one program (``fold_angles``, differentiable),
and the report (paper, Proposition "Planar saddle-node bifurcation")."""

from __future__ import annotations

import dataclasses
import math

import jax
import jax.numpy as jnp
import numpy as np

from jaxrod.discretise.planar import PlanarDiscretisation, planar_discretisation
from jaxrod.equilibria.folds import Fold as SceneFold
from jaxrod.equilibria.folds import folds as scene_folds
from jaxrod.equilibria.record import Branch
from jaxrod.magnet.diagram import DEFAULT_N, default_options, trace_diagram
from jaxrod.params import RANGES, check, check_degree, check_track_clearance
from jaxrod.programs import jit
from jaxrod.scenes.dipole import (
    ALPHA_MODEL,
    DipoleMagnet,
    preset_or_scene,
    tip_angle,
    tip_position,
)
from jaxrod.solvers.continuation import continuation_run
from jaxrod.solvers.folds import (
    FoldPoint,
    differentiable_fold,
    fold_coefficients,
    moore_spence_solve,
)
from jaxrod.status import SolverError, Status
from jaxrod.stored import StoredProgram


class PaperNames:
    """The paper's names of a magnet-angle fold's common fields (``SceneFold``):
    ``alpha_deg`` (value in degrees), ``tip_deg``, ``dF_dalpha``, ``theta`` (the state)."""

    @property
    def alpha_deg(self) -> float:
        return math.degrees(self.value)

    @property
    def tip_deg(self) -> float:
        return self.tip_angle_deg

    @property
    def dF_dalpha(self) -> float:
        return self.dF_dvalue

    @property
    def theta(self) -> np.ndarray:
        return self.state


@dataclasses.dataclass(frozen=True)
class Fold(PaperNames, SceneFold):
    """A saddle-node of the paper's planar branch in the magnet angle, refined by
    Moore-Spence: the fold record of every scene (``jaxrod.equilibria.folds.Fold``, with
    ``vary`` = "magnet.alpha" and ``value`` in radians) and the paper's extras.

    ``normal_form_c``: alpha - alpha* ~ c (q - q*)^2 (radians); ``tip_parabola_c``:
    alpha - alpha* ~ c_tip (tip - tip*)^2 (radians; the paper's Corollary "Fold in the
    experimental tip displacement angle", c_tip = -F_qq / (2 F_alpha T*^2)); ``kind``
    "lower" or "upper" (or "fold" beyond a pair); ``opens`` the side of the fold where the
    branch lies; ``hessian_smallest`` its two smallest Hessian eigenvalues. The paper's
    names read the common fields (``PaperNames``).
    """

    opens: str = dataclasses.field(default="", kw_only=True)
    kind: str = dataclasses.field(default="fold", kw_only=True)  # the paper's: lower, upper

    def as_dict(self) -> dict:
        return {
            "kind": self.kind, "alpha_deg": self.alpha_deg, "q": self.q, "tip_deg": self.tip_deg,
            "dF_dalpha_sign": int(np.sign(self.dF_dalpha)),
            "d2F_dq2_sign": int(np.sign(self.d2F_dq2)),
            "dF_dalpha": self.dF_dalpha, "d2F_dq2": self.d2F_dq2,
            "normal_form_c": self.normal_form_c, "tip_parabola_c": self.tip_parabola_c,
            "opens": self.opens, "hessian_smallest_eigenvalues": list(self.hessian_smallest),
            "converged": self.converged, "residual_norm": self.residual_norm,
            "iterations": self.iterations,
        }


def _fold_report(fp: FoldPoint, disc: PlanarDiscretisation):
    """The normal form and stability data of a converged fold, from its Moore-Spence
    Jacobian (no new assembly)."""
    x, J = fp.x, fp.newton.jacobian
    d_alpha, d_qq, phi_q = fold_coefficients(None, x, fp.lam, fp.null_vector, None, disc.mean,
                                             jacobian=J)
    c = -d_qq / (2.0 * d_alpha)
    X = tip_position(x, disc)
    V = jax.jvp(lambda th: tip_position(th, disc), (x,), (phi_q,))[1]
    T = (X[1] * V[0] - X[0] * V[1]) / jnp.dot(X, X)
    m = x.shape[0]
    eigs = jnp.linalg.eigvalsh(J[:m, :m])
    return (d_alpha, d_qq, c, c / T**2, disc.mean(x), tip_angle(x, disc), eigs[:2], phi_q, X)


def _refine_one(theta0, alpha0, scene, disc, tol):
    args = (scene, disc)
    _, V = jnp.linalg.eigh(ALPHA_MODEL.hessian(theta0, alpha0, args))
    fp = moore_spence_solve(ALPHA_MODEL, theta0, alpha0, V[:, 0], args, tol)
    return fp, _fold_report(fp, disc)


def _refine_program(theta0, alpha0, scene, disc, tol):
    return jax.vmap(_refine_one, in_axes=(0, 0, None, None, None))(theta0, alpha0, scene, disc,
                                                                    tol)


_refine_batch = StoredProgram("magnet-refine", _refine_program)


#: Capacity of the continuation that finds the fold guesses (alpha up to 90 degrees).
FOLD_PAIR_CAPACITY = 128


def run_to_second_fold(scene: DipoleMagnet, disc: PlanarDiscretisation,
                       alpha_max: float = math.pi / 2, capacity: int = FOLD_PAIR_CAPACITY):
    """The continuation in alpha from the straight rod at alpha = 0 that stops after the
    second fold (or at ``alpha_max``), and its approximate folds: (run, states, angles,
    null-vector guesses, number of folds passed).

    The straight rod is an equilibrium at alpha = 0 for every (G, M, D) by the mirror
    symmetry theta -> -theta of E_perm there (no Newton solve needed; the run records its
    residual). At the recorded point nearest each fold the state part of the branch's
    tangent is the null-vector guess (at the fold it is the Hessian's kernel).
    """
    options = default_options(0)._replace(max_folds=2.0, lam_min=-0.1, lam_max=alpha_max)
    raw = continuation_run(ALPHA_MODEL, jnp.zeros(disc.size), 0.0, (scene, disc), options,
                           capacity, 1.0, spectrum=False)
    t = raw.tangent_lam
    change = t[:-1] * t[1:] < 0.0
    i = jnp.nonzero(change, size=2, fill_value=0)[0]
    j = jnp.where(jnp.abs(t[i]) <= jnp.abs(t[i + 1]), i, i + 1)
    return raw, raw.x[j], raw.lam[j], raw.tangent_x[j], jnp.sum(change)


def fold_guesses(scene: DipoleMagnet, disc: PlanarDiscretisation):
    """Approximate folds in (0, 90] degrees (``run_to_second_fold``): (states, angles,
    null-vector guesses, found)."""
    raw, x, lam, phi, folds = run_to_second_fold(scene, disc)
    found = (raw.residual_norm[0] <= default_options().tol) & (folds >= 2)
    return x, lam, phi, found


def fold_angles(G, M, D, n: int = 12, tol: float = 1e-13):
    """(alpha_lower, alpha_upper) in radians and a converged flag, differentiable in G, M, D.

    Pure JAX (jit, vmap and grad compose): the fold guesses come from a one-sided
    continuation (no gradient flows through it) and each fold is the implicitly
    differentiated solution of its Moore-Spence system (``differentiable_fold``). Assumes
    the S-shaped diagram; ``converged`` is False, and the angles NaN, when two folds are not
    found in (0, 90] degrees, a Moore-Spence solve fails or (G, M, D) lie outside their
    valid ranges (``jaxrod.params.RANGES``). Concrete inputs are validated (ParameterError);
    traced ones are checked inside the program. Compiled once per (n, tol): later calls
    with new values, and ``jax.grad`` of it, reuse the program.

    Each fold solves grad E = 0, H phi = 0, l . phi = 1 in (theta, phi, alpha). Paper:
    Proposition ``thm:planar_fold``.
    """
    if not any(isinstance(v, jax.core.Tracer) for v in (G, M, D)):
        check("G-magnet", G)
        check("M", M)
        check_track_clearance(D)
        check_degree(n, "N-magnet")
    return _fold_angles_program(G, M, D, n=n, tol=tol)


def valid_groups(G, M, D):
    """Inside a program: whether (G, M, D) lie in their valid ranges (``RANGES``)."""
    return (RANGES["G-magnet"].contains(G) & RANGES["M"].contains(M)
            & RANGES["D"].contains(D))


@jit(static_argnames=("n", "tol"))
def _fold_angles_program(G, M, D, n: int, tol: float):
    valid = valid_groups(G, M, D)
    G, M, D = (jnp.where(valid, v, x) for v, x in zip((G, M, D), (1.0, 0.0, 2.0)))
    scene = DipoleMagnet(G, M, D, 0.0)
    disc = planar_discretisation(n, "clamped")
    x0, lam0, phi0, found = fold_guesses(jax.lax.stop_gradient(scene), disc)
    solve = lambda x, l, p: differentiable_fold(ALPHA_MODEL, x, l, p, (scene, disc), tol)
    z, stats = jax.vmap(solve)(x0, lam0, phi0)
    alphas = jnp.sort(z[:, -1])
    converged = valid & found & jnp.all(stats[:, 0] == 1.0) & (alphas[1] - alphas[0] > 1e-9)
    return jnp.where(converged, alphas, jnp.nan), converged


def fold_pair(scene: DipoleMagnet, n: int = 12, tol: float = 1e-13, throw: bool = True):
    """Fast path to (alpha_lower, alpha_upper) in degrees, and whether both converged.

    One compiled call of ``fold_angles``: continuation from the straight rod towards
    alpha > 0 that stops after the second fold, then both Moore-Spence solves (vmapped).
    N = 12 reaches the round-off floor at the paper's parameters (use ``locate_folds`` for
    the full report and diagram). ``throw`` (default, as every host entry point):
    raise ``SolverError`` (NOT_CONVERGED); False: NaN angles with False.
    """
    alphas, converged = fold_angles(scene.G, scene.M, scene.D, n=n, tol=tol)
    if throw and not bool(converged):
        raise SolverError(Status.NOT_CONVERGED, "fold_pair: no two converged folds in (0, 90] "
                          "degrees")
    return np.degrees(np.asarray(alphas)), bool(converged)


def refine_folds(scene: DipoleMagnet, disc: PlanarDiscretisation, theta0, alpha0,
                 tol: float = 1e-13) -> list[Fold]:
    """Moore-Spence from approximate folds (rows of theta0, alpha0), all in one vmapped call.

    The null-vector guess is the lowest eigenvector of the Hessian at each start.
    """
    theta0 = np.atleast_2d(np.asarray(theta0, np.float64))
    alpha0 = np.atleast_1d(np.asarray(alpha0, np.float64))
    # on the host at once: indexing device arrays would compile a program per index
    fp, rep = jax.device_get(_refine_batch(theta0, alpha0, scene, disc, tol))
    folds = []
    for i in range(alpha0.shape[0]):
        d_alpha, d_qq, c, c_tip, q, tip, eigs, phi_q, X = (np.asarray(v[i]) for v in rep)
        conv = bool(fp.newton.converged[i])
        folds.append(Fold(
            vary="magnet.alpha", value=float(fp.lam[i]), tip_angle_deg=math.degrees(float(tip)),
            tip_position=np.array([X[0], 0.0, X[1]]), state=np.asarray(fp.x[i]),
            null_vector=phi_q, converged=conv, residual_norm=float(fp.newton.residual_norm[i]),
            iterations=int(fp.newton.iterations[i]),
            status=Status.of(conv), q=float(q),
            dF_dvalue=float(d_alpha), d2F_dq2=float(d_qq), normal_form_c=float(c), kind="",
            tip_parabola_c=float(c_tip),
            opens="increasing alpha" if float(c) > 0 else "decreasing alpha",
            hessian_smallest=(float(eigs[0]), float(eigs[1]))))
    return folds


@dataclasses.dataclass(frozen=True)
class FoldReport:
    """Folds with alpha > 0 (lower first), the hysteresis width, and the diagram."""

    folds: list[Fold]
    branch: Branch
    n: int
    problems: tuple[str, ...] = ()
    scene: DipoleMagnet | None = None

    @property
    def converged(self) -> bool:
        return self.branch.complete and all(f.converged for f in self.folds) \
            and not self.problems

    @property
    def status(self) -> Status:
        return Status.of(self.converged)

    @property
    def hysteresis_width_deg(self) -> float | None:
        kinds = {f.kind: f for f in self.folds}
        if "lower" in kinds and "upper" in kinds:
            return kinds["upper"].alpha_deg - kinds["lower"].alpha_deg
        return None

    def as_dict(self) -> dict:
        return {"folds": [f.as_dict() for f in self.folds],
                "hysteresis_width_deg": self.hysteresis_width_deg,
                "converged": self.converged, "n": self.n,
                "branch_status": list(self.branch.status), "problems": list(self.problems)}


def locate_folds(scene: DipoleMagnet, n: int = DEFAULT_N, branch: Branch | None = None,
                 tol: float = 1e-13, throw: bool = True) -> FoldReport:
    """Detect the folds on the diagram and refine those with alpha > 0.

    The two folds with alpha > 0 are named by their angle: ``upper`` (the engaged branch
    turns back; release in a sweep of increasing alpha) and ``lower`` (the disengaged
    branch turns back; capture). Folds at alpha < 0 are their mirror images. With no
    fold (no bistability) the list is empty.

    A fold solves grad E = 0, H phi = 0, l . phi = 1 (Moore-Spence) with dF/dalpha != 0 and
    d2F/dq2 != 0. Paper: Proposition ``thm:planar_fold``, Corollary ``cor:tip_angle_fold``;
    the numbers of Corollary ``cor:permanent_physical_parameters``.

    ``throw`` (default, as every host entry point): raise ``SolverError`` (NOT_CONVERGED,
    naming the problems) where the report is not converged; False: the report says so
    (``converged`` and ``status``).
    """
    disc = planar_discretisation(check_degree(n, "N-magnet"), "clamped")
    given = branch is not None
    branch = branch or trace_diagram(scene, n)
    report = _folds_on(scene, disc, branch, n, tol)
    options = default_options()
    for _ in range(2):  # near the cusp the two folds can fall within one step: refine it
        if given or not report.problems:
            break
        options = options._replace(ds_max=0.2 * options.ds_max, max_points=2 * options.max_points)
        report = _folds_on(scene, disc, trace_diagram(scene, n, options), n, tol)
    if throw and not report.converged:
        bad = [f.kind for f in report.folds if not f.converged]
        why = list(report.problems) + ([f"fold(s) {', '.join(bad)} not converged"] if bad
                                       else []) + ([] if report.branch.complete else
                                                   ["the diagram did not reach its end"])
        raise SolverError(Status.NOT_CONVERGED, "locate_folds: " + "; ".join(why))
    return report


#: A branch whose smallest Hessian eigenvalue dips below this with no fold detected is
#: re-traced with a finer step (two folds near a cusp can hide inside one step).
NEAR_SINGULAR = 1e-2


def _folds_on(scene, disc, branch: Branch, n: int, tol) -> FoldReport:
    starts = []
    for i in branch.fold_indices:
        j = i if abs(branch.tangent_alpha[i]) < abs(branch.tangent_alpha[i + 1]) else i + 1
        if branch.alpha[j] > 0.0:
            starts.append(j)
    folds = refine_folds(scene, disc, branch.theta[starts], branch.alpha[starts], tol) \
        if starts else []
    folds.sort(key=lambda f: f.alpha_deg)
    problems = []
    same = [i for i in range(len(folds) - 1)
            if abs(folds[i + 1].alpha_deg - folds[i].alpha_deg) < 1e-7
            and abs(folds[i + 1].q - folds[i].q) < 1e-7]
    if same:
        # two starts reached one fold: it is listed once, and the branch is re-traced with a
        # finer step (``locate_folds``) to find the fold that was missed
        problems.append(f"{len(same)} fold start(s) converged to a fold already found: the "
                        "folds lie close together (near a cusp) for the continuation's step")
        folds = [f for i, f in enumerate(folds) if i - 1 not in same]
    if len(folds) == 2:
        folds = [dataclasses.replace(folds[0], kind="lower"),
                 dataclasses.replace(folds[1], kind="upper")]
    else:
        folds = [dataclasses.replace(f, kind="fold") for f in folds]
    if not folds and np.nanmin(np.abs(branch.min_eig)) < NEAR_SINGULAR:
        problems.append(f"no fold detected, but the Hessian's smallest eigenvalue comes within "
                        f"{NEAR_SINGULAR:g} of zero: two folds may hide within one continuation "
                        "step (parameters near the cusp)")
    return FoldReport(folds=folds, branch=branch, n=n, problems=tuple(problems), scene=scene)


def folds(scene, vary: str | None = None, start: float | None = None,
          stop: float | None = None, n: int = DEFAULT_N, **options):
    """The folds of any scene, or rig from ``jaxrod.load_scene``, along the input ``vary``
    from ``start`` to ``stop``: in the order met, each refined by Moore-Spence with its
    normal form and its ``value`` (``jaxrod.equilibria.folds.folds``; ``options``: state,
    throw, margins). A rig's every number can be ``vary`` (``rod.youngs_modulus``, in the
    file's units).

    The paper's rig as a preset: ``folds(DipoleMagnet(G, M, D))`` without ``vary`` is its
    fold pair in the magnet's angle, named ``lower`` and ``upper`` (``locate_folds``, with
    the near-cusp re-trace; ``options``: branch, tol, throw)."""
    return preset_or_scene(scene, vary, lambda s: locate_folds(s, n, **options),
                           lambda s: scene_folds(s, vary, start, stop, n, **options),
                           "the folds are met along")
