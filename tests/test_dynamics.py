"""Time integration: the variational midpoint scheme (period of a mode, energy without
drift, second order) and BDF2 (L-stable: settles on the static equilibrium; the snap past
a fold lands where the quasi-static sweep's descent does)."""

import dataclasses
import math

import numpy as np
import pytest
from command_line import run_cli

import jaxrod as jr
from jaxrod.dynamics.integrate import simulate
from jaxrod.dynamics.modes import modes
from jaxrod.params import ParameterError

CANTILEVER = jr.Scene({"bending": jr.Bending()})
HARD = jr.Scene({"bending": jr.Bending(), "field": jr.Zeeman(5.0, math.pi / 2)})


def _period(tr):
    x = tr.tip_position[:, 0]
    i = np.nonzero(np.sign(x[:-1]) * np.sign(x[1:]) < 0)[0]
    t = tr.time[i] - x[i] * (tr.time[i + 1] - tr.time[i]) / (x[i + 1] - x[i])
    return 2.0 * np.mean(np.diff(t))


def test_a_small_oscillation_has_the_modes_period_to_second_order():
    """Released from its first mode shape, the cantilever swings with period 2 pi / omega_1
    (the modes' eigenproblem); the midpoint scheme's error falls as dt^2; the energy holds
    to 1e-8 relative."""
    m = modes(CANTILEVER, n=12)
    T = 2 * math.pi / m.omega[0]
    q0 = 1e-3 * m.shapes[:, 0] / np.max(np.abs(m.shapes[:, 0]))
    errors = []
    for div in (50, 100, 200):
        tr = simulate(CANTILEVER, q0, 3 * T, T / div, n=12)
        assert tr.converged
        errors.append(abs(_period(tr) - T) / T)
        assert np.ptp(tr.energy) <= 1e-8 * np.mean(tr.energy)
    assert errors[-1] < 1e-4
    assert 3.5 < errors[0] / errors[1] < 4.5 and 3.5 < errors[1] / errors[2] < 4.5


def test_the_3d_rod_swings_as_the_planar_one():
    """The upright rod under gravity on the 3D director chart: its modes come in pairs
    equal to the planar rod's (to 1e-10), and released from one of them it swings with the
    period 2 pi / omega_1 (to the midpoint scheme's dt^2), the energy held to 1e-8."""
    scene3 = jr.Scene({"bending": jr.Bending(), "gravity": jr.Gravity(2.0)}, geometry="3d")
    planar = modes(jr.Scene({"bending": jr.Bending(), "gravity": jr.Gravity(2.0)}), n=12)
    m = modes(scene3, n=12)
    assert m.omega[:6] == pytest.approx(np.repeat(planar.omega[:3], 2), rel=1e-10)
    T = 2 * math.pi / m.omega[0]
    q0 = m.state + 1e-3 * m.shapes[:, 0] / np.max(np.abs(m.shapes[:, 0]))
    tr = simulate(scene3, q0, 3 * T, T / 200, n=12)
    horizontal = tr.tip_position[:, :2]
    swing = dataclasses.replace(tr, tip_position=np.c_[horizontal @ horizontal[0], 0 * tr.time,
                                                       0 * tr.time])
    assert tr.converged and abs(_period(swing) - T) < 1e-4 * T
    assert np.ptp(tr.energy) <= 1e-8 * np.mean(tr.energy)


def test_large_motion_energy_without_drift():
    """The hard-magnetic cantilever released straight in a transverse field (a large swing,
    undamped): the total energy's spread falls as dt^2 and it does not drift."""
    spreads = []
    for dt in (0.01, 0.005, 0.0025):
        tr = simulate(HARD, np.zeros(16), 2.0, dt, n=16)
        assert tr.converged and tr.tip_tangent_deg.max() > 100.0
        spreads.append(np.ptp(tr.energy))
        half = len(tr.energy) // 2
        assert abs(np.mean(tr.energy[:half]) - np.mean(tr.energy[half:])) < spreads[-1]
    assert spreads[0] / spreads[1] > 2.5 and spreads[1] / spreads[2] > 3.0


