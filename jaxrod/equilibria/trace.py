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

from jaxrod.equilibria.equilibrium import (
    CAPACITY,
    DEFAULT_N,
    discretise,
    given_state,
    path_program,
)
from jaxrod.equilibria.record import Branch, branch_from_runs, first_points
from jaxrod.params import ParameterError
from jaxrod.programs import jit
from jaxrod.scenes.checks import check_scene, rebuild
from jaxrod.scenes.files import FileScene
from jaxrod.scenes.path import Path, along
from jaxrod.scenes.scene import Scene
from jaxrod.solvers.continuation import ContinuationOptions
from jaxrod.status import Status


def branch_options(max_points: int = CAPACITY) -> ContinuationOptions:
    """Steps of at most 1/20 of the range; the run ends outside [0, 1] in lam."""
    return ContinuationOptions(ds=0.01, ds_min=1e-9, ds_max=0.05, lam_min=0.0, lam_max=1.0,
                               tol=1e-12, max_points=max_points)


def check_range(scene, vary: str, start, stop) -> tuple[float, float]:
    """(start, stop) as floats, after checking that ``vary`` names an input of the scene (or
    a number of the rig)."""
    along(scene, (vary,))
    start, stop = float(start), float(stop)
    if not (math.isfinite(start) and math.isfinite(stop)) or start == stop:
        raise ParameterError(f"the range of {vary} must be two different finite values, got "
                             f"{start} to {stop}")
    return start, stop


def path_of(scene, vary: str, start: float, stop: float, margins: dict | None = None):
    """(path along ``vary``, the magnets' radii by term name): the inputs checked at both
    ends of the range (``jaxrod.scenes.checks``; a rig's numbers by building it there)."""
    path = along(scene, (vary,))
    if margins is None:
        margins = getattr(scene, "margins", None)
    for v in (start, stop):
        at = margins if isinstance(scene, Scene) else rebuild(scene, vary, v).margins
        check_scene(path.at_host(v), at, where=f"{vary} = {v:g}")
    return path, margins


#: Samples of a magnet's path over a range (then bisection to the value where it enters).
PATH_SAMPLES = 1025


def reach_along(path: Path, start: float, stop: float, margins: dict | None = None
                ) -> float | None:
    """The first value of the path's parameter between ``start`` and ``stop`` at which a
    magnet enters the rod's reach (``Scene.clearance`` reaches zero), or None if the whole
    path stays clear. Only a path that moves a magnet's term can bring it in; its path is
    sampled at ``PATH_SAMPLES`` values and the entry refined by bisection to round-off.
    ParameterError if a magnet is within reach at ``start`` itself."""
    vary = path.keys[0] if path.keys else "the input"
    if path.at_host(start).clearance(margins) <= 0.0:
        raise ParameterError(f"{vary}: at {start:g} a magnet is within the rod's reach (its "
                             "centre must lie farther from the clamp than the rod's length)")
    if not any(hasattr(path.template.terms[t], "centre") for t in path.moved_terms()):
        return None
    gap = lambda v: path.at_host(v).clearance(margins)
    values = np.linspace(start, stop, PATH_SAMPLES)
    magnets = [t for t in path.template.terms if hasattr(path.template.terms[t], "centre")]
    gaps = np.asarray(_gaps(path, jnp.asarray(values),
                            {t: float((margins or {}).get(t, 0.0)) for t in magnets}))
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


@jit
def _gaps(path, values, margins):
    """min over the magnets of |centre| - 1 - margin at each value (one vmapped program)."""
    def gap(v):
        scene = path.at(jnp.reshape(v, (1,)))
        return jnp.min(jnp.stack([jnp.linalg.norm(scene.terms[t].centre()) - 1.0 - m
                                  for t, m in margins.items()]))

    return jax.vmap(gap)(values)




def trace(scene: Scene | FileScene, vary: str, start: float, stop: float,
          n: int = DEFAULT_N,
           state=None, options: ContinuationOptions | None = None,
           margins: dict | None = None) -> Branch:
    """The equilibria of ``scene`` (a ``Scene``, or a rig from ``jaxrod.load_scene``) as the
    input ``vary`` goes from ``start`` to ``stop`` (for a rig, any of its numbers, in the
    file's units: ``rod.youngs_modulus``, ``rod.length``; ``jaxrod.scenes.path``).

    Equilibria solve grad E(x; v) = 0 (the discrete Euler-Lagrange equations); stability is
    the Hessian's inertia (``Branch.stable``). The branch starts from the equilibrium at
    v = start reached by ramping the loads from zero, or continued from ``state``.
    ``Branch.value`` holds v; ``Branch.status`` says why it ended. A path that brings a
    magnet within the rod's reach (``reach_along``; ``margins``: the magnets' radii by term
    name) is followed up to the value where it enters, and ends there with status
    ``MAGNET_IN_REACH`` (``complete`` False).
    """
    start, stop = check_range(scene, vary, start, stop)
    path, margins = path_of(scene, vary, start, stop, margins)
    entry = reach_along(path, start, stop, margins)
    end = stop if entry is None else entry
    disc = discretise(path.template, n)
    opts = options or branch_options()
    x0, given = given_state(state, disc)
    run, observed, X, at_start = jax.device_get(path_program(
        path, disc, start, end - start, x0, given, opts._replace(max_points=0),
        opts.max_points))
    # lam -> the input's value, and the tangent's lam component in the input's units
    run = run._replace(lam=start + (end - start) * run.lam,
                       tangent_lam=(end - start) * run.tangent_lam)
    b = branch_from_runs([(run, False, observed)])
    b = dataclasses.replace(b, vary=vary, tip_position=np.asarray(X)[:int(run.num_points)])
    ramp = Status(int(at_start[3]))
    if not ramp.ok:  # the loads' ramp did not reach full load: the start is not the answer
        b = dataclasses.replace(b, status=b.status + (ramp,), complete=False)
    if entry is not None:  # the path brings a magnet into the rod: the part before it
        beyond = (b.value - entry) * math.copysign(1.0, stop - start) > 0.0
        k = len(b) - int(np.argmax(~beyond[::-1])) if not beyond.all() else 1
        b = dataclasses.replace(first_points(b, k),
                                status=b.status + (Status.MAGNET_IN_REACH,), complete=False)
    return b
