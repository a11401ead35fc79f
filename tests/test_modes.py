"""Vibration modes of equilibria: the classical cantilever (closed form), the upright rod
with gravity, a uniform field or an opposed tip load (shooting for the fourth-order
eigenproblem, an independent method), and the soft mode at a fold."""

import json
import math

import numpy as np
import pytest
from command_line import run_cli
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

import jaxrod as jr
from jaxrod.dynamics.modes import in_hertz, modes


def cantilever_omegas(count):
    """omega_k = beta_k^2, 1 + cos(beta) cosh(beta) = 0 (Euler-Bernoulli, clamped-free)."""
    out, b = [], 1.0
    while len(out) < count:
        f = lambda x: 1.0 + math.cos(x) * math.cosh(x)
        if f(b) * f(b + 0.1) < 0:
            out.append(brentq(f, b, b + 0.1, xtol=1e-15, rtol=1e-15) ** 2)
        b += 0.1
    return out


def test_the_clamped_rod_is_the_classical_cantilever():
    """3.516015, 22.03449, 61.69721 (and the fourth) to 1e-8 relative, spectrally in N."""
    ref = cantilever_omegas(4)
    assert [round(w, 5) for w in ref[:3]] == [3.51602, 22.03449, 61.69721]
    scene = jr.Scene({"bending": jr.Bending()})
    errors = []
    for n in (8, 12, 16, 24):
        omega = modes(scene, n=n).omega
        errors.append(max(abs(w - r) / r for w, r in zip(omega[:4], ref)))
    assert errors[0] > 1e-5 and errors[2] < 1e-12 and errors[3] < 1e-12
    assert errors[1] < errors[0]


def _determinant(w2, P):
    """det of the shooting map for -theta'' - P theta - w2 W = 0, w' = theta, W' = -w,
    w(0) = theta(0) = 0, theta'(1) = W(1) = 0."""
    def rhs(s, y):
        w, th, dth, W = y
        return [th, dth, -P(s) * th - w2 * W, -w]

    ends = [solve_ivp(rhs, (0.0, 1.0), y0, method="DOP853", rtol=1e-13, atol=1e-15).y[:, -1]
            for y0 in ([0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0])]
    return ends[0][2] * ends[1][3] - ends[1][2] * ends[0][3]


@pytest.mark.parametrize("G, A, load", [(2.0, 0.0, 0.0), (5.0, 3.0, 0.0), (1.0, 0.0, 1.5)])
def test_straight_rod_modes_against_shooting(G, A, load):
    """The upright rod with gravity G, a vertical field (the soft wire's anisotropy A) or an
    opposed tip load (a hard-magnetic rod, the field against its magnetisation): the lowest
    three frequencies against the roots of the shooting determinant, to 1e-8 relative."""
    terms = {"bending": jr.Bending(), "gravity": jr.Gravity(G)}
    if A:
        terms["field"] = jr.Anisotropy(A)
    if load:
        terms["field"] = jr.Zeeman(load, math.pi)
    m = modes(jr.Scene(terms), np.zeros(24), n=24)
    P = lambda s: G * (1.0 - s) - A + load
    for w2 in m.omega_squared[:3]:
        lo, hi = w2 * (1 - 1e-4), w2 * (1 + 1e-4)
        root = brentq(lambda x: _determinant(x, P), lo, hi, xtol=1e-13, rtol=1e-14)
        assert abs(w2 - root) <= 1e-8 * root


def test_the_soft_mode_at_a_fold_goes_as_the_fourth_root_of_the_distance():
    """On the stable branch next to the paper's upper fold the lowest omega^2 falls as
    |alpha - alpha*|^(1/2) (so omega as its fourth root), and is zero at the fold."""
    scene = jr.Scene({"bending": jr.Bending(), "gravity": jr.Gravity(2.2),
                      "magnet": jr.Dipole(0.0236, 11.25 / 9.2, 0.0)})
    fold = max(jr.folds(scene, "magnet.alpha", 0.0, math.pi / 2), key=lambda f: f.value)
    at = scene.replace("magnet.alpha", fold.value)
    assert abs(modes(at, fold.state, n=16).omega_squared[0]) <= 1e-8
    w2 = []
    deltas = (1e-3, 1e-4, 1e-5)
    for d in deltas:
        near = scene.replace("magnet.alpha", fold.value - d)  # the side of the two states
        # the normal form alpha - alpha* = c (q - q*)^2 predicts both states (phi: int = 1)
        dq = math.sqrt(d / abs(fold.normal_form_c))
        states = [jr.equilibrium(near, state=fold.state + s * dq * fold.null_vector, n=16)
                  for s in (1.0, -1.0)]
        stable = [e for e in states if e.stable]
        assert stable
        w2.append(modes(near, stable[0].state, n=16).omega_squared[0])
    slopes = np.diff(np.log(w2)) / np.diff(np.log(deltas))
    assert np.all(np.abs(slopes - 0.5) < 0.02), slopes


