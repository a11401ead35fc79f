"""Any number of a rig, varied by name: the path through the scene's inputs
(``jaxrod.scenes.path``), one program for every key, and the checks of concrete inputs."""

import math

import jax
import numpy as np
import pytest
from scipy.optimize import brentq

import jaxrod as jr
from jaxrod.equilibria.folds import folds
from jaxrod.params import ParameterError
from jaxrod.scenes.files import load
from jaxrod.scenes.path import along
from jaxrod.scenes.terms import Bending, Dipole, Gravity

N = 12


def _leaves(scene):
    return np.concatenate([np.ravel(v) for v in jax.tree_util.tree_leaves(scene)])


@pytest.mark.parametrize("settings", [
    ["rod.youngs_modulus=1.5e11"], ["rod.length=0.08"], ["rod.radius=3e-5"],
    ["field.0.diameter=0.012"], ["gravity.g=5.0"], ["field.0.angle_deg=30.0"],
    ["rod.youngs_modulus=1.5e11", "rod.length=0.08", "field.0.angle_deg=30.0"]])
def test_a_rig_number_moves_the_scene_as_the_file_built_there(settings):
    """The path's products of powers against the rig file built anew at the new values
    (``jaxrod.scenes.files``, an independent route through every group): to round-off."""
    rig = load("permanent-magnet")
    keys = [s.split("=")[0] for s in settings]
    values = [float(s.split("=")[1]) for s in settings]
    moved = along(rig, keys)
    built = load("permanent-magnet", settings).scene
    np.testing.assert_allclose(_leaves(moved.at(np.array(values))), _leaves(built),
                               rtol=1e-14, atol=1e-15)
    np.testing.assert_allclose(_leaves(moved.at_host(*values)), _leaves(built), rtol=1e-14,
                               atol=1e-15)


def _paper_fold_angles(settings):
    """The paper's fold angles (degrees) of the rig built with ``settings``: the paper's own
    route (the reduced diagram in alpha, ``jr.folds`` of ``DipoleMagnet``) on the groups
    the file gives."""
    scene = load("permanent-magnet", settings).scene
    G, M, D = (float(scene.value(k)) for k in ("gravity.G", "field0.M", "field0.D"))
    return [f.alpha_deg for f in jr.folds(jr.DipoleMagnet(G, M, D, 0.0), n=N).folds]


@pytest.mark.parametrize("key, alpha, start, stop", [
    ("rod.youngs_modulus", 35.0, 1.0e11, 4.0e11),
    ("rod.length", 30.0, 0.06, 0.104)])
def test_folds_in_a_physical_input_agree_with_the_folds_in_the_angle(key, alpha, start, stop):
    """Varying Young's modulus (or the rod's length) at a fixed magnet angle: the two folds
    in E (in L), each where one of the paper's folds in the angle, computed at that E by the
    paper's route, sits at the fixed angle (Brent's root of alpha_fold(E) - alpha). Both
    solve to Newton's 1e-12 in their scaled parameters at the same N; the fold angle moves
    by O(1) radian per unit of ln E, so the two values agree to ~1e-11 relative: asked 1e-9."""
    rig = load("permanent-magnet", [f"field.0.angle_deg={alpha}"])
    found = folds(rig, key, start, stop, n=N)
    assert len(found) == 2
    for f in found:
        roots = []
        for which in (0, 1):
            g = lambda v: _paper_fold_angles([f"{key}={v!r}"])[which] - alpha
            lo, hi = 0.99 * f.value, 1.01 * f.value
            if g(lo) * g(hi) < 0:
                roots.append(brentq(g, lo, hi, xtol=1e-15 * f.value, rtol=1e-15))
        assert len(roots) == 1
        assert abs(f.value / roots[0] - 1.0) <= 1e-9, (f.value, roots[0])


