"""Sweeps at a finite rate: the input moves at a constant speed and the rod follows
dynamically (``jaxrod.dynamics.integrate``: BDF2 with drag, adaptive steps), so it switches
later than the static fold.

Near a fold the motion reduces to the fold's normal form (``jaxrod.dynamics.normal_form``):
swept at rate eps, the switch lags the fold by an amount that scales as eps^(2/3) where
damping dominates and as eps^(4/5) where inertia does (tests/test_dynamics.py measures both
and the prefactors). A switch is a snap of the tip: a run of steps where the tip's direction
moves faster than ``threshold`` times the fastest it moves in the whole sweep and ten times
its median speed in time (the rod following the input; before the first such step, if lower:
an undamped rod rings on after a snap), runs closer than ``merge`` time units being one snap
and its ringing; its value is where the tip is fastest in the first run.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from jaxrod.dynamics.integrate import Trajectory, simulate
from jaxrod.equilibria.equilibrium import DEFAULT_N
from jaxrod.params import ParameterError
from jaxrod.scenes.scene import Scene


@dataclasses.dataclass(frozen=True)
class RateSweep:
    """``values``: the input at the end of each step; ``switches``: the input where the rod
    snapped, in sweep order; ``trajectory``: the motion."""

    vary: str
    values: np.ndarray
    switches: list
    trajectory: Trajectory

    def as_dict(self) -> dict:
        return {"vary": self.vary, "values": self.values.tolist(), "switches": self.switches,
                "time": self.trajectory.time.tolist(),
                "tip_angle_deg": self.trajectory.tip_angle_deg.tolist(),
                "converged": self.trajectory.converged}


def _median_in_time(speed, dt) -> float:
    """The speed exceeded for half of the time (steps weighted by their length)."""
    order = np.argsort(speed)
    weight = np.cumsum(dt[order])
    return float(speed[order][np.searchsorted(weight, 0.5 * weight[-1])])


def switches(time, values, tip_deg, threshold: float = 0.25, merge: float = 20.0) -> list:
    """The input's values where the tip snapped (module docstring)."""
    dt = np.diff(np.r_[0.0, time])
    speed = np.abs(np.diff(np.r_[tip_deg[0], tip_deg])) / dt
    fast = speed > threshold * np.max(speed)
    # a snap is fast against the sweep's own following motion too: the median speed in time
    # over the whole sweep, or before the first fast step if lower (an undamped rod rings on
    # after its snap)
    first = int(np.argmax(fast))
    following = _median_in_time(speed, dt)
    if first >= 10:
        following = min(following, _median_in_time(speed[:first], dt[:first]))
    fast &= speed > 10.0 * following
    edges = np.diff(np.r_[0, fast.astype(int), 0])
    starts, ends = np.nonzero(edges == 1)[0], np.nonzero(edges == -1)[0]
    out, last_end = [], None
    for s, e in zip(starts, ends):
        if last_end is None or time[s] - time[last_end - 1] > merge:
            out.append(float(values[s + int(np.argmax(speed[s:e]))]))
        last_end = e
    return out


def rate_sweep(scene: Scene, vary: str, state, stop: float, rate: float, damping: float,
               dt: float = 0.05, n: int = DEFAULT_N, tol: float | None = 1e-6,
               max_steps: int = 20000, velocity=None) -> RateSweep:
    """Move ``vary`` from the scene's value to ``stop`` at ``rate`` (its units per unit
    time; the sign is taken from the direction) from the equilibrium ``state`` at rest (or
    with ``velocity``), with drag ``damping``; adaptive steps at the accuracy ``tol`` no
    longer than ``dt`` (``tol=None``: fixed steps ``dt``) (module docstring)."""
    scene.check_key(vary)
    start = float(np.asarray(scene.value(vary)))
    if not (np.isfinite(rate) and rate != 0.0):
        raise ParameterError(f"rate must be a finite number other than 0, got {rate!r}")
    if not np.isfinite(stop) or stop == start:
        raise ParameterError(f"the sweep's end must differ from its start ({start:g})")
    speed = abs(rate) * np.sign(stop - start)
    t_end = (stop - start) / speed
    tr = simulate(scene, state, t_end, min(dt, 1e-3) if tol else dt, damping=damping, n=n,
                  vary=vary, rate=speed, scheme="bdf2", tol=tol, dt_max=dt,
                  max_steps=max_steps, velocity=velocity)
    values = start + speed * tr.time
    return RateSweep(vary, values, switches(tr.time, values, tr.tip_angle_deg), tr)
