"""Rods twisted with both ends held (``jaxrod.twisted``): the branch in the end rotation and
PyElastica's helical buckling state against the closed form of the localised helix.

Reference (van der Heijden, Neukirch, Goss, Thompson 2003, eqs. 27 and 52; the long-rod
limit of the localised helix of a rod clamped at both ends): with end shortening d (in L)
and end rotation R (radians), the end moment m = M L / B and tension t = T L^2 / B solve

    d = sqrt(16 / t (1 - m^2 / (4 t))),    R = m / gamma + 4 arccos(m / (2 sqrt t)),

and the centreline, s in [-1/2, 1/2] from the middle, t' = t / 4 pi^2, m' = m / 2 pi,
k = pi sqrt(4 t' - m'^2), lies at distance A / cosh(k s) from the axis, A = sqrt(4 t' -
m'^2) / (2 pi t'). Solved here by scipy's fsolve.
"""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxrod.discretise.framed import framed_jet
from jaxrod.params import ParameterError
from jaxrod.scenes.terms import TaperedBending
from jaxrod.twisted.branch import twist_branch, twisted_equilibrium
from jaxrod.twisted.rod import TwistedRod

#: PyElastica's HelicalBucklingCase: B = 1.345, C = 0.789 (gamma = 0.58662 to five digits).
PYELASTICA_GAMMA = 0.789 / 1.345
#: The same case as a scene file.
PYELASTICA_RIG = f"""units = "nondimensional"
geometry = "3d"
[rod]
support = "clamped-clamped"
twist_ratio = {PYELASTICA_GAMMA!r}
[ends]
rotation_turns = 27.0
shortening = 0.03
"""


@pytest.mark.parametrize("kwargs, name", [
    (dict(twist_ratio=0.0, shortening=0.1), "twist_ratio"),
    (dict(bending_ratio=-1.0, shortening=0.1), "bending_ratio"),
    (dict(twist_ratio=float("nan"), shortening=0.1), "twist_ratio"),
    (dict(shortening=0.1, tension=10.0), "tension, shortening"),
    (dict(), "tension, shortening"),
    (dict(shortening=1.0), "shortening"),
    (dict(shortening=0.0), "shortening"),
    (dict(tension=float("inf")), "tension"),
    (dict(shortening=0.1, n=6), "n"),
    (dict(shortening=0.1, loads={"a": TaperedBending(), "b": TaperedBending()}), "loads"),
])
def test_bad_inputs_are_named(kwargs, name):
    with pytest.raises(ParameterError, match=f"^{name}:"):
        TwistedRod(**kwargs)


@pytest.mark.slow
def test_the_branch_keeps_its_linking_number_and_its_end_moment_is_the_twist_at_the_end():
    """Shortening 0.1, gamma = 0.7, from the Euler-buckled rod to 3 turns at n = 32: every
    point converged (its residual below the corrector's 1e-10); Tw + Wr = turns to 1e-12
    (Calugareanu-White-Fuller); the reported end moment (the energy's derivative in the
    turns) equals the constitutive moment about the axis at the far clamp, gamma u3(1),
    to 1e-8 (the far end's frame is turned about e3, so M . e3 = C u3 there; a pointwise
    value, it converges spectrally: 1e-4, 3e-7, 8e-10 at n = 16, 24, 32); the first
    point's tension is the Euler elastica's thrust, negative. A state under tension control
    cannot start a rod under shortening control."""
    rod = TwistedRod(twist_ratio=0.7, shortening=0.1, n=32)
    branch = twist_branch(rod, 3.0, ds_max=1.0)
    assert branch.message.startswith("reached the end") and branch.points[-1].turns >= 3.0
    disc = rod.discretisation()
    for p in branch.points:
        assert p.converged and p.residual <= 1e-10
        assert abs(p.twist + p.writhe - p.turns) <= 1e-12
        jet_at_far_end = disc.jets(p.x, p.turns)[-1]
        assert abs(p.twist_moment - 0.7 * float(framed_jet(jet_at_far_end)[1][2])) <= 1e-8
    assert branch.points[0].tension < -4 * math.pi**2
    state = twisted_equilibrium(rod, 2.5, start=branch.points[0], ds_max=1.0)
    assert state.converged and abs(state.turns - 2.5) == 0.0
    on_tension = twisted_equilibrium(
        TwistedRod(twist_ratio=0.7, tension=state.tension, n=32), 2.5, start=state)
    assert on_tension.converged and abs(on_tension.twist_moment - state.twist_moment) <= 1e-9
    with pytest.raises(ParameterError, match="start"):
        twist_branch(rod, 3.0, start=on_tension)