def test_in_hertz():
    """f = omega / (2 pi L^2 sqrt(rho A / (E I))): the first mode of a 10 cm steel rod of
    radius 1 mm against the textbook (beta^2 / 2 pi) sqrt(E I / (rho A L^4))."""
    L, r, E, rho = 0.1, 1e-3, 200e9, 7850.0
    f = in_hertz(cantilever_omegas(1)[0], L, r, E, rho)
    A, I = math.pi * r**2, math.pi * r**4 / 4
    assert abs(f - 1.8751040687**2 / (2 * math.pi) * math.sqrt(E * I / (rho * A * L**4))) \
        <= 1e-6 * f


def test_cli_modes_json(tmp_path):
    """The clamped rod's modes from the command line, with the damping ratios of a drag c
    and a Kelvin-Voigt eta (c / 2 omega + eta omega / 2 on the unloaded rod) and a figure of
    the shapes."""
    proc = run_cli("modes", "--G", "0", "--A", "0", "--json", "--damping", "0.5",
                   "--kelvin-voigt", "1e-3", "--plot", tmp_path / "modes.png")
    assert proc.returncode == 0, proc.stderr
    out = json.loads(proc.stdout)
    omega = out["omega"]
    assert omega == sorted(omega)
    for w, r in zip(omega[:3], cantilever_omegas(3)):
        assert abs(w - r) <= 1e-8 * r
    for w, z in zip(omega, out["damping_ratio"]):
        assert z == pytest.approx(0.5 / (2 * w) + 1e-3 * w / 2, rel=1e-8)
    assert (tmp_path / "modes.png").stat().st_size > 0


def test_modes_along_a_branch_change_sign_at_its_folds():
    """The lowest omega^2 along the paper's branch: positive where the branch is stable,
    negative where it is not, and its sign changes exactly where folds were detected."""
    scene = jr.Scene({"bending": jr.Bending(), "gravity": jr.Gravity(2.2),
                      "magnet": jr.Dipole(0.0236, 11.25 / 9.2, 0.0)})
    b = jr.branch(scene, "magnet.alpha", 0.0, math.pi / 2, n=16)
    w2 = jr.modes_along(scene, b, n=16, count=2)
    assert w2.shape == (len(b.value), 2) and np.all(w2[:, 0] <= w2[:, 1])
    assert np.array_equal(w2[:, 0] > 0, b.stable)
    changes = np.nonzero(np.sign(w2[:-1, 0]) != np.sign(w2[1:, 0]))[0]
    assert np.array_equal(changes, b.fold_indices)


def test_cli_branch_of_a_scene_file_has_the_modes_as_rows(capsys):
    """jaxrod branch RIG --modes 2: the lowest omega^2 at every point, negative exactly where
    the branch is unstable (it crosses zero at both folds of the rotating field)."""
    from jaxrod.cli import main

    assert main(["branch", "hard-magnetic-cantilever", "--vary", "field.0.angle_deg",
                 "--from", "90", "--to", "300", "--modes", "2", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    w2 = np.array(out["omega_squared"])
    assert w2.shape == (out["points"], 2) and len(out["folds"]) == 2
    assert np.array_equal(w2[:, 0] > 0, np.array(out["stable"]))


def test_thirty_modes_are_right_or_not_printed(capsys):
    """jaxrod modes --count 30 prints 30 modes, each the classical cantilever's to 1e-8
    (it printed 24, modes 14-24 wrong, mode 24 by 23x): N is raised from 24 until the 30
    agree with a coarser degree's; asked for more than the largest degree resolves, a
    clear error; at a degree capped below what they need, UNDER_RESOLVED."""
    from jaxrod.cli import main
    from jaxrod.dynamics.modes import resolved_modes

    assert main(["modes", "--G", "0", "--A", "0", "--count", "30", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["converged"] and out["status"] == "success" and out["resolved"] == 30
    ref = np.array(cantilever_omegas(30))
    assert len(out["omega"]) == 30
    assert np.max(np.abs(np.array(out["omega"]) / ref - 1.0)) <= 1e-8
    scene = jr.Scene({"bending": jr.Bending()})
    capped = resolved_modes(scene, 14, n=8, n_max=32)
    assert capped.status == jr.Status.UNDER_RESOLVED and capped.resolved < 14
    with pytest.raises(jr.ParameterError, match="count"):
        resolved_modes(scene, 200)
