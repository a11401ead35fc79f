"""The terms of the rigs beyond the paper's (a uniform field on a hard magnetisation, a
programmed magnetisation, a magnet anywhere, on a rail, on a curve): their assembled
derivatives against autodiff of the whole energy, their planar forms against their director
forms, and the curve's special cases."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from test_engine import _call, _state, _whole, assert_planar_forms_equal_director_forms

import jaxrod as jr
from jaxrod.derivatives import Structured
from jaxrod.discretise.director import director_discretisation
from jaxrod.discretise.planar import planar_discretisation
from jaxrod.equilibria.equilibrium import FIXED
from jaxrod.scenes.scene import Input, Scene
from jaxrod.scenes.terms import PathDipole, PointDipole, ProgrammedMagnetisation, Zeeman

N = 12


def _terms(geometry):
    terms = {"bending": jr.Bending(), "gravity": jr.Gravity(1.3),
             "field": Zeeman(2.5, 1.1, 0.2 if geometry == "3d" else 0.0),
             "magnet": PointDipole(0.05, jnp.array([0.4, 0.1, 1.3]),
                                   jnp.array([0.3, 0.2, 1.0]), jnp.array([1.0, 0.0, 0.2]),
                                   0.1),
             "guide": PathDipole(0.04, jnp.array([[-0.5, 0.0, 1.4], [1.0, 0.0, 0.1],
                                                  [0.3, 0.0, -0.2]]), 0.3,
                                 jnp.array([0.0, 0.0, 1.0]), 1.0)}
    if geometry == "planar":
        terms["programmed"] = ProgrammedMagnetisation(1.5, 0.7, jnp.array([0.2, -0.4, 0.3]))
    return terms


@pytest.mark.parametrize("geometry", ["planar", "3d"])
def test_assembled_derivatives_equal_autodiff(geometry):
    scene = Scene(_terms(geometry), geometry=geometry)
    disc = planar_discretisation(N) if geometry == "planar" else director_discretisation(N)
    x = _state(disc.size)
    model = Structured(Input("field.angle"))
    ref = _whole(model.scene_at)
    names = ("energy", "gradient", "hessian", "gradient_lam")

    @jax.jit
    def both(x, lam, args, phi):
        return tuple([getattr(m, name)(x, lam, args) for name in names]
                     + [m.third(x, lam, args, phi)] for m in (model, ref))

    got, want = both(x, 0.5, (scene, disc, 0.4, 1.2), _state(disc.size, 1.0))
    for name, a, b in zip(names + ("third",), got, want):
        assert np.max(np.abs(a - b)) <= 1e-11 * (1 + np.max(np.abs(b))), name


def test_planar_forms_equal_director_forms():
    terms = _terms("3d")
    terms["field"] = Zeeman(2.5, 1.1, 0.0)
    assert_planar_forms_equal_director_forms(Scene(terms))


def test_the_programmed_magnetisation_at_a_constant_angle_is_a_rotated_field():
    """phi constant: -load cos(theta + phi - a) is the tangent magnetisation in the field
    rotated by -phi."""
    disc = planar_discretisation(N)
    x = _state(disc.size)
    a = Scene({"bending": jr.Bending(), "f": ProgrammedMagnetisation(3.0, 1.0,
                                                                     jnp.array([0.3]))})
    b = Scene({"bending": jr.Bending(), "f": Zeeman(3.0, 0.7)})
    for name in ("energy", "gradient", "hessian"):
        u = _call(FIXED, name, x, 0.0, (a, disc))
        v = _call(FIXED, name, x, 0.0, (b, disc))
        assert np.max(np.abs(u - v)) <= 1e-12 * (1 + np.max(np.abs(v))), name


def test_a_curve_of_degree_one_is_a_rail():
    c0, u = np.array([0.5, 0.0, 1.2]), np.array([0.8, 0.0, 0.6])
    curve = PathDipole(0.1, jnp.stack([c0, u]), 0.7, jnp.array([0.0, 0.0, 1.0]), 0.0)
    rail = PointDipole(0.1, c0, jnp.array([0.0, 0.0, 1.0]), u, 0.7)
    X = jnp.array([0.3, 0.05, 0.9])
    assert abs(curve.endpoint(X) - rail.endpoint(X)) <= 1e-15
    bent = PathDipole(0.1, jnp.array([[0.0, 0.0, 1.5], [1.0, 0.0, 0.0], [0.0, 0.0, -0.5]]),
                      0.4, jnp.array([0.0, 0.0, 1.0]), 1.0)
    assert np.allclose(bent.centre(), [0.4, 0.0, 1.5 - 0.5 * 0.16], atol=1e-15)
    t = np.array([1.0, 0.0, -0.4])
    assert np.allclose(bent.tangent(), t / np.linalg.norm(t), atol=1e-15)


def test_a_magnet_on_a_curve_in_a_scene_file(tmp_path):
    """path = "curve": the degree-one curve from (0.5, 1.2) along x gives the rail's folds in
    t, as the magnet's horizontal position shifted by 0.5."""
    from test_scene_files import RAIL

    from jaxrod.scenes.files import load

    path = tmp_path / "curve.toml"
    path.write_text(RAIL.replace("position = [0.0, 1.2]        # on a straight rail at "
                                 "height 1.2 rod lengths",
                                 "path = \"curve\"\ncoefficients = [[0.5, 1.2], [1.0, 0.0]]"))
    file = load(path)
    key, factor = file.input_of("field.0.t")
    got = [f.value / factor for f in jr.folds(file.scene, key, -0.5, 1.0, n=16)]
    rail = tmp_path / "rail.toml"
    rail.write_text(RAIL)
    ref_file = load(rail)
    ref = [f.value for f in jr.folds(ref_file.scene, "field0.position.0", 0.0, 1.5,
                                           n=16)]
    assert len(got) == len(ref) == 2
    assert all(abs(g + 0.5 - r) <= 1e-10 for g, r in zip(got, ref))


