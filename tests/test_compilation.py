"""Public entry points compile once: a second and third call with new parameter values (same
N, same shapes) compile nothing. Compilations are counted with JAX's own monitoring events
(one '/jax/core/compile/backend_compile_duration' event per XLA compilation)."""

import contextlib

import jax
import numpy as np
import pytest
from jax import monitoring

from jaxrod.inverse import youngs as fit_youngs
from jaxrod.magnet import diagram as magnet
from jaxrod.magnet import folds as magnet_folds
from jaxrod.magnet import sweep as magnet_sweep
from jaxrod.magnet.batch import fold_pairs
from jaxrod.uniform import greenhill

_count = [0]
_listening = [False]


def _listener(name, duration, **kwargs):
    if _listening[0] and "backend_compile" in name:
        _count[0] += 1


monitoring.register_event_duration_secs_listener(_listener)


@contextlib.contextmanager
def compilations():
    """Counts XLA compilations inside the block: ``with compilations() as c: ...; c[0]``."""
    _count[0] = 0
    _listening[0] = True
    try:
        yield _count
    finally:
        _listening[0] = False


D_EXP = 11.25 / 9.2
# (G, M) pairs of the paper's wire at E = 200, 180, 160 GPa
VALUES = [(2.2 * 200 / E, 0.0236 * 200 / E) for E in (200.0, 180.0, 160.0)]


def _recompiles(call) -> list[int]:
    """Compilations of each call after the first, each with new values."""
    call(*VALUES[0])
    counts = []
    for values in VALUES[1:]:
        with compilations() as c:
            call(*values)
        counts.append(c[0])
    return counts


def test_counter_sees_a_compilation():
    f = jax.jit(lambda x: x * 3.0 + 1.0)
    with compilations() as c:
        f(np.arange(7.0))
    assert c[0] >= 1


@pytest.mark.parametrize("name, call", [
    ("fold_angles", lambda G, M: magnet_folds.fold_angles(G, M, D_EXP)),
    ("grad fold_angles",
     lambda G, M: jax.grad(lambda g: magnet_folds.fold_angles(g, M, D_EXP)[0][1])(G)),
    ("fold_pair", lambda G, M: magnet_folds.fold_pair(magnet.make_scene(G, M, D_EXP))),
    ("locate_folds", lambda G, M: magnet_folds.locate_folds(magnet.make_scene(G, M, D_EXP), n=12)),
    ("fold_pairs", lambda G, M: fold_pairs(np.array([G, 1.1 * G]), np.array([M, M]),
                                           np.full(2, D_EXP))),
    ("greenhill", lambda G, M: greenhill.greenhill(4.0 * G, "clamped", A=300.0 * M)),
    ("hysteresis_sweep", lambda G, M: magnet_sweep.hysteresis_sweep(
        magnet.make_scene(G, M, D_EXP), n=12, alpha_max_deg=10.0, step_deg=2.0)),
])
def test_no_recompilation_for_new_values(name, call):
    assert _recompiles(call) == [0, 0], name


def test_fit_does_not_recompile():
    angles = [[-25.0, 38.0, 24.0, -42.0], [-26.0, 37.0, 25.0, -41.0], [-24.0, 39.0, 23.0, -43.0]]
    fit_youngs.fit_youngs_modulus(angles[0], 1.0, True)
    for a in angles[1:]:
        with compilations() as c:
            fit_youngs.fit_youngs_modulus(a, 1.0, True)
        assert c[0] == 0