def _closed_form(gamma: float, shortening: float, turns: float) -> tuple[float, float]:
    from scipy.optimize import fsolve

    def equations(mt):
        m, t = mt
        return [math.sqrt(16.0 / t * (1.0 - m * m / (4.0 * t))) - shortening,
                m / gamma + 4.0 * math.acos(m / (2.0 * math.sqrt(t))) - 2 * math.pi * turns]

    m, t = fsolve(equations, [100.0, 3000.0], xtol=1e-14)
    assert max(abs(r) for r in equations((m, t))) <= 1e-9
    return m, t


@pytest.mark.slow
def test_pyelastica_helical_buckling_state_is_the_localised_helix():
    """PyElastica's helical buckling case (gamma = 0.789 / 1.345, shortening 0.03, 27 turns),
    reached by turning the far end of the Euler-buckled rod at n = 48, then solved at
    n = 96, 128, 192: the end moment and tension converge spectrally (their change to
    n = 192 falls a hundredfold from n = 96 to 128) and agree with the long-rod closed form
    (module docstring), 98.541496 and 2900.9932, to 1e-7 relative at n = 192 (measured:
    1.3e-8, the finite length; the printed 98.5415 and 2900.99 to every digit); the
    distance of the centreline from the axis is A / cosh(k s) to within the infinite
    helix's own distance at the two clamps, 2 A / cosh(k / 2) = 7.6e-5 A, where the finite
    rod's is zero (measured: 4.3e-5 A; 1.4e-5 A over the middle half); the far end is where
    the clamp holds it; the state is stable (the under-resolved n = 96 shows a spurious
    unstable direction; its status says so: UNDER_RESOLVED, while n = 192 is resolved)."""
    m_ref, t_ref = _closed_form(PYELASTICA_GAMMA, 0.03, 27.0)
    assert round(m_ref, 4) == 98.5415 and round(t_ref, 2) == 2900.99
    rod = TwistedRod(twist_ratio=PYELASTICA_GAMMA, shortening=0.03, n=48)
    branch = twist_branch(rod, 27.0, ds_max=2.0)
    assert not branch.folds
    state = twisted_equilibrium(rod, 27.0, start=branch.points[-2])
    reactions = []
    for n in (96, 128, 192):
        state = twisted_equilibrium(TwistedRod(twist_ratio=PYELASTICA_GAMMA, shortening=0.03,
                                               n=n), 27.0, start=state)
        assert state.converged
        if n == 96:
            assert state.unstable == 1 and state.status.name == "UNDER_RESOLVED"
        reactions.append(np.array([state.twist_moment, state.tension]))
    change = [np.max(np.abs(r / reactions[-1] - 1)) for r in reactions[:2]]
    assert change[1] <= 0.01 * change[0]
    error = max(abs(state.twist_moment / m_ref - 1), abs(state.tension / t_ref - 1))
    assert error <= 1e-7 and state.unstable == 0 and state.status.name == "SUCCESS"
    assert round(state.twist_moment, 4) == 98.5415 and round(state.tension, 2) == 2900.99
    tp, mp = t_ref / (4 * math.pi**2), m_ref / (2 * math.pi)
    root = math.sqrt(4 * tp - mp * mp)
    amplitude, k = root / (2 * math.pi * tp), math.pi * root
    from jaxrod import spectral

    s_fine = np.linspace(0.0, 1.0, 401)
    s, r = state.centreline()
    xy = spectral.interpolation_matrix(len(s) - 1, s_fine) @ r[:, :2]
    radius = np.hypot(xy[:, 0], xy[:, 1])
    expected = amplitude / np.cosh(k * (s_fine - 0.5))
    assert np.max(np.abs(radius - expected)) <= 2 * amplitude / np.cosh(k / 2)
    assert abs(r[-1, 2] - 0.97) <= 1e-12 and np.max(np.abs(r[-1, :2])) <= 1e-12
    jax.clear_caches()


