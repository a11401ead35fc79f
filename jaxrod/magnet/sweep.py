"""The experiment's quasi-static protocol on the permanent magnet's diagram: the hysteresis
sweep (the rod follows its equilibrium and snaps at the folds) and the square-root law of the
tip angle next to a fold."""

from __future__ import annotations

import math

import jax
import jax.numpy as jnp
import numpy as np

from jaxrod.discretise.planar import planar_discretisation
from jaxrod.equilibria.equilibrium import mean_functional
from jaxrod.equilibria.sweep import Sweep
from jaxrod.equilibria.sweep import sweep as scene_sweep
from jaxrod.magnet.diagram import DEFAULT_N, _equilibrium
from jaxrod.magnet.folds import Fold
from jaxrod.params import check, check_degree
from jaxrod.progress import Interrupted
from jaxrod.scenes.dipole import ALPHA_MODEL, DipoleMagnet, preset_or_scene, tip_angle
from jaxrod.status import SolverError, Status


def hysteresis_sweep(scene: DipoleMagnet, n: int = DEFAULT_N, alpha_max_deg: float = 50.0,
                     step_deg: float = 0.25, progress: bool = False,
                     throw: bool = True) -> dict:
    """The experiment's protocol: alpha from -alpha_max to +alpha_max (clockwise), then back,
    as the generic quasi-static sweep (``jaxrod.equilibria.sweep``) of the paper's scene in
    the magnet's angle: at each position the previous state is continued by Newton; where it
    no longer exists as a nearby stable equilibrium (a fold was passed) the rod snaps,
    descending the energy to the other stable branch. Returns both sweeps with the tip
    angle and q at each position, the snaps on the grid (the first grid angle past a fold)
    and whether every step converged.

    ``progress``: a progress bar. Ctrl-C raises ``jaxrod.progress.Interrupted`` whose
    ``partial`` is this dict for the positions done (``complete`` False, ``reason`` saying
    where). ``throw`` (default, as every host entry point): raise ``SolverError``
    (NOT_CONVERGED) if a step did not converge; False: ``converged`` False in the dict.

    Paper: the loop of eq. ``intro-hysteresis`` and Theorem ``thm:permanent_physical``
    (capture at the lower fold, release at the upper).
    """
    alpha_max_deg = check("alpha-max", alpha_max_deg)
    step_deg = check("step", step_deg)
    n = check_degree(n, "N-magnet")
    up = np.arange(-alpha_max_deg, alpha_max_deg + 0.5 * step_deg, step_deg)
    alphas = np.radians(np.concatenate([up, up[::-1][1:]]))
    try:
        done = scene_sweep(scene.scene, "magnet.alpha", alphas, n, progress=bool(progress))
    except Interrupted as stop:
        raise Interrupted(_as_dict(stop.partial, up.size, n), "sweep") from None
    result = _as_dict(done, up.size, n)
    if throw and not result["converged"]:
        raise SolverError(Status.NOT_CONVERGED, "hysteresis_sweep: a step did not converge")
    return result


def _as_dict(s: Sweep, n_up: int, n: int) -> dict:
    """The generic sweep in the experiment's words: the magnet angle, the direction."""
    alpha_deg = np.degrees(s.values)
    q = np.asarray(jax.vmap(mean_functional(planar_discretisation(n, "clamped")))(s.states)) \
        if len(s.values) else np.zeros(0)
    direction = np.where(np.arange(alpha_deg.size) < n_up, "cw", "ccw")
    snaps = [{"direction": str(direction[i]), "alpha_deg": float(alpha_deg[i]),
              "tip_before_deg": float(s.tip_angle_deg[i - 1]),
              "tip_after_deg": float(s.tip_angle_deg[i])}
             for i in np.nonzero(s.snapped)[0]]
    return {"alpha_deg": alpha_deg, "tip_deg": np.asarray(s.tip_angle_deg), "q": q,
            "snapped": np.asarray(s.snapped), "direction": direction, "snaps": snaps,
            "converged": s.converged, "complete": s.complete, "reason": s.reason}


def square_root_law(scene: DipoleMagnet, fold: Fold, n: int = DEFAULT_N,
                    offsets_deg=np.geomspace(1e-5, 1e-2, 7)) -> dict:
    """Fit the exponent p in |tip - tip*| ~ |alpha - alpha*|^p on both branches at a fold.

    Returns, for the branch with q > q* and the one with q < q*, the fitted exponent, whether
    all solves converged, and whether that branch is stable.

    Equilibria at alpha* - sign(c) delta (the side where they exist) are found by Newton
    from the fold state shifted along the null vector by the normal form,
    q - q* = +-sqrt(delta / |c|); the exponent is the least-squares slope in log-log.

    Paper: Corollary ``cor:tip_angle_fold`` (tip - tip* ~ sqrt(alpha - alpha*) at a fold).
    """
    disc = planar_discretisation(n, "clamped")
    a_star = math.radians(fold.alpha_deg)
    out = {}
    for side, sign in (("q > q*", 1.0), ("q < q*", -1.0)):
        dtips, ok = [], True
        for d in np.radians(offsets_deg):
            alpha = a_star + math.copysign(d, fold.normal_form_c)
            dq = math.sqrt(d / abs(fold.normal_form_c))
            guess = jnp.asarray(fold.theta + sign * dq * fold.null_vector)
            res = _equilibrium(guess, alpha, scene, disc)
            ok &= bool(res.converged)
            dtips.append(abs(float(tip_angle(res.x, disc)) - math.radians(fold.tip_deg)))
        H = ALPHA_MODEL.hessian(res.x, alpha, (scene, disc))
        slope = np.polyfit(np.log(np.radians(offsets_deg)), np.log(dtips), 1)[0]
        out[side] = {"exponent": float(slope), "converged": ok,
                     "stable": bool(jnp.linalg.eigvalsh(H)[0] > 0.0)}
    return out


def sweep(scene, vary: str | None = None, values=None, n: int = DEFAULT_N, **options):
    """Move the input ``vary`` of any scene, or rig from ``jaxrod.load_scene``, through
    ``values`` quasi-statically, the rod snapping where its equilibrium ceases to exist
    (``jaxrod.equilibria.sweep.sweep``; ``options``: state, progress).

    The paper's rig as a preset: ``sweep(DipoleMagnet(G, M, D))`` without ``vary`` is the
    experiment's protocol, the magnet's angle to +-alpha_max and back
    (``hysteresis_sweep``; ``options``: alpha_max_deg, step_deg, progress, throw)."""
    return preset_or_scene(scene, vary, lambda s: hysteresis_sweep(s, n, **options),
                           lambda s: scene_sweep(s, vary, values, n, **options),
                           "to move (and its values)")
