"""Fits and maps of twisted rods (``jaxrod.inverse.twist_fit``, ``jaxrod.twisted.fold_map``): the
localised helix's fold in end rotation, its sensitivities, a fit and a map, against the
long-rod closed form; bad inputs."""

from __future__ import annotations

import functools
import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from test_twisted import PYELASTICA_GAMMA, _localised_fold

from jaxrod.inverse.twist_fit import fit_twist_folds
from jaxrod.params import ParameterError
from jaxrod.twisted.branch import twist_branch, twisted_equilibrium
from jaxrod.twisted.fold_map import twist_fold_map
from jaxrod.twisted.folds import fold_sensitivity
from jaxrod.twisted.rod import TwistedRod


def _helix_rod(**kwargs) -> TwistedRod:
    """PyElastica's rod (3% shortening) at n = 96 on a grid gathered at the middle, its
    localised state centred: its fold is the closed form's to 1e-10 (``test_twisted``)."""
    return TwistedRod(**{"twist_ratio": PYELASTICA_GAMMA, "shortening": 0.03, "n": 96,
                         "layer_width": 0.015, "centred": True, **kwargs})


@functools.lru_cache(maxsize=1)
def _helix_branch():
    """The branch from 27 turns to its fold (the start reached at n = 48 first)."""
    rod = TwistedRod(twist_ratio=PYELASTICA_GAMMA, shortening=0.03, n=48)
    start = twisted_equilibrium(rod, 27.0)
    start = twisted_equilibrium(_helix_rod(), 27.0, start=start)
    return twist_branch(_helix_rod(), 39.0, start=start, ds_max=0.5, max_folds=1)


def _fold_turns(shortening, gamma):
    """The closed form's fold (``_localised_fold``) in jax, to differentiate."""
    u = 0.5 + gamma * shortening / 4.0
    m = 8.0 / shortening * jnp.sqrt(u * (1.0 - u))
    return (m / gamma + 4.0 * jnp.arcsin(jnp.sqrt(u))) / (2.0 * math.pi)


@pytest.mark.slow
def test_the_folds_sensitivities_are_the_closed_forms_derivatives():
    """d(fold turns)/d(shortening) and d/d(twist ratio) at PyElastica's fold (36.676
    turns), from the fold's null vector and the residual's forward-mode derivatives, are
    the closed form's derivatives (autodiff of the closed form) to 1e-8 (measured 1e-10:
    the fold itself is the closed form's to 1e-13)."""
    branch = _helix_branch()
    fold = branch.fold_points[0]
    assert fold.converged and abs(fold.value / _localised_fold(PYELASTICA_GAMMA, 0.03)[0]
                                  - 1) <= 1e-10
    sens = fold_sensitivity(fold, "turns", ["shortening", "twist_ratio"])
    ref = jax.grad(_fold_turns, argnums=(0, 1))(0.03, PYELASTICA_GAMMA)
    np.testing.assert_allclose(sens, np.array(ref), rtol=1e-8)


@pytest.mark.slow
def test_a_fit_recovers_the_shortening_from_the_measured_fold():
    """The fold measured at the closed form's 36.676 turns (sigma 0.01 turns), the
    shortening fitted from 0.031: 0.03 to 1e-9, its standard deviation sigma over the
    sensitivity (the closed form's derivative), in a few Gauss-Newton steps."""
    turns = _localised_fold(PYELASTICA_GAMMA, 0.03)[0]
    start = _helix_branch().points[0]
    rod = _helix_rod(shortening=0.031)
    fit = fit_twist_folds(rod, "turns", (27.0, 39.0), [turns], ["shortening"], sigma=0.01,
                          ds_max=0.5, start=start)
    assert fit.converged and fit.iterations <= 8, fit.reason
    assert abs(fit.estimates["shortening"] / 0.03 - 1) <= 1e-9
    slope = float(jax.grad(_fold_turns)(0.03, PYELASTICA_GAMMA))
    assert abs(fit.std["shortening"] / (0.01 / abs(slope)) - 1) <= 1e-6
    assert abs(fit.residuals[0]) <= 1e-9


@pytest.mark.slow
def test_a_map_of_the_fold_over_shortening_and_twist_ratio_is_the_closed_forms():
    """The first fold in end rotation over a 2 x 2 grid of shortening (0.03, 0.032) and
    twist ratio (0.5866, 0.62), one fold looked for: at every point the closed form's to
    1e-10 (measured 2e-14), every point SUCCESS."""
    m = twist_fold_map(_helix_rod(), "turns", (27.0, 39.0), ("shortening", [0.03, 0.032]),
                       ("twist_ratio", [PYELASTICA_GAMMA, 0.62]), folds=1, ds_max=0.5)
    assert np.all(m.status == 0) and np.all(m.count == 1)
    for j, gamma in enumerate(m.y_values):
        for i, d in enumerate(m.x_values):
            assert abs(m.first[j, i] / _localised_fold(gamma, d)[0] - 1) <= 1e-10
    jax.clear_caches()