@pytest.mark.slow
def test_the_fold_from_the_command_line(tmp_path):
    """PyElastica's case as a scene file, ``jaxrod branch --vary ends.rotation_turns --from 27
    --to 39 --layer-width 0.015 --centred --max-folds 1 --json``: the branch ends at its
    first fold, refined and reported in turns, the closed form's (``_localised_fold``) to
    1e-10, with its moment and tension; the run is complete and resolved."""
    import json

    from command_line import run_cli

    rig = tmp_path / "helical.toml"
    rig.write_text(PYELASTICA_RIG)
    proc = run_cli("branch", rig, "--vary", "ends.rotation_turns", "--from", "27", "--to",
                   "39", "--layer-width", "0.015", "--centred", "--max-folds", "1", "--json")
    assert proc.returncode == 0, proc.stderr
    out = json.loads(proc.stdout)
    assert out["status"] == "success" and out["complete"] and len(out["folds"]) == 1
    fold = out["folds"][0]
    for key, reference in zip(("value", "twist_moment", "tension"),
                              _localised_fold(PYELASTICA_GAMMA, 0.03)):
        assert abs(fold[key] / reference - 1) <= 1e-10
    jax.clear_caches()


def _loaded_rod(**kwargs) -> TwistedRod:
    """A rod under every kind of load the framed rod takes: gravity off the axis, a soft
    wire's anisotropy, a programmed remanence in a tilted field and in a magnet's field (on
    the positions along the rod), a magnet at the far end; its section tapered."""
    from jaxrod.scenes.terms import (
        Anisotropy,
        Gravity,
        PointDipole,
        ProgrammedDipole,
        ProgrammedMagnetisation,
        TaperedBending,
    )

    loads = {"gravity": Gravity(2.0, jnp.array([0.6, 0.0, -0.8])),
             "soft": Anisotropy(1.5, jnp.array([0.0, 0.6, 0.8])),
             "field": ProgrammedMagnetisation(3.0, 0.4, jnp.array([0.3, -0.5]),
                                              jnp.array([1.0, 0.2])),
             "magnet": PointDipole(0.7, jnp.array([0.5, 0.2, 2.5])),
             "programmed magnet": ProgrammedDipole(0.4, jnp.array([1.5, 0.3, 0.8]),
                                                   jnp.array([0.0, 1.0, 0.2]),
                                                   jnp.array([0.3, 0.5])),
             "bending": TaperedBending(jnp.array([1.0, -0.2, 0.05]))}
    return TwistedRod(loads=loads, **kwargs)


@pytest.mark.slow
def test_pyelastica_case_as_a_scene_file_is_reached_by_turning_while_approaching(tmp_path):
    """PyElastica's case as a scene file (gamma = 0.789 / 1.345 to every digit, 3%
    shortening, 27 turns): ``jaxrod equilibrium --json`` turns the far end while it
    approaches at n = 48 and doubles n until resolved; its end moment and tension are the
    closed form's to 1e-7 (the finite length), and the state is stable."""
    import json

    from command_line import run_cli

    rig = tmp_path / "helical.toml"
    rig.write_text(PYELASTICA_RIG)
    proc = run_cli("equilibrium", rig, "--json")
    assert proc.returncode == 0, proc.stderr
    out = json.loads(proc.stdout)
    m_ref, t_ref = _closed_form(PYELASTICA_GAMMA, 0.03, 27.0)
    assert abs(out["twist_moment"] / m_ref - 1) <= 1e-7
    assert abs(out["tension"] / t_ref - 1) <= 1e-7
    assert out["stable"] and out["status"] == "success" and out["n"] >= 96
    jax.clear_caches()