def test_the_discrete_gradient_conserves_the_energy_of_a_large_motion():
    """The same large swing by the discrete gradient: the energy (from the canonical state,
    not a step's differences) held to 1e-10 of the swing's kinetic energy at every step size
    (Newton's tolerance, 1e-12 a step, accumulating), where the midpoint scheme's spread is
    O(dt^2); with drag and Kelvin-Voigt damping the energy falls at every step. (The
    scheme's second order: the damped-mode tests above.)"""
    for dt in (0.02, 0.005, 0.00125):
        tr = simulate(HARD, np.zeros(16), 1.0, dt, n=16, scheme="discrete-gradient")
        peak = tr.kinetic.max()
        assert tr.converged and peak > 1.0 and tr.tip_tangent_deg.max() > 100.0
        assert np.max(np.abs(tr.energy)) <= 1e-10 * peak  # E(0) = 0
    damped = simulate(HARD, np.zeros(16), 1.0, 0.01, damping=2.0, kelvin_voigt=0.01, n=16,
                      scheme="discrete-gradient")
    assert damped.converged and np.all(np.diff(np.r_[0.0, damped.energy]) < 0.0)


def test_bdf2_settles_on_the_static_equilibrium():
    eq = jr.equilibrium(HARD, n=16)
    tr = simulate(HARD, np.zeros(16), 20.0, 0.01, damping=5.0, n=16, scheme="bdf2")
    assert tr.converged
    assert abs(tr.tip_tangent_deg[-1] - eq.tip_tangent_deg) <= 1e-7
    assert np.max(np.abs(tr.states[-1] - eq.state)) <= 1e-9


@pytest.mark.parametrize("scheme", ["midpoint", "bdf2", "discrete-gradient"])
def test_a_damped_mode_decays_as_the_damped_oscillator(scheme):
    """The first mode released with drag c: each mode obeys x'' + c x' + omega^2 x = 0
    (the drag acts like the mass), so the tip follows x0 exp(-c t / 2) (cos(w t) +
    c / (2 w) sin(w t)), w = sqrt(omega^2 - c^2 / 4); every scheme to second order."""
    m = modes(CANTILEVER, n=12)
    c, w1 = 0.8, m.omega[0]
    wd = math.sqrt(w1**2 - c**2 / 4)
    q0 = 1e-4 * m.shapes[:, 0] / np.max(np.abs(m.shapes[:, 0]))
    x0 = simulate(CANTILEVER, q0, 1e-9, 1e-9, n=12).tip_position[0, 0]  # the start's tip
    t_end = 2 * math.pi / wd
    exact = x0 * math.exp(-c * t_end / 2) * (math.cos(wd * t_end)
                                             + c / (2 * wd) * math.sin(wd * t_end))
    errors = []
    for div in (80, 160, 320):
        tr = simulate(CANTILEVER, q0, t_end, t_end / div, damping=c, n=12, scheme=scheme)
        errors.append(abs(tr.tip_position[-1, 0] - exact) / abs(x0))
    assert errors[-1] < 1e-4
    # second order (BDF2 from above: its first step is backward Euler)
    assert 3.3 < errors[0] / errors[1] < 5.0 and 3.3 < errors[1] / errors[2] < 5.0


@pytest.mark.parametrize("scheme", ["midpoint", "bdf2", "discrete-gradient"])
def test_kelvin_voigt_damps_a_mode_as_its_frequency_squared(scheme):
    """The first mode released with internal (Kelvin-Voigt) damping eta on the unloaded
    cantilever, whose Hessian is the dissipation's form K: x'' + eta omega^2 x' + omega^2 x
    = 0, damping ratio eta omega / 2 (``Modes.damping_ratios``); every scheme to second
    order."""
    m = modes(CANTILEVER, n=12)
    eta, w1 = 0.05, m.omega[0]
    c = eta * w1**2
    assert m.damping_ratios(0.0, eta)[:3] == pytest.approx(eta * m.omega[:3] / 2, rel=1e-9)
    wd = math.sqrt(w1**2 - c**2 / 4)
    q0 = 1e-4 * m.shapes[:, 0] / np.max(np.abs(m.shapes[:, 0]))
    x0 = simulate(CANTILEVER, q0, 1e-9, 1e-9, n=12).tip_position[0, 0]
    t_end = 2 * math.pi / wd
    exact = x0 * math.exp(-c * t_end / 2) * (math.cos(wd * t_end)
                                             + c / (2 * wd) * math.sin(wd * t_end))
    errors = []
    for div in (80, 160, 320):
        tr = simulate(CANTILEVER, q0, t_end, t_end / div, kelvin_voigt=eta, n=12,
                      scheme=scheme)
        errors.append(abs(tr.tip_position[-1, 0] - exact) / abs(x0))
    assert errors[-1] < 1e-4
    assert 3.3 < errors[0] / errors[1] < 5.0 and 3.3 < errors[1] / errors[2] < 5.0