@pytest.mark.parametrize("kwargs, name", [
    (dict(measured=[float("nan")]), "measured"),
    (dict(measured=[float("inf")]), "measured"),
    (dict(free=["turns"]), "free"),
    (dict(free=["tension"]), "tension: not an input of this rod"),
    (dict(free=["shortening", "shortening"]), "free"),
    (dict(sigma=0.0), "sigma"),
    (dict(bounds={"shortening": (0.05, 0.06)}), "bounds"),
])
def test_a_fits_bad_inputs_are_named(kwargs, name):
    rod = TwistedRod(shortening=0.03, n=8)
    args = {"measured": [30.0], "free": ["shortening"], **kwargs}
    with pytest.raises(ParameterError, match=name):
        fit_twist_folds(rod, "turns", (27.0, 39.0), args.pop("measured"), args.pop("free"),
                        **args)


@pytest.mark.parametrize("x, y, folds, name", [
    (("turns", [1.0]), ("shortening", [0.1]), 2, "x, y"),
    (("shortening", [0.1]), ("shortening", [0.2]), 2, "x, y"),
    (("shortening", [0.1]), ("twist_ratio", [0.6]), 3, "folds"),
    (("shortening", [float("nan")]), ("twist_ratio", [0.6]), 2, "finite"),
    (("tension", [1.0]), ("twist_ratio", [0.6]), 2, "tension: not an input"),
])
def test_a_maps_bad_inputs_are_named(x, y, folds, name):
    with pytest.raises(ParameterError, match=name):
        twist_fold_map(TwistedRod(shortening=0.03, n=8), "turns", (0.0, 2.0), x, y,
                       folds=folds)


@pytest.mark.slow
def test_fit_and_map_of_a_framed_cantilever_from_the_command_line(tmp_path):
    """The shipped hard-magnetic cantilever as a rod that carries its frame (3D, its
    remanence programmed at 0 degrees), its field turned from 90 to 300 degrees, n = 24,
    against the planar engine (``jaxrod folds``, an independent discretisation): ``jaxrod
    folds`` of the framed file gives the planar folds to 1e-8 degrees;
    ``jaxrod fit`` from B = 1.3 mT to the planar folds at 1.25 mT recovers 1.25 mT to 1e-9;
    ``jaxrod map`` over B = 1.25 and 1.4 mT gives both folds at each B to 1e-8 degrees,
    with map.json and map.png; ``jaxrod foldcurve`` along B (two points) the first fold
    at each to 1e-8 degrees."""
    import json
    from pathlib import Path

    from command_line import run_cli

    import jaxrod

    text = (Path(jaxrod.__file__).parent / "rigs" / "hard-magnetic-cantilever.toml").read_text()
    rig = tmp_path / "framed.toml"
    rig.write_text("geometry = \"3d\"\n" + text.replace(
        "remanence = 1.0e5         # A/m, along the tangent", "remanence = 1.0e5\nangle_deg = 0.0"))
    span = ["--vary", "field.0.angle_deg", "--from", "90", "--to", "300"]

    def planar(B):
        proc = run_cli("folds", "hard-magnetic-cantilever", *span, "--set", f"field.0.B={B}",
                       "--json")
        assert proc.returncode == 0, proc.stderr
        return [f["value"] for f in json.loads(proc.stdout)["folds"]]

    at, above = planar(1.25e-3), planar(1.4e-3)
    assert len(at) == len(above) == 2
    proc = run_cli("folds", rig, *span, "--n", "24", "--json")
    assert proc.returncode == 0, proc.stderr + proc.stdout
    folds = [f["value"] for f in json.loads(proc.stdout)["folds"]]
    assert len(folds) == 2 and max(abs(a - b) for a, b in zip(folds, at)) <= 1e-8
    proc = run_cli("fit", rig, *span, "--set", "field.0.B=1.3e-3", "--free", "field.0.B",
                   "--folds", *map(str, at), "--sigma", "0.1", "--n", "24", "--json")
    assert proc.returncode == 0, proc.stderr + proc.stdout
    out = json.loads(proc.stdout)
    assert out["converged"] and abs(out["estimates"]["field.0.B"] / 1.25e-3 - 1) <= 1e-9
    proc = run_cli("map", rig, *span, "--x", "field.0.B:1.25e-3:1.4e-3:2", "--y",
                   "magnetisation.angle_deg:0:0:1", "--n", "24", "--out", tmp_path / "map",
                   "--quiet", "--json")
    assert proc.returncode == 0, proc.stderr + proc.stdout
    m = json.loads((tmp_path / "map" / "map.json").read_text())
    assert m["count"] == [[2, 2]] and m["failed_points"] == 0
    for i, ref in enumerate((at, above)):
        assert abs(m["first"][0][i] - ref[0]) <= 1e-8
        assert abs(m["second"][0][i] - ref[1]) <= 1e-8
    assert (tmp_path / "map" / "map.png").exists()
    proc = run_cli("foldcurve", rig, *span, "--along", "field.0.B",
                   "--along-to", "1.4e-3", "--points", "2", "--n", "24", "--json")
    assert proc.returncode == 0, proc.stderr + proc.stdout
    curve = json.loads(proc.stdout)
    assert curve["converged"] and curve["along_values"] == [1.25e-3, 1.4e-3]
    assert max(abs(v - ref[0]) for v, ref in zip(curve["values"], (at, above))) <= 1e-8