@pytest.mark.slow
def test_the_assembled_linearisation_is_the_lagrangians_derivatives():
    """The branch's residual and Jacobian, assembled from the nodes' 6 x 6 Hessians, the
    far-end terms' 3 x 3 Hessian and the path's column by forward mode, equal autodiff of
    the Lagrangian (the definition: energy with every kind of load and the centring, the
    far end's three constraints, the phase condition on and pinned, a path through the
    turns and a field's strength together) at a random point of an anisotropic rod, to
    round-off (1e-13 of the largest entry)."""
    from jaxrod.twisted import equations

    rod = _loaded_rod(twist_ratio=0.6, bending_ratio=1.3, shortening=0.1, n=8, centred=True)
    disc, k, keys = rod.discretisation(), rod.constraints, ("turns", "field.load")
    w = np.random.default_rng(1).normal(size=disc.size + k + 2) * 0.3
    x_ref, c, _ = equations._phase(jnp.asarray(w[:disc.size] + 0.1), disc, True)
    data, m = equations._Path(keys, (0.0, 0.0), (1.0, 2.5)).data(rod, 0.3, disc), \
        disc.size + k + 1
    grad = jax.grad(equations._lagrangian)
    assembled = jax.jit(equations._linearise, static_argnums=(3, 4))
    reference = jax.jit(lambda *a: (grad(*a), jax.jacfwd(grad)(*a)), static_argnums=(3, 4))
    for on in (1.0, 0.0):
        aux = (x_ref, c * on, jnp.asarray(on))
        R, J = assembled(w, aux, data, keys, k)
        R0, J0 = reference(w, aux, data, keys, k)
        np.testing.assert_allclose(R, R0[:m], rtol=0, atol=1e-13 * np.max(np.abs(R0)))
        np.testing.assert_allclose(J, J0[:m], rtol=0, atol=1e-13 * np.max(np.abs(J0)))


def _localised_fold(gamma: float, shortening: float) -> tuple[float, float, float]:
    """The localised helix's fold in the end rotation under shortening control, in the
    long-rod limit (module docstring): with u = d^2 t / 16, m = (8 / d) sqrt(u (1 - u)) and
    R = m / gamma + 4 arcsin(sqrt u), so dR/du = 0 at u = 1/2 + gamma d / 4: (turns, m, t)
    there. Beyond it (u > 1/2 + gamma d / 4) R falls again: the branch turns back."""
    d = shortening
    u = 0.5 + gamma * d / 4.0
    m = 8.0 / d * math.sqrt(u * (1.0 - u))
    turns = (m / gamma + 4.0 * math.asin(math.sqrt(u))) / (2.0 * math.pi)
    return turns, m, 16.0 * u / d**2


@pytest.mark.slow
def test_pyelastica_cases_fold_in_end_rotation_is_the_closed_forms():
    """PyElastica's case turned on from 27 turns (3% shortening): the localised helix
    tightens (k = sqrt(4 t - m^2) / 2 from 22 to 67) and stays stable to a fold at 36.676
    turns, beyond which no nearby state exists and the branch turns back unstable. The
    closed form (``_localised_fold``, exact for the long rod; the finite rod's difference
    is of order exp(-k), 1e-29) gives the fold's turns, moment and tension; here at n = 96
    on the grid gathered into a layer of width 0.015 at the middle, the slide held by the
    centring (its stiffness exp(-67) of the others otherwise, below round-off): to 1e-10
    (measured: 1e-14, 3e-14, 2e-12). The fold curve in (rotation, shortening), traced
    across the turns from this branch (``twist_fold_curve``: at 34 and 28 turns the fold
    in the shortening): the closed form's d with R(d) = those turns, and t = 8 / d^2 +
    4 gamma / d there (u = 1/2 + gamma d / 4), to 1e-10 (measured 3e-14)."""
    from scipy.optimize import brentq

    from jaxrod.twisted.fold_curve import twist_fold_curve

    turns_f, m_f, t_f = _localised_fold(PYELASTICA_GAMMA, 0.03)
    rod = TwistedRod(twist_ratio=PYELASTICA_GAMMA, shortening=0.03, n=48)
    branch = twist_branch(rod, 27.0, ds_max=2.0)
    start = twisted_equilibrium(rod, 27.0, start=branch.points[-2])
    rod = TwistedRod(twist_ratio=PYELASTICA_GAMMA, shortening=0.03, n=96, layer_width=0.015,
                     centred=True)
    start = twisted_equilibrium(rod, 27.0, start=start)
    branch = twist_branch(rod, 39.0, start=start, ds_max=0.5, max_folds=1)
    assert len(branch.folds) == 1 and len(branch.fold_points) == 1
    i = branch.folds[0]
    before, after = branch.points[:i], branch.points[i:]
    assert all(p.unstable == 0 and p.status.name == "SUCCESS" for p in before)
    assert all(p.unstable == 1 for p in after if p.status.name == "SUCCESS")
    fold = branch.fold_points[0]
    assert fold.converged and fold.state.status.name == "SUCCESS"
    assert abs(fold.value / turns_f - 1) <= 1e-10
    assert abs(fold.state.twist_moment / m_f - 1) <= 1e-10
    assert abs(fold.state.tension / t_f - 1) <= 1e-10
    curve = twist_fold_curve(branch, [34.0, 28.0], "shortening", 0.08, ds_max=0.5)
    assert curve.complete
    for turns, d, t in zip(curve.turns, curve.column("value"), curve.column("tension")):
        d_ref = brentq(lambda e: _localised_fold(PYELASTICA_GAMMA, e)[0] - turns, 0.02, 0.2,
                       xtol=1e-15)
        assert abs(d / d_ref - 1) <= 1e-10
        assert abs(t / (8.0 / d_ref**2 + 4.0 * PYELASTICA_GAMMA / d_ref) - 1) <= 1e-10
    jax.clear_caches()