def test_the_snap_past_the_papers_upper_fold_lands_where_the_sweep_does():
    """The magnet moved 0.05 degrees past the upper fold: from the fold state the rod snaps
    (damped) and comes to rest on the disengaged state, the one the quasi-static sweep's
    energy descent lands on."""
    scene = jr.Scene({"bending": jr.Bending(), "gravity": jr.Gravity(2.2),
                      "magnet": jr.Dipole(0.0236, 11.25 / 9.2, 0.0)})
    fold = max(jr.folds(scene, "magnet.alpha", 0.0, math.pi / 2), key=lambda f: f.value)
    past = fold.value + math.radians(0.05)
    tr = simulate(scene.replace("magnet.alpha", past), fold.state, 40.0, 0.02, damping=3.0,
                  scheme="bdf2")
    assert tr.converged
    sweep = jr.sweep(scene, "magnet.alpha",
                           np.radians(np.r_[0.0:math.degrees(fold.value):0.5]).tolist()
                           + [past])
    landing = sweep.snaps[-1]["tip_after_deg"]
    assert tr.tip_angle_deg[0] > landing + 10.0  # it started engaged
    assert abs(tr.tip_angle_deg[-1] - landing) <= 1e-6


@pytest.mark.parametrize("kw, match", [({"dt": 0.0}, "dt"), ({"damping": -1.0}, "damping"),
                                       ({"scheme": "rk4"}, "scheme")])
def test_bad_requests(kw, match):
    args = {"state": np.zeros(16), "t_end": 1.0, "dt": 0.01} | kw
    with pytest.raises(ParameterError, match=match):
        simulate(HARD, **args)


def test_cli_snap_json(tmp_path):
    """jaxrod snap from the paper's upper fold: the time series and a duration; the rod comes
    to rest on the disengaged state (stable), having lost energy to the drag; the same
    series as CSV, a figure and an animation of the rod."""
    import csv
    import json

    files = {k: tmp_path / f"snap.{k}" for k in ("csv", "png", "gif")}
    proc = run_cli("snap", "--G", "2.2", "--M", "0.0236", "--D", "1.2228", "--fold", "upper",
                   "--damping", "1", "--json", "--csv", files["csv"], "--plot", files["png"],
                   "--animate", files["gif"])
    assert proc.returncode == 0, proc.stderr
    rows = list(csv.DictReader(open(files["csv"])))
    assert files["png"].stat().st_size > 0 and files["gif"].read_bytes()[:3] == b"GIF"
    out = json.loads(proc.stdout)
    assert {"duration", "time", "tip_angle_deg", "energy", "kinetic"} <= set(out)
    assert out["duration"] > 0 and out["rest_stable"]
    assert out["rest_tip_deg"] < out["tip_angle_deg"][0] - 10.0  # it let go
    assert out["energy"][-1] < out["energy"][0]
    assert len(out["time"]) == len(out["tip_angle_deg"]) == len(out["kinetic"]) == len(rows)
    assert float(rows[-1]["tip_angle_deg"]) == pytest.approx(out["tip_angle_deg"][-1])


