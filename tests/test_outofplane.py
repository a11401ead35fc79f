import json
import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxrod.discretise.director import director_discretisation
from jaxrod.discretise.planar import planar_discretisation
from jaxrod.magnet import diagram as magnet
from jaxrod.magnet import folds as magnet_folds
from jaxrod.scenes.three_d import DipoleMagnet3D, UniformField3D, magnet_position
from jaxrod.scenes.uniform import UniformField
from jaxrod.solvers.descent import descend
from jaxrod.solvers.newton import newton
from jaxrod.three_d.outofplane import out_of_plane, out_of_plane_batch

D = 11.25 / 9.2
N = 16


def _newton_3d(scene3, x0, ddisc):
    return newton(lambda x, _: jax.grad(scene3.energy)(x, ddisc), x0, None, tol=1e-12)


def test_3d_energies_restricted_to_the_plane_are_the_planar_ones():
    ddisc = director_discretisation(N)
    theta = jnp.asarray(np.random.default_rng(1).normal(size=N)) * 0.4
    x = ddisc.from_planar(theta)
    planar = magnet.make_scene(2.2, 0.0236, D).with_alpha(0.3)
    three = DipoleMagnet3D(2.2, 0.0236, D, magnet_position(0.3))
    assert float(three.energy(x, ddisc)) == pytest.approx(
        float(planar.energy(theta, ddisc.planar)), rel=1e-13)
    pinned = director_discretisation(N, "pinned")
    th_p = jnp.asarray(np.random.default_rng(2).normal(size=N + 1)) * 0.4
    assert float(UniformField3D(10.0, 3.0).energy(pinned.from_planar(th_p), pinned)) == \
        pytest.approx(float(UniformField(10.0, 3.0).energy(th_p, pinned.planar)), rel=1e-13)


def _planar_equilibrium(scene, alpha):
    """A stable planar equilibrium at alpha, by Newton from the nearest stable branch point."""
    branch = magnet.trace_diagram(scene, N)
    i = int(np.argmin(np.abs(branch.alpha - alpha) + 10 * (~branch.stable)))
    planar = magnet._equilibrium(jnp.asarray(branch.theta[i]), alpha, scene,
                                 planar_discretisation(N))
    assert bool(planar.converged)
    return planar


def test_3d_newton_from_an_out_of_plane_perturbation_returns_to_the_planar_equilibrium():
    scene = magnet.make_scene(2.2, 0.0236, D)
    alpha = math.radians(35.0)
    planar = _planar_equilibrium(scene, alpha)
    ddisc = director_discretisation(N)
    three = DipoleMagnet3D(scene.G, scene.M, scene.D, magnet_position(alpha))
    x0 = ddisc.from_planar(planar.x).at[N:].set(0.05 * jnp.sin(jnp.arange(1, N + 1)))
    res = _newton_3d(three, x0, ddisc)
    assert bool(res.converged)
    v1, v2 = ddisc.split(res.x)
    np.testing.assert_allclose(v1, planar.x, atol=1e-12)
    assert float(jnp.max(jnp.abs(v2))) < 1e-12


def test_magnet_off_the_plane_gives_the_rotated_planar_equilibrium():
    # gravity and the clamp are symmetric about e3: a magnet at azimuth beta gives the planar
    # equilibrium rotated by beta, a genuinely 3D state (v = theta (cos beta, sin beta))
    scene = magnet.make_scene(2.2, 0.0236, D)
    alpha, beta = math.radians(20.0), 0.7
    planar = _planar_equilibrium(scene, alpha)
    ddisc = director_discretisation(N)
    three = DipoleMagnet3D(scene.G, scene.M, scene.D, magnet_position(alpha, beta))
    # energy descent from the unrotated planar equilibrium (a large rotation for Newton)
    res = descend(lambda x, _: three.energy(x, ddisc), ddisc.from_planar(planar.x))
    v1, v2 = ddisc.split(res.x)
    assert bool(res.converged) and float(jnp.max(jnp.abs(v2))) > 0.05
    np.testing.assert_allclose(v1, planar.x * math.cos(beta), atol=1e-11)
    np.testing.assert_allclose(v2, planar.x * math.sin(beta), atol=1e-11)


@pytest.mark.parametrize("G, M", [(2.2, 0.0236), (4.4, 0.0472)])
def test_out_of_plane_form_is_positive_on_the_engaged_branch_and_matches_the_formula(G, M):
    scene = magnet.make_scene(G, M, D)
    disc = planar_discretisation(N)
    report = magnet_folds.locate_folds(scene, n=N)
    b = report.branch
    upper = [f for f in report.folds if f.kind == "upper"][0]
    sel = b.engaged  # from the straight rod up to the upper fold
    start = sel.start
    r = {k: np.asarray(v) for k, v in out_of_plane_batch(
        jnp.asarray(b.theta[sel]), jnp.asarray(b.alpha[sel]), scene, disc).items()}
    assert r["coupling"].max() == 0.0
    assert r["min_eig_perp"].min() > 1.0  # 1.80 (E = 200 GPa), 1.11 (E = 100 GPa)
    np.testing.assert_allclose(r["min_eig_perp"], r["min_eig_perp_formula"], rtol=1e-9)
    assert (r["g1"][1:] < 0).all() and r["theta_in_0_pi"][1:].all()
    # at each fold the 3D Hessian's smallest eigenvalue is the in-plane one (~0)
    for f in report.folds:
        c = out_of_plane(jnp.asarray(f.theta), math.radians(f.alpha_deg), scene, disc)
        assert abs(float(c["min_eig_plane"])) < 1e-8 < float(c["min_eig_perp"])
    assert upper.alpha_deg > np.degrees(b.alpha[start + 1])


def test_cli_outofplane_json(capsys):
    from jaxrod.cli import main

    assert main(["outofplane", "--G", "2.2", "--M", "0.0236", "--D", str(D), "--alpha", "35",
                 "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert len(out["points"]) == 3
    for p in out["points"]:
        assert {"alpha_deg", "min_eig_perp", "coupling"} <= set(p)
        assert p["coupling"] == 0.0 and p["min_eig_perp"] > 0
    with pytest.raises(SystemExit) as stop:  # argparse refuses it: exit 2
        main(["outofplane", "--G", "2.2", "--M", "0.0236", "--D", str(D), "--alpha", "95"])
    assert stop.value.code == 2