def test_the_straight_rods_branch_points_are_the_greenhill_moments():
    """The straight rod turned from 0 to 5 turns at n = 16 under tension t = 10, 0, 100
    and -10: the branch's count of unstable directions jumps by 2 (the rotational
    symmetry's two-dimensional kernel, where a determinant would not change sign); the
    first branch point's twisting moment is the linearised equations' (the determinant
    method of tests/test_framed.py; at t = 0 2 x with tan x = x) to 1e-8. At t = 10 half
    the pull is a field b = 5 along the axis on the rod's axial remanence (energy
    -b int d3 . e3: a dead load). The bent branch leaves the branch point subcritically
    (toward fewer turns), one direction unstable."""
    from scipy.optimize import brentq
    from test_framed import _critical_moment_by_determinant

    from jaxrod.scenes.terms import Zeeman
    from jaxrod.twisted.branch import switch_branch

    x = brentq(lambda v: math.tan(v) - v, 4.0, 4.6, xtol=1e-15)
    for t, b, reference in ((100.0, 0.0, None), (0.0, 0.0, 2 * x), (10.0, 5.0, None),
                            (-10.0, 0.0, None)):
        rod = TwistedRod(twist_ratio=0.769, tension=t - b, n=16,
                         loads={"field0": Zeeman(b)})
        branch = twist_branch(rod, 5.0)
        assert branch.complete and not branch.folds
        first = branch.branch_points[0]
        assert first.converged and first.unstable == (0, 2)
        reference = reference or _critical_moment_by_determinant(t)
        assert abs(first.state.twist_moment / reference - 1) <= 1e-8
    bent = switch_branch(first, 0.0, ds_max=0.3)
    assert bent.complete and all(p.unstable == 1 for p in bent.points)
    assert all(p.converged and p.residual <= 1e-10 for p in bent.points)
    assert bent.points[1].turns < first.state.turns


def _contact_branch(n: int, layer_width: float) -> tuple:
    """PyElastica's rod (3% shortening) with self-contact at its diameter 0.007 L, turned
    from 25 turns (the helix reached by turning while approaching, at n = 48, then
    regridded) to 40."""
    rod = TwistedRod(twist_ratio=PYELASTICA_GAMMA, shortening=0.03, n=48)
    start = twisted_equilibrium(rod, 25.0)
    rod = TwistedRod(twist_ratio=PYELASTICA_GAMMA, shortening=0.03, n=n,
                     layer_width=layer_width, centred=True, contact_diameter=0.007)
    start = twisted_equilibrium(rod, 25.0, start=start)
    return twist_branch(rod, 40.0, start=start, ds_max=1.0, max_points=200)


