"""The quasi-static protocol on any scene: an input moved through given values, the rod
following its equilibrium and snapping where it ceases to exist.

At each value lam_k the previous state x_{k-1} is continued by Newton on grad E(x; lam_k) = 0.
The step is *followed* when Newton converges to a stable state (the Hessian's smallest
eigenvalue positive) within an RMS distance 0.1 of x_{k-1}; otherwise a fold was passed and
the rod *snaps*: the energy E(.; lam_k) is descended from x_{k-1} to the stable state it
falls into (``jaxrod.solvers.descent``). The values run in compiled chunks (``lax.scan``),
progress and Ctrl-C acting between them.

The first state is reached the same way: the loads ramped quasi-statically from zero
(``Scene.load_scale`` from 0 to 1 in ``CHUNK`` steps from the unloaded straight rod, the
rod snapping where its loaded equilibrium ceases to exist), by the same compiled program
as the sweep itself.
"""

from __future__ import annotations

import dataclasses
import math

import jax
import jax.numpy as jnp
import numpy as np

from jaxrod.equilibria.equilibrium import (
    DEFAULT_N,
    MODEL,
    NO_REST,
    discretise,
    given_state,
    solve_at,
    tip,
)
from jaxrod.equilibria.trace import path_of
from jaxrod.params import ParameterError
from jaxrod.programs import jit
from jaxrod.progress import Interrupted, interrupt_requested, progress_bar
from jaxrod.scenes.files import FileScene
from jaxrod.scenes.path import ALONG, along
from jaxrod.scenes.scene import Scene
from jaxrod.solvers.descent import descend

#: Values per compiled chunk.
CHUNK = 256
#: A followed step moves the state by at most this RMS (radians); more means a snap.
FOLLOW_RMS = 0.1


def follow_step(model, x_prev, lam, args):
    """(x, snapped, converged) at lam from x_prev (module docstring; traceable)."""
    res = solve_at(model, x_prev, lam, args)
    stable = jnp.linalg.eigvalsh(model.hessian(res.x, lam, args))[0] > 0.0
    close = jnp.sqrt(jnp.mean((res.x - x_prev) ** 2)) < FOLLOW_RMS
    followed = res.converged & stable & close

    def snap(_):
        d = descend(model, x_prev, args, lam=lam)
        return d.x, d.converged

    x, ok = jax.lax.cond(followed, lambda _: (res.x, res.converged), snap, None)
    return x, ~followed, ok


def follow_path(model, x0, lams, args):
    """States along the values ``lams`` from x0: (last state, (states, snapped, converged))
    (traceable, one ``lax.scan``)."""
    def step(x, lam):
        x, snapped, ok = follow_step(model, x, lam, args)
        return x, (x, snapped, ok)

    return jax.lax.scan(step, x0, lams)


def _chunk_program(x0, values, path, disc):
    args = (path, disc, 0.0, 1.0, NO_REST)
    end, (xs, snapped, ok) = follow_path(MODEL, x0, values, args)
    observed = jax.vmap(lambda x, v: tip(ALONG(v, args)[0], x, disc))(xs, values)
    return end, xs, snapped, ok, observed


_chunk = jit(_chunk_program)


def _start(scene: Scene, disc, state) -> tuple[jax.Array, bool]:
    """(the state at the first value, whether every step to it converged): ``state`` as
    given (the sweep's first step continues it by Newton), or the loads ramped from zero
    through ``_chunk`` along ``load_scale`` (module docstring)."""
    x0, given = given_state(state, disc)
    if given:
        return x0, True
    loads = along(scene, ("load_scale",))
    x, _, _, ok, _ = _chunk(jnp.zeros(disc.size), np.linspace(0.0, 1.0, CHUNK), loads, disc)
    return x, bool(jnp.all(ok))


@dataclasses.dataclass(frozen=True)
class Sweep:
    """A quasi-static sweep of ``vary`` through ``values``: the state, tip angle (degrees,
    from +z toward +x) and tip position at each value, whether the rod snapped on arriving
    there, whether each step converged; ``complete`` False when interrupted (``reason``)."""

    vary: str
    values: np.ndarray
    states: np.ndarray
    tip_angle_deg: np.ndarray
    tip_position: np.ndarray
    snapped: np.ndarray
    step_converged: np.ndarray
    complete: bool = True
    reason: str | None = None

    @property
    def converged(self) -> bool:
        return bool(np.all(self.step_converged))

    @property
    def snaps(self) -> list[dict]:
        """Where the rod snapped: the value and the tip before and after."""
        return [{"value": float(self.values[i]),
                 "tip_before_deg": float(self.tip_angle_deg[i - 1]) if i else math.nan,
                 "tip_after_deg": float(self.tip_angle_deg[i])}
                for i in np.nonzero(self.snapped)[0]]


def sweep(scene: Scene | FileScene, vary: str, values, n: int = DEFAULT_N, state=None,
          progress: bool = True) -> Sweep:
    """Move the input ``vary`` of ``scene`` through ``values`` quasi-statically (module
    docstring), from the equilibrium at the first value reached by ramping the loads from
    zero, or from ``state``. Ctrl-C raises ``jaxrod.Interrupted`` whose ``partial`` is the
    sweep so far.

    Paper: the experiment's protocol (eq. ``intro-hysteresis``), for any scene and input.
    """
    values = np.asarray(values, float).ravel()
    if values.size < 2 or not np.all(np.isfinite(values)):
        raise ParameterError(f"values of {vary}: at least two finite values, got {values.size}")
    path, _ = path_of(scene, vary, float(values.min()), float(values.max()))
    disc = discretise(path.template, n)
    x, started = _start(path.at_host(float(values[0])), disc, state)
    parts = []
    bar = progress_bar(values.size, "sweep", unit="value", enabled=progress)

    def result(reason):
        done = sum(p[0].shape[0] for p in parts)
        cols = [np.concatenate([p[j] for p in parts]) if parts else np.zeros(0)
                for j in range(5)]
        return Sweep(vary, values[:done], cols[0], np.degrees(cols[3]), cols[4],
                     cols[1].astype(bool), cols[2].astype(bool), reason is None, reason)

    done = 0
    try:
        for lo in range(0, values.size, CHUNK):
            chunk = values[lo:lo + CHUNK]
            padded = np.pad(chunk, (0, CHUNK - chunk.size), mode="edge")
            _, xs, snapped, ok, (angle, X) = jax.device_get(
                _chunk(x, jnp.asarray(padded), path, disc))
            k = chunk.size
            # the state after the last real value (padding repeats it: the same state)
            x = jnp.asarray(xs[k - 1])
            parts.append((xs[:k], snapped[:k], ok[:k] & started, angle[:k], X[:k]))
            done += k
            bar.update(k)
            if interrupt_requested() and done < values.size:
                raise KeyboardInterrupt
    except KeyboardInterrupt:
        raise Interrupted(result(f"interrupted (Ctrl-C) after {done} of {values.size} "
                                 "values"), "sweep") from None
    finally:
        bar.close()
    return result(None)
