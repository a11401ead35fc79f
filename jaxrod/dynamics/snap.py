"""The snap: the motion from a fold of any scene to where the rod comes to rest.

The input that the fold is met along is moved a little past the fold (``past``, to the side
where the branch has no equilibrium nearby), and the motion from the fold's state at rest
is integrated (``jaxrod.dynamics.integrate``: BDF2 with damping, the energy-conserving
discrete gradient without) with drag ``damping``. Defined, from
the tip's direction (degrees from +z toward +x):

    leave     the first time the tip is more than ``band`` from its start (the fold's tip);
    arrive    the first time after that it is within ``band`` of where it comes to rest;
    settle    the last time it is more than ``band`` from where it comes to rest;
    duration  settle - leave (None when the motion has not settled by t_end: raise t_end,
              or add damping); ``transit`` = arrive - leave, defined without damping too.

The resting state is the last state polished by Newton (a static equilibrium), with its
stability; without enough damping to settle by t_end, it is where the same start comes to
rest with the drag raised to 2. Near the fold the rod leaves slowly (the normal form's
bottleneck), so ``leave`` depends on ``past``; the duration hardly does.

``leave``, ``arrive`` and ``settle`` are interpolated linearly between the samples where
the tip crosses the band (``band_times``: one definition for ``snap``, ``duration_of`` and
the benchmarks).

``duration_of`` is the same duration as a JAX function of the scene (its inputs traced):
the fold re-solved by Moore-Spence and differentiated implicitly, the motion by fixed-step
BDF2 in a ``lax.scan``, the resting direction the last step's. Its forward-mode
derivative (``jax.jvp``, ``jax.jacfwd``) in any input, the Young's modulus through the
groups and the time unit, is exact for the discrete duration (tests/test_dynamics.py: against
central differences).
"""

from __future__ import annotations

import dataclasses
import math

import jax.numpy as jnp
import numpy as np

from jaxrod.derivatives import Structured
from jaxrod.dynamics.integrate import Trajectory, _run_bdf, simulate
from jaxrod.equilibria.equilibrium import DEFAULT_N, discretise, equilibrium, tip
from jaxrod.equilibria.folds import Fold
from jaxrod.params import ParameterError
from jaxrod.scenes.path import along, still_path
from jaxrod.scenes.scene import Input, Scene
from jaxrod.solvers.folds import differentiable_fold


@dataclasses.dataclass(frozen=True)
class Snap:
    """A snap from a fold: the trajectory, the moved input's value, leave/settle/duration
    (module docstring), where it rests (tip direction, stable), the largest tip speed
    (degrees per unit time), the overshoot past the resting tip (degrees) and the
    integrator's ``scheme``."""

    trajectory: Trajectory
    value: float
    leave: float | None
    arrive: float | None
    settle: float | None
    duration: float | None
    rest_tip_deg: float
    rest_stable: bool
    peak_tip_speed: float
    overshoot_deg: float
    band_deg: float
    scheme: str = "bdf2"

    @property
    def transit(self) -> float | None:
        return None if self.leave is None or self.arrive is None else self.arrive - self.leave

    def as_dict(self) -> dict:
        return self.trajectory.as_dict() | {
            "value": self.value, "leave": self.leave, "arrive": self.arrive,
            "settle": self.settle, "duration": self.duration, "transit": self.transit,
            "rest_tip_deg": self.rest_tip_deg,
            "rest_stable": self.rest_stable, "peak_tip_speed_deg": self.peak_tip_speed,
            "overshoot_deg": self.overshoot_deg, "band_deg": self.band_deg,
            "scheme": self.scheme}