@pytest.mark.slow
def test_self_contact_closes_the_hysteresis_loop_of_the_localised_helix():
    """PyElastica's rod of diameter 0.007 L turned on under 3% shortening. The helix's fold
    (no contact yet: its strands 2.2 h apart) is the closed form's to 1e-10. Past it the
    loop tightens, unstable, as the turns fall, until its strands touch (self-distance h);
    held apart there (never closer than 0.95 h: the penalty's overlap), the branch turns
    back at a second fold at fewer turns and climbs, stable, past the first fold's turns
    (one unstable direction between the folds). The rod turned on jumps there; turned
    back, it stays looped down to the second fold: the hysteresis loop. The second fold
    at n = 96 (layer 0.012) and n = 128 (layer 0.01) agree to 0.5% (a contact state's
    kink is resolved algebraically, not spectrally; measured 0.19%)."""
    turns_f, _, _ = _localised_fold(PYELASTICA_GAMMA, 0.03)
    lows = []
    for n, width in ((96, 0.012), (128, 0.01)):
        branch = _contact_branch(n, width)
        assert branch.complete and len(branch.folds) == 2
        up, down = branch.fold_points
        assert up.converged and down.converged
        assert abs(up.value / turns_f - 1) <= 1e-10 and up.state.self_distance > 2 * 0.007
        assert down.value < up.value and down.state.self_distance <= 0.007
        assert branch.column("self_distance").min() >= 0.95 * 0.007
        between = branch.points[branch.folds[0]:branch.folds[1]]
        after = branch.points[branch.folds[1]:]
        assert after[-1].turns > up.value and all(p.self_distance < 0.007 for p in after)
        # one unstable direction between the folds, none on the looped branch
        assert all(p.unstable == 1 for p in between[1:-1] if p.converged)
        assert all(p.unstable == 0 for p in after[1:] if p.converged)
        lows.append(down.value)
    assert abs(lows[0] / lows[1] - 1) <= 5e-3
    jax.clear_caches()


@pytest.mark.slow
def test_an_axial_field_changes_nothing_under_shortening_control_but_the_reaction():
    """A hard-magnetic rod magnetised along its tangent in a field b = 5 along the axis,
    its far end held at 1 - e and turned once (the state reached by turning while
    approaching, n = 16): the field's energy -b int d3 . e3 is constant, so the state and
    its moment are those without the field (to Newton's tolerance), and the clamp's
    reaction is less by b."""
    from jaxrod.scenes.terms import Zeeman

    states = [twisted_equilibrium(TwistedRod(twist_ratio=0.7, shortening=0.1, n=16,
                                             loads={"field": Zeeman(b)}), 1.0)
              for b in (5.0, 0.0)]
    assert all(s.converged for s in states)
    assert abs(states[0].twist_moment - states[1].twist_moment) <= 1e-9
    assert abs(states[0].tension - (states[1].tension - 5.0)) <= 1e-8
    np.testing.assert_allclose(states[0].x, states[1].x, rtol=0, atol=1e-9)


HELD = """
units = "nondimensional"
geometry = "3d"
[rod]
support = "clamped-clamped"
twist_ratio = 0.769
[ends]
rotation_turns = 1.0
tension = 5.0
[magnetisation]
kind = "hard"
[[field]]
kind = "uniform"
load = 5.0
angle_deg = 0.0
"""


def test_the_command_line_on_a_rod_held_at_both_ends(tmp_path):
    """``jaxrod branch RIG --vary ends.rotation_turns --json`` on a scene file of the
    clamped-clamped rod pulled by 5 and by a field of 5 on its axial remanence: its first
    branch point (in turns) is where the straight rod's moment 2 pi gamma turns reaches the
    determinant method's under tension 10, a two-dimensional kernel; ``jaxrod equilibrium``
    prints the straight rod's twisting moment 2 pi gamma turns and the clamp's pull."""
    import json

    from command_line import run_cli
    from test_framed import _critical_moment_by_determinant

    rig = tmp_path / "held.toml"
    rig.write_text(HELD)
    proc = run_cli("branch", rig, "--vary", "ends.rotation_turns", "--from", "0", "--to",
                   "2.5", "--n", "16", "--json")
    assert proc.returncode == 0, proc.stderr
    out = json.loads(proc.stdout)
    first = out["branch_points"][0]
    moment = 2 * math.pi * 0.769 * first["value"]
    assert abs(moment / _critical_moment_by_determinant(10.0) - 1) <= 1e-8
    assert first["unstable"] == [0, 2] and first["kernel_dimension"] == 2
    assert out["folds"] == [] and out["converged"] and out["value"][-1] >= 2.5
    proc = run_cli("equilibrium", rig, "--n", "16", "--json")
    out = json.loads(proc.stdout)
    assert proc.returncode == 0 and out["status"] == "success" and out["stable"]
    assert abs(out["twist_moment"] - 2 * math.pi * 0.769) <= 1e-12
    assert out["tension"] == 5.0 and out["turns"] == 1.0


