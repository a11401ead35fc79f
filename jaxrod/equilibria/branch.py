"""The equilibrium branch of any scene along any of its inputs.

Pseudo-arclength continuation (``jaxrod.solvers.continuation``) of grad E(x; v) = 0 in the
input v = ``vary`` on the scale v = start + (stop - start) lam, lam from 0 to 1, from the
equilibrium at v = start (ramped from zero loads, or continued from a given state). The
branch is followed round folds; it ends at either end of the range.
"""

from __future__ import annotations

import dataclasses
import math

import jax
import jax.numpy as jnp
import numpy as np

from jaxrod.derivatives import Structured
from jaxrod.equilibria.equilibrium import (
    DEFAULT_N,
    discretise,
    mean_functional,
    ramp,
    solve_at,
    tip,
)
from jaxrod.equilibria.record import Branch, branch_from_runs, first_points
from jaxrod.params import ParameterError
from jaxrod.programs import jit
from jaxrod.scenes.scene import Input, Scene
from jaxrod.solvers.continuation import ContinuationOptions, continuation_run
from jaxrod.status import Status


def branch_options(max_points: int = 400) -> ContinuationOptions:
    """Steps of at most 1/20 of the range; the run ends outside [0, 1] in lam."""
    return ContinuationOptions(ds=0.01, ds_min=1e-9, ds_max=0.05, lam_min=0.0, lam_max=1.0,
                               tol=1e-12, max_points=max_points)


def check_range(scene: Scene, vary: str, start, stop) -> tuple[float, float]:
    """(start, stop) as floats, after checking that ``vary`` names a scalar input."""
    scene.check_key(vary)
    start, stop = float(start), float(stop)
    if not (math.isfinite(start) and math.isfinite(stop)) or start == stop:
        raise ParameterError(f"the range of {vary} must be two different finite values, got "
                             f"{start} to {stop}")
    return start, stop


#: Samples of a magnet's path over a range (then bisection to the value where it enters).
PATH_SAMPLES = 1025


def reach_along(scene: Scene, vary: str, start: float, stop: float,
                margins: dict | None = None) -> float | None:
    """The first value of ``vary`` between ``start`` and ``stop`` at which a magnet enters
    the rod's reach (``Scene.clearance`` reaches zero), or None if the whole path stays
    clear. Only an input of a magnet's term moves a magnet; its path is sampled at
    ``PATH_SAMPLES`` values and the entry refined by bisection to round-off.
    ParameterError if a magnet is within reach at ``start`` itself."""
    if scene.replace(vary, start).clearance(margins) <= 0.0:
        raise ParameterError(f"{vary}: at {start:g} a magnet is within the rod's reach (its "
                             "centre must lie farther from the clamp than the rod's length)")
    term = vary.split(".")[0]
    if not hasattr(scene.terms.get(term), "centre"):
        return None
    gap = lambda v: scene.replace(vary, v).clearance(margins)
    values = np.linspace(start, stop, PATH_SAMPLES)
    gaps = np.array([gap(v) for v in values])
    inside = np.nonzero(gaps <= 0.0)[0]
    if len(inside) == 0:
        return None
    lo, hi = values[inside[0] - 1], values[inside[0]]
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if mid in (lo, hi):
            break
        lo, hi = (mid, hi) if gap(mid) > 0.0 else (lo, mid)
    return float(lo)


def _observed(scene, disc, x, lam, origin, span, vary):
    at = scene.replace(vary, origin + span * lam)
    angle, X = tip(at, x, disc)
    energy = Structured(Input(vary)).energy(x, lam, (scene, disc, origin, span))
    return mean_functional(disc)(x), angle, energy, X


def _branch_program(scene, disc, origin, span, x0, given, opts, capacity, vary):
    at_start = scene.replace(vary, origin)
    x_ramp, *_ = ramp(at_start, disc)
    model = Structured(Input(vary))
    args = (scene, disc, origin, span)
    start = jnp.where(given, x0, x_ramp)
    start = solve_at(model, start, 0.0, args).x
    run = continuation_run(model, start, 0.0, args, opts, capacity, 1.0)
    q, angle, energy, X = jax.vmap(
        lambda x, lam: _observed(scene, disc, x, lam, origin, span, vary))(run.x, run.lam)
    return run, (q, angle, energy), X


_program = jit(_branch_program, static_argnames=("capacity", "vary"))


def branch(scene: Scene, vary: str, start: float, stop: float, n: int = DEFAULT_N,
           state=None, options: ContinuationOptions | None = None,
           margins: dict | None = None) -> Branch:
    """The equilibria of ``scene`` as the input ``vary`` goes from ``start`` to ``stop``.

    Equilibria solve grad E(x; v) = 0 (the discrete Euler-Lagrange equations); stability is
    the Hessian's inertia (``Branch.stable``). The branch starts from the equilibrium at
    v = start reached by ramping the loads from zero, or continued from ``state``.
    ``Branch.value`` holds v; ``Branch.status`` says why it ended. A path that brings a
    magnet within the rod's reach (``reach_along``; ``margins``: the magnets' radii by term
    name) is followed up to the value where it enters, and ends there with status
    ``MAGNET_IN_REACH`` (``complete`` False).
    """
    start, stop = check_range(scene, vary, start, stop)
    entry = reach_along(scene, vary, start, stop, margins)
    end = stop if entry is None else entry
    disc = discretise(scene, n)
    opts = options or branch_options()
    given = state is not None
    x0 = jnp.asarray(state if given else np.zeros(disc.size), jnp.float64)
    run, observed, X = jax.device_get(_program(
        scene, disc, start, end - start, x0, given, opts._replace(max_points=0),
        opts.max_points, vary))
    # lam -> the input's value, and the tangent's lam component in the input's units
    run = run._replace(lam=start + (end - start) * run.lam,
                       tangent_lam=(end - start) * run.tangent_lam)
    b = branch_from_runs([(run, False, observed)])
    b = dataclasses.replace(b, vary=vary, tip_position=np.asarray(X)[:int(run.num_points)])
    if entry is not None:  # the path brings a magnet into the rod: the part before it
        beyond = (b.value - entry) * math.copysign(1.0, stop - start) > 0.0
        k = len(b) - int(np.argmax(~beyond[::-1])) if not beyond.all() else 1
        b = dataclasses.replace(first_points(b, k),
                                status=b.status + (Status.MAGNET_IN_REACH,), complete=False)
    return b
