"""Out-of-plane stability of any planar scene's equilibrium, against the paper's own check
(``jaxrod.three_d.outofplane``, with the written-out 3D dipole energy) and a symmetry."""

import math

import jax.numpy as jnp
import numpy as np
import pytest

import jaxrod as jr
from jaxrod.discretise.planar import planar_discretisation
from jaxrod.params import ParameterError
from jaxrod.scenes.dipole import DipoleMagnet
from jaxrod.three_d.outofplane import out_of_plane

G, M, D = 2.2, 0.0236, 11.25 / 9.2


@pytest.mark.parametrize("alpha_deg", [10.0, 25.0])
def test_the_papers_scene_as_terms_against_the_papers_check(alpha_deg):
    a = math.radians(alpha_deg)
    scene = jr.Scene({"bending": jr.Bending(), "gravity": jr.Gravity(G),
                      "magnet": jr.Dipole(M, D, a)})
    eq = jr.equilibrium(scene, n=16)
    got = jr.out_of_plane_stability(scene, eq.state, n=16)
    ref = out_of_plane(jnp.asarray(eq.state), a, DipoleMagnet(G, M, D, a),
                       planar_discretisation(16, "clamped"))
    assert abs(got.min_eig_perp - float(ref["min_eig_perp"])) <= 1e-10 * abs(got.min_eig_perp)
    assert abs(got.min_eig_plane - float(ref["min_eig_plane"])) <= 1e-10 * got.min_eig_plane
    assert got.coupling <= 1e-12 and got.stable_out_of_plane


def test_the_opposed_field_pitchfork_is_isotropic():
    """The straight hard-magnetic cantilever at load pi^2/4 with the field opposite: by the
    rod's symmetry about its axis, the in-plane and out-of-plane forms are equal and both
    singular."""
    scene = jr.Scene({"bending": jr.Bending(), "field": jr.Zeeman(math.pi**2 / 4, math.pi)})
    r = jr.out_of_plane_stability(scene, np.zeros(16), n=16)
    assert abs(r.min_eig_plane) <= 1e-10 and abs(r.min_eig_perp - r.min_eig_plane) <= 1e-10


def test_a_bent_hard_magnetic_cantilever_stays_in_its_plane():
    scene = jr.Scene({"bending": jr.Bending(), "field": jr.Zeeman(20.0, math.radians(150))})
    eq = jr.equilibrium(scene, n=16)
    r = jr.out_of_plane_stability(scene, eq.state, n=16)
    assert r.stable_out_of_plane and r.min_eig_plane > 0 and r.coupling <= 1e-12


@pytest.mark.parametrize("make", ["programmed", "programmed_dipole"])
def test_planar_only_terms_are_refused(make):
    """A programmed magnetisation has no 3D form: its out-of-plane check and any 3D scene
    with it are refused, naming the term."""
    from jaxrod.scenes.scene import SceneError
    from jaxrod.scenes.terms import ProgrammedDipole, ProgrammedMagnetisation

    t = ProgrammedMagnetisation(1.0) if make == "programmed" else ProgrammedDipole(0.1)
    scene = jr.Scene({"bending": jr.Bending(), "field": t})
    with pytest.raises(ParameterError, match="no 3D form"):
        jr.out_of_plane_stability(scene, np.zeros(16), n=16)
    with pytest.raises(SceneError, match="'field' has no 3D form"):
        jr.Scene({"bending": jr.Bending(), "field": t}, geometry="3d")