def test_out_of_plane_rows_of_another_count_compile_nothing():
    """A diagram's length depends on the values; the out-of-plane check pads its rows to a
    power of two, so that 5 and 7 rows (a branch of another length) share one program."""
    from jaxrod.discretise.planar import planar_discretisation
    from jaxrod.three_d.outofplane import out_of_plane, out_of_plane_at_rows

    scene = magnet.make_scene(2.2, 0.0236, D_EXP)
    disc = planar_discretisation(8)
    rng = np.random.default_rng(1)
    theta, alpha = 0.3 * rng.standard_normal((7, disc.size)), rng.uniform(-0.5, 0.5, 7)
    first = out_of_plane_at_rows(theta[:5], alpha[:5], scene, disc)
    with compilations() as c:
        rows = out_of_plane_at_rows(theta, alpha, scene, disc)
    assert c[0] == 0
    assert rows["min_eig_perp"].shape == (7,)
    np.testing.assert_allclose(rows["min_eig_perp"][:5], first["min_eig_perp"], rtol=1e-12)
    one = out_of_plane(theta[6], alpha[6], scene, disc)  # the last row, on its own
    np.testing.assert_allclose(rows["min_eig_perp"][6], one["min_eig_perp"], rtol=1e-10)


def test_a_second_key_of_the_same_scene_compiles_nothing():
    """One program per scene structure and N (the varied key is a traced path through the
    scene's inputs, ``jaxrod.scenes.path``): after the folds along one key, the folds along
    two others (one fold and none: other counts than the first's two), the equilibrium and
    a fit's start (the fold guesses) compile nothing."""
    import math

    import jaxrod as jr
    from jaxrod.equilibria.folds import fold_guesses, folds

    scene = jr.DipoleMagnet(2.2, 0.0236, 1.2228, 0.0).scene
    assert len(folds(scene, "magnet.alpha", 0.0, 0.5 * math.pi, n=12)) == 2
    with compilations() as c:
        other = folds(scene, "magnet.M", 0.0236, 0.06, n=12, throw=False)
        none = folds(scene, "gravity.G", 2.2, 2.0, n=12)
        eq = jr.equilibrium(scene, n=12)
        guesses, _ = fold_guesses(scene, "magnet.alpha", 0.0, 0.5 * math.pi, 2, n=12)
    assert none == [] and len(other) != 2
    assert eq.converged and len(guesses) == 2
    assert c[0] == 0


def test_fold_curves_along_a_second_input_compile_nothing():
    """The fold curves of a design point run on the path through all of its inputs: after
    the curves and the cusp in D, those in G and the cusp in M compile nothing."""
    import jaxrod as jr

    point = jr.DesignPoint.from_groups(2.2, 0.0236, D_EXP)
    assert all(c.converged for c in jr.fold_curves(point, "D", 1.25, n=8))
    assert jr.cusp(point, "D", n=8).converged
    with compilations() as c:
        along_G = jr.fold_curves(point, "G", 2.6, n=8)
        cusp_M = jr.cusp(point, "M", n=8)
    assert all(c.converged for c in along_G) and cusp_M.kind in ("cusp", "none")
    assert c[0] == 0


def test_a_new_duration_or_step_of_a_motion_compiles_nothing():
    """The integrators take the step size traced and the step count within a static budget
    (``jaxrod.programs.steps_loop``): after a motion of 40 steps, one of 37 steps of another
    size and another end compile nothing, and give the first's states where they coincide
    (the same steps: the first 20 of each)."""
    from jaxrod.dynamics.integrate import simulate
    from jaxrod.scenes.dipole import DipoleMagnet

    scene = DipoleMagnet(2.2, 0.0236, 1.2228, 0.1).scene
    for scheme in ("midpoint", "bdf2", "discrete-gradient"):
        first = simulate(scene, np.zeros(8), 0.4, 0.01, n=8, scheme=scheme)
        with compilations() as c:
            other = simulate(scene, np.zeros(8), 0.37, 0.01, n=8, scheme=scheme)
            simulate(scene, np.zeros(8), 0.5, 0.0125, n=8, scheme=scheme)
        assert c[0] == 0, scheme
        assert first.states.shape[0] == 40 and other.states.shape[0] == 37
        np.testing.assert_allclose(other.states[:20], first.states[:20], rtol=0, atol=1e-13)