@pytest.mark.parametrize("damping, exponent", [(10.0, 2.0 / 3.0), (0.0, 0.8)])
def test_the_switching_lag_follows_the_folds_normal_form(damping, exponent):
    """The magnet swept past the paper's upper fold at 1e-4 to 1e-2 degrees per unit time
    (adaptive steps): the switch lags the static fold as eps^(2/3) where the drag dominates
    (c = 10) and as eps^(4/5) without drag, slopes within 0.03 over the two decades; at the
    slowest rate the lag is within 5% of the normal form's power law (its prefactor from
    the fold's modal mass, dF/dalpha and d2F/dq2) and within 1% of its full solution; the
    lag goes to zero with the rate (Liu, Gomez and Vella, JMPS 2021)."""
    from jaxrod.dynamics.normal_form import normal_form
    from jaxrod.dynamics.rate_sweep import rate_sweep

    scene = jr.Scene({"bending": jr.Bending(), "gravity": jr.Gravity(2.2),
                      "magnet": jr.Dipole(0.0236, 11.25 / 9.2, 0.0)})
    fold = max(jr.folds(scene, "magnet.alpha", 0.0, math.pi / 2), key=lambda f: f.value)
    a0 = fold.value - math.radians(0.25)
    held = jr.sweep(scene, "magnet.alpha", np.radians(np.r_[0:39:0.5]).tolist())
    start = jr.equilibrium(scene.replace("magnet.alpha", a0), state=held.states[-1])
    nf = normal_form(scene, fold, damping)
    rates = np.radians([1e-4, 1e-3, 1e-2])
    lags = []
    for rate in rates:
        stop = fold.value + 1.5 * nf.lag(rate) + 20.0 * rate  # past the switch, and a snap
        s = rate_sweep(scene.replace("magnet.alpha", a0), "magnet.alpha", start.state, stop,
                       rate, damping, dt=5.0)
        assert s.trajectory.converged and len(s.switches) == 1
        lags.append(s.switches[0] - fold.value)
    assert np.all(np.diff(lags) > 0) and lags[0] < 0.3 * lags[1]  # to zero with the rate
    slope = np.polyfit(np.log(rates), np.log(lags), 1)[0]
    assert abs(slope - exponent) < 0.03, slope
    power_law = nf.damped_prefactor if damping else nf.inertial_prefactor
    assert abs(lags[0] / (power_law * rates[0] ** exponent) - 1.0) < 0.05
    assert abs(lags[0] / nf.lag(rates[0]) - 1.0) < 0.01


def test_cli_sweep_at_a_rate():
    import json

    proc = run_cli("sweep", "--G", "2.2", "--M", "0.0236", "--D", "1.2228", "--rate", "0.1",
                   "--damping", "10", "--from", "38.5", "--to", "41.5", "--json")
    assert proc.returncode == 0, proc.stderr
    (switch,) = json.loads(proc.stdout)["switch_alpha_deg"]
    assert 39.31 < switch < 41.0  # after the static fold at 39.3134 degrees


def test_time_scale_and_lambs_drag():
    """T = L^2 sqrt(rho A / (E I)) = 2 L^2 sqrt(rho / E) / r for a round rod; Lamb's
    coefficient 4 pi mu / (1/2 - gamma - ln(Re / 8)); the nondimensional drag c T / (rho A)."""
    from jaxrod.dynamics.drag import lamb_drag, nondimensional_damping, time_scale

    L, r, E, rho = 0.092, 25e-6, 200e9, 9000.0
    assert time_scale(L, r, E, rho) == pytest.approx(2 * L**2 * math.sqrt(rho / E) / r,
                                                     rel=1e-14)
    mu, rho_f, U = 1.81e-5, 1.204, 0.2
    re = rho_f * U * 2 * r / mu
    assert lamb_drag(r, U) == pytest.approx(
        4 * math.pi * mu / (0.5 - 0.5772156649015329 - math.log(re / 8)), rel=1e-14)
    c = lamb_drag(r, U)
    assert nondimensional_damping(c, L, r, E, rho) == pytest.approx(
        c * time_scale(L, r, E, rho) / (rho * math.pi * r**2), rel=1e-14)
    with pytest.raises(ParameterError, match="Reynolds"):
        lamb_drag(r, 1e3)


def test_cli_snap_of_the_papers_wire_in_seconds():
    """The paper's question: its 50 um nickel wire snapping off the magnet in air (Lamb's
    drag at the snap's speed) settles; in vacuum (no damping modelled) it does not, its
    first passage is quicker, and its energy (kinetic + potential) is conserved to 1e-8
    relative over the whole snap."""
    import json
    import os
    import subprocess
    import sys

    runs = {}
    for medium in ("air", "vacuum"):
        proc = subprocess.run([sys.executable, "-m", "jaxrod.cli", "snap", "--preset",
                               "permanent-magnet", "--medium", medium, "--json"],
                              capture_output=True, text=True, timeout=600,
                              env={**os.environ, "JAXROD_NO_CACHE": "1"})
        assert proc.returncode == 0, proc.stderr
        runs[medium] = json.loads(proc.stdout)
    air, vacuum = runs["air"], runs["vacuum"]
    assert 0.1 < air["time_scale_s"] < 0.2 and air["damping"] > 0 and vacuum["damping"] == 0
    assert air["duration_s"] > air["transit_s"] > 0 and vacuum["duration_s"] is None
    assert (air["scheme"], vacuum["scheme"]) == ("bdf2", "discrete-gradient")
    energy = np.array(vacuum["energy"])  # undamped: conserved over the whole snap
    assert max(vacuum["kinetic"]) > 0.05 * abs(energy[0])  # a real motion
    assert np.max(np.abs(energy - energy[0])) <= 1e-8 * abs(energy[0])
    assert vacuum["transit_s"] < air["transit_s"]
    assert abs(air["rest_tip_deg"] - vacuum["rest_tip_deg"]) < 1e-6