@pytest.mark.parametrize("make, key", [
    (lambda: jr.Scene({"bending": Bending(), "magnet": Dipole(0.02, 0.5)}), "magnet"),
    (lambda: jr.Scene({"bending": Bending(), "gravity": Gravity(math.nan)}), "gravity.G"),
    (lambda: load("permanent-magnet", ["rod.length=-0.09"]), "rod.length")])
def test_bad_inputs_in_python_are_named_before_any_work(make, key):
    """A magnet on the rod, a NaN, a negative length: one ParameterError naming the input."""
    with pytest.raises(ParameterError, match=key.replace(".", r"\.")):
        jr.equilibrium(make(), n=N)


def test_a_range_that_ends_past_a_valid_rig_is_refused_naming_the_key():
    rig = load("permanent-magnet")
    with pytest.raises(ParameterError, match=r"rod\.youngs_modulus"):
        folds(rig, "rod.youngs_modulus", 2e11, -1e11, n=N)
    with pytest.raises(ParameterError, match=r"rod\.lenght.*did you mean 'rod\.length'"):
        folds(rig, "rod.lenght", 0.08, 0.09, n=N)


def test_the_command_line_varies_youngs_modulus(capsys):
    """``jaxrod folds permanent-magnet --vary rod.youngs_modulus``: the folds in Pa."""
    import json

    from jaxrod.cli import main

    code = main(["folds", "permanent-magnet", "--vary", "rod.youngs_modulus", "--from",
                 "1e11", "--to", "4e11", "--set", "field.0.angle_deg=35", "--n", "12",
                 "--json"])
    out = json.loads(capsys.readouterr().out)
    rig = load("permanent-magnet", ["field.0.angle_deg=35"])
    expected = [f.value for f in folds(rig, "rod.youngs_modulus", 1e11, 4e11, n=out["n"])]
    assert code == 0 and out["converged"]
    np.testing.assert_allclose([f["value"] for f in out["folds"]], expected, rtol=1e-12)


def test_the_folds_are_a_differentiable_function_of_any_rig_number():
    """``jr.fold_function``: the two fold angles of the paper's rig as a function of Young's
    modulus and the rod's length (each enters several groups non-linearly), its Jacobian by
    implicit differentiation against central differences of ``jr.folds`` (a continuation
    from the straight rod at each value), Richardson-extrapolated from h = 1e-3 and 5e-4
    (error O(h^4) ~ 1e-12, the folds refined to 1e-12): asked 1e-7 relative. vmap over
    parameter sets, and a key that is vary, refused."""
    rig = load("permanent-magnet")
    keys = ["rod.youngs_modulus", "rod.length"]
    f, p0 = jr.fold_function(rig, "field.0.angle_deg", (0.0, 90.0), keys, n=N)
    values, converged = f(p0)
    assert bool(converged)
    np.testing.assert_allclose(values, [g.value for g in folds(
        rig, "field.0.angle_deg", 0.0, 90.0, n=N)], rtol=0, atol=1e-9)
    J = np.asarray(jax.jacfwd(lambda p: f(p)[0])(p0))

    def central(j, h):
        at = [[g.value for g in folds(load("permanent-magnet", [
            f"{keys[j]}={float(p0[j] * (1 + s * h))!r}"]), "field.0.angle_deg", 0.0, 90.0,
            n=N)] for s in (1, -1)]
        return (np.array(at[0]) - np.array(at[1])) / (2 * h * p0[j])

    for j in range(2):
        richardson = (4 * central(j, 5e-4) - central(j, 1e-3)) / 3
        np.testing.assert_allclose(J[:, j], richardson, rtol=1e-7)
    batch, ok = jax.vmap(f)(np.stack([p0, p0 * 1.01]))
    assert bool(np.all(ok)) and np.allclose(batch[0], values, rtol=0, atol=1e-12)
    with pytest.raises(ParameterError, match="inputs"):
        jr.fold_function(rig, "field.0.angle_deg", (0.0, 90.0), ["field.0.angle_deg"], n=N)
