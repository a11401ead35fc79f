"""Figures of the rod in time: a snap's tip and energies against time, the rod's shape as
an animation, and the switching lag against the sweep rate beside the fold's normal form
(matplotlib; the numerics never import this module)."""

from __future__ import annotations

import matplotlib

if not matplotlib.get_backend().lower().startswith("module://"):  # keep notebook backends
    matplotlib.use("Agg")

import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib import animation  # noqa: E402

from jaxrod.equilibria.equilibrium import discretise  # noqa: E402
from jaxrod.programs import jit  # noqa: E402


def _time(tr, time_scale):
    return (tr.time * time_scale, "time (s)") if time_scale else (tr.time, "time (units T)")


def snap_figure(s, time_scale: float | None = None):
    """The tip's direction (with the band around the landing state, leave and settle marked)
    and the kinetic and total energy against time."""
    tr = s.trajectory
    t, label = _time(tr, time_scale)
    k = time_scale or 1.0
    fig, (ax, ax2) = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
    ax.plot(t, tr.tip_angle_deg, lw=1.5)
    ax.axhspan(s.rest_tip_deg - s.band_deg, s.rest_tip_deg + s.band_deg, color="C2",
               alpha=0.2, label=f"landing state ± {s.band_deg:g} deg")
    for name, when, colour in (("leave", s.leave, "C1"), ("settle", s.settle, "C3")):
        if when is not None:
            ax.axvline(when * k, color=colour, ls="--", lw=1, label=name)
    ax.set_ylabel("tip direction (deg)")
    ax.legend(loc="best", fontsize=8)
    duration = "not settled" if s.duration is None else f"{s.duration * k:.4g}"
    ax.set_title(f"snap: duration {duration}" + (" s" if time_scale and s.duration else ""))
    ax2.plot(t, tr.kinetic, label="kinetic")
    ax2.plot(t, tr.energy - tr.energy[-1], label="total - final")
    ax2.set_yscale("symlog", linthresh=1e-6)
    ax2.set_xlabel(label)
    ax2.set_ylabel("energy (E I / L)")
    ax2.legend(loc="best", fontsize=8)
    fig.tight_layout()
    return fig


@jit
def _shapes(scene, disc, states):
    return jax.vmap(lambda x: scene.positions(x, disc))(states)


def rod_shapes(scene, states, n: int):
    """The rod's centre line r(s) at the quadrature nodes for each state, (k, n_q, 3)."""
    return np.asarray(_shapes(scene, discretise(scene, n), jnp.asarray(states)))


def modes_figure(scene, m, n: int, count: int = 4, amplitude: float = 0.15):
    """The equilibrium's centre line and, beside it, each of the lowest ``count`` modes'
    shapes: the centre line displaced along the mode (its largest displacement
    ``amplitude`` rod lengths), both signs."""
    base = rod_shapes(scene, m.state[None], n)[0]
    fig, axes = plt.subplots(1, count, figsize=(3 * count, 3.6), sharey=True)
    for k, ax in enumerate(np.atleast_1d(axes)):
        v = m.shapes[:, k]
        for sign, style in ((1.0, "-"), (-1.0, "--")):
            x = m.state + sign * 1e-6 * v
            dr = (rod_shapes(scene, x[None], n)[0] - base) / 1e-6  # the shape's displacement
            dr = dr * amplitude / max(np.max(np.linalg.norm(dr, axis=1)), 1e-300)
            ax.plot(base[:, 0] + dr[:, 0], base[:, 2] + dr[:, 2], style, color=f"C{k}")
        ax.plot(base[:, 0], base[:, 2], color="0.5", lw=1)
        w = m.omega[k]
        ax.set_title(f"mode {k + 1}: omega = " + ("unstable" if np.isnan(w) else f"{w:.5g}"))
        ax.set_aspect("equal")
        ax.set_xlabel("x / L")
    np.atleast_1d(axes)[0].set_ylabel("z / L")
    fig.tight_layout()
    return fig


def snap_animation(scene, s, n: int, path: str, time_scale: float | None = None,
                   frames: int = 120, fps: int = 20):
    """An animation of the rod's shape during the snap (GIF by Pillow, MP4 by ffmpeg),
    ``frames`` frames evenly in time, written to ``path``."""
    tr = s.trajectory
    pick = np.unique(np.linspace(0, len(tr.time) - 1, frames).round().astype(int))
    r = rod_shapes(scene, tr.states[pick], n)
    t, label = _time(tr, time_scale)
    fig, ax = plt.subplots(figsize=(5, 5))
    span = max(np.max(np.abs(r[..., 0])), np.max(r[..., 2]), 1e-3) * 1.1
    ax.set_xlim(-span, span)
    ax.set_ylim(min(np.min(r[..., 2]), 0.0) - 0.05, span)
    ax.set_aspect("equal")
    ax.set_xlabel("x / L")
    ax.set_ylabel("z / L")
    (line,) = ax.plot([], [], lw=2)
    (trace,) = ax.plot([], [], lw=0.8, color="0.6")
    title = ax.set_title("")

    def draw(i):
        line.set_data(r[i, :, 0], r[i, :, 2])
        trace.set_data(r[:i + 1, -1, 0], r[:i + 1, -1, 2])
        title.set_text(f"{label.split(' (')[0]} {t[pick[i]]:.4g}{' s' if time_scale else ''}")
        return line, trace, title

    anim = animation.FuncAnimation(fig, draw, frames=len(pick), blit=False)
    writer = animation.PillowWriter(fps=fps) if str(path).endswith(".gif") else \
        animation.FFMpegWriter(fps=fps)
    anim.save(path, writer=writer)
    plt.close(fig)
    return path


def lag_figure(rates, lags, normal_form, unit: str = "rad", ax=None):
    """The switching lag against the rate (log-log): the measured points, the normal form's
    full prediction, its damped (2/3) and inertial (4/5) power laws, and the crossover
    (on ``ax``, or a new figure)."""
    rates, lags = np.asarray(rates), np.asarray(lags)
    fine = np.geomspace(rates.min() / 2, rates.max() * 2, 60)
    fig, ax = plt.subplots(figsize=(6.5, 4.8)) if ax is None else (ax.figure, ax)
    ax.loglog(rates, lags, "o", label="simulated (BDF2, adaptive steps)")
    ax.loglog(fine, [normal_form.lag(e) for e in fine], "-", lw=1.5,
              label="normal form (inertia and drag)")
    ax.loglog(fine, normal_form.inertial_prefactor * fine**0.8, ":", label="inertial: eps^(4/5)")
    if normal_form.damping > 0:
        ax.loglog(fine, normal_form.damped_prefactor * fine ** (2 / 3), "--",
                  label="damped: eps^(2/3)")
        c = normal_form.crossover_rate
        if fine[0] <= c <= fine[-1]:
            ax.axvline(c, color="0.5", lw=0.8)
            ax.text(c, ax.get_ylim()[0], " crossover", color="0.4", va="bottom")
    ax.set_xlabel(f"sweep rate ({unit} per unit time)")
    ax.set_ylabel(f"switch - fold ({unit})")
    ax.legend(fontsize=8)
    return fig