@pytest.mark.slow
def test_the_framed_cantilever_in_an_opposed_field_buckles_at_pi_squared_over_four():
    """A cantilever (a free end) that carries its frame, magnetised along its tangent, in a
    field opposite its magnetisation raised from 0 to 4 (n = 16, the load path): the
    straight rod's count of unstable directions jumps from 0 to 2 (in the plane and out of
    it, the symmetry's two-dimensional kernel; the twist takes no part) at the tip-loaded
    elastica's pi^2 / 4, to 1e-10."""
    from jaxrod.scenes.terms import Zeeman

    rod = TwistedRod(support="clamped", n=16, loads={"field0": Zeeman(0.0, math.pi)})
    branch = twist_branch(rod, 4.0, vary="field0.load")
    assert branch.complete and not branch.folds
    first = branch.branch_points[0]
    assert first.converged and first.unstable == (0, 2)
    assert abs(first.value / (math.pi**2 / 4) - 1) <= 1e-10


@pytest.mark.slow
@pytest.mark.parametrize("rig, settings", [
    ("cantilever", []),
    ("cantilever", ["magnetisation.angle_deg=30.0"]),
    ("permanent-magnet", ["field.0.angle_deg=20.0"]),
    ("rail", ["field.0.position.0=0.5"]),
    ("tapered", ["magnetisation.angle_deg=30.0"]),
])
def test_planar_scenes_as_framed_rods_give_their_planar_numbers(rig, settings, tmp_path):
    """Planar scenes (a hard-magnetic cantilever in a field across it, the same programmed
    at 30 degrees to its tangent, the paper's rig with its magnet at 20 degrees, a rod
    programmed at 10 degrees under gravity in a magnet's non-uniform field: a load on the
    positions along the rod, ``jaxrod.twisted.distributed``; the cantilever tapered, E I(s)
    / E I = 1 - 0.4 T_1 + 0.1 T_2, programmed at 30 degrees) solved as
    rods that carry their frame (n = 24, the load ramp from the straight rod): the tip angle
    is the planar rod's (n = 24 and above until resolved) to 1e-9 degrees, the rod stays in
    its plane, and its count of unstable directions (in the plane, out of it and in twist)
    is zero where the planar state is stable and, where the 3D director model has the
    term, stable out of the plane."""
    from test_scene_files import CANTILEVER, RAIL

    from jaxrod.equilibria.resolution import resolved_equilibrium
    from jaxrod.scenes.files import load
    from jaxrod.three_d.scene_stability import out_of_plane_stability

    path = rig
    if rig in ("cantilever", "tapered"):
        path = tmp_path / "cantilever.toml"
        text = CANTILEVER
        if rig == "tapered":
            text = text.replace("support = \"clamped\"", "support = \"clamped\"\n"
                                "stiffness_profile = [1.0, -0.4, 0.1]")
        if settings:
            text = text.replace("remanence = 1.0e5", "remanence = 1.0e5\nangle_deg = 0.0")
        path.write_text(text)
    elif rig == "rail":
        path = tmp_path / "rail.toml"
        path.write_text(RAIL.replace('kind = "soft"', 'kind = "hard"\nangle_deg = 10'))
    file = load(path, settings)
    planar = resolved_equilibrium(file.scene, n=24)
    assert planar.status.name == "SUCCESS"
    loads = {k: t for k, t in file.scene.terms.items() if type(t).__name__ != "Bending"}
    state = twisted_equilibrium(TwistedRod(support="clamped", n=24, loads=loads), 0.0)
    assert state.status.name == "SUCCESS"
    X = state.tip_position()
    assert abs(math.degrees(math.atan2(X[0], X[2])) - planar.equilibrium.tip_angle_deg) <= 1e-9
    assert np.max(np.abs(state.centreline()[1][:, 1])) <= 1e-12
    stable = planar.equilibrium.stable
    if rig == "permanent-magnet" or (rig == "cantilever" and not settings):
        stable = stable and out_of_plane_stability(
            file.scene, planar.equilibrium.state, planar.n).stable_out_of_plane
    assert (state.unstable == 0) == stable