def snap(scene: Scene, fold: Fold, damping: float, t_end: float = 60.0, dt: float = 0.01,
         past: float = 1e-3, band: float = 0.5, n: int = DEFAULT_N,
         kelvin_voigt: float = 0.0, scheme: str | None = None) -> Snap:
    """The snap from ``fold`` (of ``scene``, from ``jr.folds``) with drag ``damping``;
    ``past``: how far the input is moved past the fold (its units), ``band``: degrees;
    ``kelvin_voigt``: internal damping (``jaxrod.dynamics.integrate``); ``scheme``: the
    integrator (``simulate``'s; by default BDF2, which settles, where there is damping, and
    the discrete gradient, which conserves the energy, where there is none)."""
    if not fold.converged:
        raise ParameterError("fold: the fold did not converge; refine it first")
    for name, v in (("past", past), ("band", band)):
        if not (math.isfinite(v) and v > 0):
            raise ParameterError(f"{name} must be a finite number > 0, got {v!r}")
    # past the fold: to the side where the branch has no equilibrium next to the fold
    side = -1.0 if fold.normal_form_c > 0 else 1.0
    value = fold.value + side * past
    at = along(scene, (fold.vary,)).at_host(value)
    if scheme is None:
        scheme = "bdf2" if damping + kelvin_voigt > 0 else "discrete-gradient"
    tr = simulate(at, fold.state, t_end, dt, damping=damping, n=n, scheme=scheme,
                  kelvin_voigt=kelvin_voigt)
    rest = equilibrium(at, n=n, state=tr.states[-1], throw=False)
    if not (rest.converged and rest.stable and tr.kinetic[-1] < 1e-8):
        damped = simulate(at, fold.state, t_end, dt, damping=max(damping, 2.0), n=n,
                          scheme="bdf2")
        rest = equilibrium(at, n=n, state=damped.states[-1], throw=False)
    tip = tr.tip_angle_deg
    leave, arrive, settle = (None if math.isnan(t) else t for t in map(float, band_times(
        np.r_[0.0, tr.time], np.r_[fold.tip_angle_deg, tip], fold.tip_angle_deg,
        rest.tip_angle_deg, band)))
    if not (rest.converged and damping + kelvin_voigt > 0):
        settle = None
    speed = np.abs(np.diff(np.r_[fold.tip_angle_deg, tip])) / dt
    direction = np.sign(rest.tip_angle_deg - fold.tip_angle_deg)
    overshoot = float(max(0.0, np.max(direction * (tip - rest.tip_angle_deg))))
    return Snap(trajectory=tr, value=value, leave=leave, arrive=arrive, settle=settle,
                duration=None if leave is None or settle is None else settle - leave,
                rest_tip_deg=rest.tip_angle_deg, rest_stable=rest.stable,
                peak_tip_speed=float(np.max(speed)), overshoot_deg=overshoot, band_deg=band,
                scheme=scheme)


def band_times(time, angle, start, rest, band):
    """(leave, arrive, settle) of the module docstring from samples ``angle`` (degrees) at
    ``time`` (the start at index 0), each where the distance to the band's edge crosses zero
    between two samples (linear interpolation); NaN where the motion does not do it (never
    leaves, never arrives, or is outside the band at the end). Pure jnp: host arrays and
    traced ones alike."""
    time, angle = jnp.asarray(time), jnp.asarray(angle)
    n = angle.shape[0]

    def cross(d, k):  # between samples k - 1 and k
        k = jnp.clip(k, 1, n - 1)
        return time[k - 1] + (time[k] - time[k - 1]) * d[k - 1] / (d[k - 1] - d[k])

    away = jnp.abs(angle - start) - band
    i = jnp.argmax(away > 0)
    left = jnp.any(away > 0)
    off = jnp.abs(angle - rest) - band
    inside = (off <= 0) & (jnp.arange(n) >= i)
    j = jnp.argmax(inside)
    last_off = n - 1 - jnp.argmax(off[::-1] > 0)
    nan = jnp.nan
    leave = jnp.where(left, jnp.where(i > 0, cross(away, i), time[0]), nan)
    arrive = jnp.where(left & jnp.any(inside), jnp.where(j > 0, cross(off, j), time[0]), nan)
    settle = jnp.where(left & jnp.any(off > 0) & (off[-1] <= 0), cross(off, last_off + 1), nan)
    return leave, arrive, settle


def duration_of(scene: Scene, fold: Fold, damping, t_end: float = 60.0, dt: float = 0.01,
                past: float = 1e-3, band: float = 0.5, n: int = DEFAULT_N):
    """The snap's duration (``snap``'s definition; module docstring) as a traceable function
    of ``scene``'s inputs and ``damping``: ``fold`` (of ``scene`` at its given inputs) is the
    start of the fold's Newton solve at the traced ones. Returns (duration, converged)."""
    disc = discretise(scene, n)
    m = disc.size
    side = -1.0 if fold.normal_form_c > 0 else 1.0
    steps = int(np.ceil(t_end / dt - 1e-9))
    z, stats = differentiable_fold(Structured(Input(fold.vary)), jnp.asarray(fold.state), 0.0,
                                   jnp.asarray(fold.null_vector),
                                   (scene, disc, fold.value, 1.0))
    x, value = z[:m], fold.value + z[-1]
    at = scene.replace(fold.vary, value + side * past)
    start = jnp.degrees(tip(scene.replace(fold.vary, value), x, disc)[0])
    out = _run_bdf(still_path(at), disc, x, jnp.zeros(m), dt, steps, (damping, None), 0.0,
                   0.0)
    angle, converged = jnp.degrees(out[3]), out[-2]
    time = dt * jnp.arange(0, steps + 1)
    angle = jnp.concatenate([start[None], angle])
    leave, _, settle = band_times(time, angle, start, angle[-1], band)
    duration = settle - leave
    ok = (stats[0] == 1.0) & jnp.all(converged) & jnp.isfinite(duration)
    return duration, ok