def test_the_snap_duration_is_differentiable_in_youngs_modulus():
    """d(duration in seconds)/dE for the paper's wire snapping in air: the groups G and M
    go as 1 / E, the time unit and the nondimensional drag (fixed in N s / m^2) as E^-1/2;
    forward mode through the fold's implicit derivative and the BDF2 steps
    (``duration_of``) against central differences (a batch under vmap), to 1e-6."""
    import jax
    import jax.numpy as jnp

    from jaxrod.dynamics.drag import time_scale
    from jaxrod.dynamics.snap import duration_of, snap
    from jaxrod.params import NDFEB_MAGNET, preset

    rod, _ = preset("permanent-magnet")
    E0, rho = rod.material.youngs_modulus, rod.material.density
    T0 = time_scale(rod.length, rod.diameter / 2, E0, rho)
    G0, M0, D = rod.G, rod.M(NDFEB_MAGNET), rod.D(NDFEB_MAGNET)
    c0 = 1.1  # the drag in air at the snap's speed, nondimensional at E0

    def scene(r):
        return jr.Scene({"bending": jr.Bending(), "gravity": jr.Gravity(G0 * r),
                         "magnet": jr.Dipole(M0 * r, D, 0.0)})

    fold = max(jr.folds(scene(1.0), "magnet.alpha", 0.0, math.pi / 2),
               key=lambda f: f.value)

    def seconds(e):  # e = E / E0
        r = 1.0 / e
        d, ok = duration_of(scene(r), fold, c0 * jnp.sqrt(r), t_end=30.0, dt=0.02)
        return T0 * jnp.sqrt(r) * d, ok

    value, ok = jax.jit(seconds)(1.0)
    assert ok
    by_snap = snap(scene(1.0), fold, c0, t_end=30.0, dt=0.02).duration * T0
    assert abs(value - by_snap) < 2 * 0.02 * T0  # the same duration, to its steps
    derivative = jax.jit(lambda e: jax.jvp(lambda x: seconds(x)[0], (e,), (1.0,))[1])(1.0)
    h = 1e-4  # the three moduli as one batch, under vmap
    batch, oks = jax.jit(jax.vmap(seconds))(jnp.array([1.0, 1.0 + h, 1.0 - h]))
    assert np.all(oks) and float(batch[0]) == pytest.approx(float(value), rel=1e-12)
    central = (batch[1] - batch[2]) / (2 * h)
    assert float(derivative) == pytest.approx(float(central), rel=1e-6)  # per E0


@pytest.mark.parametrize("argv, says", [
    (["snap", "--G", "2.2", "--M", "0.0236", "--D", "1.2228", "--damping", "-1"], "damping"),
    (["snap", "--G", "2.2", "--M", "0.0236", "--D", "1.2228", "--kelvin-voigt", "-0.1"],
     "kelvin-voigt"),
    (["sweep", "--G", "2.2", "--M", "0.0236", "--D", "1.2228", "--rate", "0", "--from", "38",
      "--to", "41"], "rate"),
    (["sweep", "--G", "2.2", "--M", "0.0236", "--D", "1.2228", "--rate", "nan", "--from",
      "38", "--to", "41"], "rate"),
    (["modes", "hard-magnetic-cantilever", "--set", "rod.density=0"], "rod.density"),
    (["snap", "--G", "2.2", "--M", "0.001", "--D", "1.2228"], "no two folds"),
])
def test_bad_dynamics_input_is_one_line_and_exit_2(argv, says, capsys):
    """Negative damping, zero density, a rate of zero or NaN, a fold that these inputs do not
    have: one line naming it, exit 2."""
    from jaxrod.cli import main

    try:
        code = main(argv)
    except SystemExit as e:  # refused by the argument parser
        code = e.code
    err = capsys.readouterr().err.strip()
    assert code == 2 and says in err and len(err.splitlines()) == 1, err