@pytest.mark.slow
def test_the_framed_cantilevers_folds_are_the_planar_rods(tmp_path):
    """The shipped hard-magnetic cantilever (load 5) as a rod that carries its frame
    (n = 24), its field turned from 90 to 300 degrees: the branch's folds, refined where the
    path parameter turns back (``jaxrod.twisted.folds``), are the planar engine's folds
    (``jaxrod folds``, refined by their extended system) to 1e-9 degrees."""
    import json

    from command_line import run_cli

    from jaxrod.scenes.files import load

    proc = run_cli("folds", "hard-magnetic-cantilever", "--vary", "field.0.angle_deg",
                   "--from", "90", "--to", "300", "--json")
    planar = [f["value"] for f in json.loads(proc.stdout)["folds"]]
    assert proc.returncode == 0 and planar
    file = load("hard-magnetic-cantilever")
    loads = {k: t for k, t in file.scene.terms.items() if k != "bending"}
    rod = TwistedRod(support="clamped", n=24, loads=loads)
    start = twisted_equilibrium(rod, 0.0)
    branch = twist_branch(rod, math.radians(300.0), vary="field0.angle", start=start,
                          ds_max=0.2)
    framed = [math.degrees(f.value) for f in branch.fold_points]
    assert all(f.converged for f in branch.fold_points)
    assert len(framed) == len(planar)
    assert max(abs(a - b) for a, b in zip(framed, planar)) <= 1e-9


def test_the_phase_condition_is_on_only_where_the_whole_path_keeps_the_symmetry():
    """A symmetric rod (an axial field) keeps its phase condition along its turns or its
    field's strength, and drops it along the field's angle or the bending ratio, which
    break the symmetry part way (a phase condition there would force states that are no
    equilibria); a rod whose field is across the axis has none."""
    from jaxrod.scenes.terms import Zeeman
    from jaxrod.twisted.equations import _Path

    axial = TwistedRod(tension=1.0, n=8, loads={"field0": Zeeman(2.0)})
    across = TwistedRod(tension=1.0, n=8, loads={"field0": Zeeman(2.0, 1.0)})
    assert axial.symmetric and not across.symmetric
    for keys, on in ((("turns",), True), (("field0.load",), True),
                     (("turns", "shortening"), True), (("field0.angle",), False),
                     (("bending_ratio",), False)):
        path = _Path(keys, (0.0,) * len(keys), (1.0,) * len(keys))
        assert path.phase(axial) == on and not path.phase(across)


@pytest.mark.slow
def test_a_field_out_of_the_plane_by_its_azimuth(tmp_path):
    """``[[field]] azimuth_deg`` in 3D (``jaxrod equilibrium RIG --json``): the cantilever
    magnetised along its tangent in the field at 90 degrees turned to azimuth 60 has its tip
    where the field at azimuth 0 puts it, turned by 60 degrees about z (the rod's symmetry;
    to 1e-12); programmed at 30 degrees to its tangent (a rod that carries its frame), the
    field at 90 degrees and azimuth 180 is the field at -90 degrees (the same state, to
    1e-12). A planar rod refuses an azimuth, naming the key."""
    import json

    from command_line import run_cli
    from test_scene_files import CANTILEVER

    def tip(azimuth, angle=90.0, programmed=False):
        text = "geometry = \"3d\"\n" + CANTILEVER.replace(
            "angle_deg = 90          # from +z toward +x",
            f"angle_deg = {angle}\nazimuth_deg = {azimuth}")
        if programmed:
            text = text.replace("remanence = 1.0e5", "remanence = 1.0e5\nangle_deg = 30.0")
        path = tmp_path / "rig.toml"
        path.write_text(text)
        proc = run_cli("equilibrium", path, "--json")
        assert proc.returncode == 0, proc.stderr
        return np.array(json.loads(proc.stdout)["tip_position"])

    turned, c = tip(60.0), math.radians(60.0)
    rotation = np.array([[math.cos(c), -math.sin(c), 0.0], [math.sin(c), math.cos(c), 0.0],
                         [0.0, 0.0, 1.0]])
    np.testing.assert_allclose(turned, rotation @ tip(0.0), rtol=0, atol=1e-12 * 0.05)
    np.testing.assert_allclose(tip(180.0, programmed=True), tip(0.0, -90.0, programmed=True),
                               rtol=0, atol=1e-12 * 0.05)
    (tmp_path / "planar.toml").write_text(CANTILEVER.replace(
        "angle_deg = 90          # from +z toward +x", "angle_deg = 90\nazimuth_deg = 10"))
    proc = run_cli("equilibrium", tmp_path / "planar.toml")
    assert proc.returncode == 2 and "field.0.azimuth_deg" in proc.stderr
    jax.clear_caches()