def test_a_programmed_magnetisation_in_a_magnets_field():
    """The distributed form: with phi = 0 it is the tangent magnetisation's endpoint form
    (the same equilibrium to round-off); with a profile, two discretisations agree and a
    scene file builds it."""
    from jaxrod.scenes.terms import ProgrammedDipole

    c, u = jnp.array([0.3, 0.0, 1.3]), jnp.array([0.2, 0.0, 1.0])
    endpoint = Scene({"bending": jr.Bending(), "m": PointDipole(0.3, c, u)})
    distributed = Scene({"bending": jr.Bending(), "m": ProgrammedDipole(0.3, c, u)})
    a, b = jr.equilibrium(endpoint, n=16), jr.equilibrium(distributed, n=16)
    assert abs(a.tip_tangent_deg - b.tip_tangent_deg) <= 1e-10
    bent = Scene({"bending": jr.Bending(),
                  "m": ProgrammedDipole(0.3, c, u, jnp.array([0.2, 0.5]))})
    coarse, fine = jr.equilibrium(bent, n=16), jr.equilibrium(bent, n=32)
    assert abs(coarse.tip_tangent_deg - fine.tip_tangent_deg) <= 1e-9
    assert abs(coarse.tip_tangent_deg - a.tip_tangent_deg) > 1.0  # the profile matters


def test_a_programmed_magnetisation_with_a_magnet_in_a_scene_file(tmp_path):
    from test_scene_files import RAIL

    from jaxrod.scenes.files import load
    from jaxrod.scenes.terms import ProgrammedDipole

    path = tmp_path / "rail.toml"
    path.write_text(RAIL.replace('kind = "soft"', 'kind = "hard"\nangle_deg = 10'))
    file = load(path)
    assert isinstance(file.scene.terms["field0"], ProgrammedDipole)
    eq = jr.equilibrium(file.scene.replace("field0.position.0", 0.5), n=16)
    assert eq.converged
