"""The engine: scenes composed from terms, derivatives assembled from their structure, and the
generic analyses (equilibrium, branch, folds, fold curve, map) over any scene and input.

References: plain autodiff of the whole energy (derivatives), the paper's scenes as written
before the terms existed (energies), ``jr.folds`` and ``jr.fold_pairs`` (the paper's diagram
and fast path), a Moore-Spence solve on the autodiff energy (a new term's folds).
"""

import functools
import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from tip_spring import TipSpring

import jaxrod as jr
from jaxrod.derivatives import Autodiff, Structured
from jaxrod.discretise.director import director_discretisation
from jaxrod.discretise.planar import planar_discretisation
from jaxrod.equilibria.equilibrium import FIXED
from jaxrod.scenes.dipole import ALPHA_MODEL, DipoleMagnet
from jaxrod.scenes.scene import Input, Scene, SceneError
from jaxrod.scenes.terms import TERMS, Anisotropy, Bending, Dipole, Gravity, term
from jaxrod.scenes.three_d import DipoleMagnet3D, UniformField3D, magnet_position
from jaxrod.scenes.uniform import UniformField
from jaxrod.solvers.folds import moore_spence_solve
from jaxrod.status import SolverError, Status

G, M, D = 2.2, 0.0236, 1.2
N = 12


def paper_scene(geometry="planar", alpha=0.0, beta=0.0, **extra):
    return Scene({"bending": Bending(), "gravity": Gravity(G), "magnet": Dipole(M, D, alpha,
                                                                                beta),
                  **extra}, geometry=geometry)


def spring_scene(k=0.05):
    return paper_scene(spring=TipSpring(k, jnp.array([0.0, 0.0, 1.0])))


@term("gravity_as_distributed")
class _DistributedGravity:
    """Gravity written through the positions, G int_0^1 r(s) . e3 ds: the same energy as
    ``Gravity`` (by parts), as a distributed term (autodiff as a whole)."""

    G: float

    def distributed(self, r, d3, s, w):
        return self.G * jnp.dot(w, r[:, 2])


@functools.partial(jax.jit, static_argnums=(0, 1))
def _call(model, name, x, lam, args):
    """model.name(x, lam, args) compiled (op by op, assembled Hessians are slow)."""
    return getattr(model, name)(x, lam, args)


def _state(size, scale=0.3):
    return scale * jnp.sin(0.7 * jnp.arange(size) + 0.2)


def _whole(scene_at):
    return Autodiff(lambda x, lam, args: scene_at(lam, args)[0].energy(x, args[1]))


@pytest.mark.parametrize("geometry", ["planar", "3d"])
def test_assembled_derivatives_equal_autodiff_of_the_whole_energy(geometry):
    # every kind of term at once: densities (bending, gravity, a tilted anisotropy), two
    # endpoint potentials (the dipole, a tip spring) and a distributed term
    terms = {"spring": TipSpring(0.3, jnp.array([0.1, 0.0, 0.9])),
             "lifted": _DistributedGravity(0.7),
             "aniso": Anisotropy(1.3, jnp.array([0.6, 0.0, 0.8]))}
    scene = paper_scene(geometry, 0.4, 0.3 if geometry == "3d" else 0.0, **terms)
    disc = planar_discretisation(N) if geometry == "planar" else director_discretisation(N)
    x = _state(disc.size)
    model = Structured(Input("magnet.alpha"))
    ref = _whole(model.scene_at)
    names = ("energy", "gradient", "hessian", "gradient_lam")

    @jax.jit  # one program per case: op-by-op autodiff of Hessians is slow
    def both(x, lam, args, phi):
        return tuple([getattr(m, name)(x, lam, args) for name in names]
                     + [m.third(x, lam, args, phi)] for m in (model, ref))

    args, lam = (scene, disc, 0.1, 0.8), 0.5
    got, want = both(x, lam, args, _state(disc.size, 1.0))
    for name, a, b in zip(names + ("third",), got, want):
        assert np.max(np.abs(a - b)) <= 1e-11 * (1 + np.max(np.abs(b))), name


def test_a_distributed_term_equals_its_endpoint_form():
    disc = planar_discretisation(N)
    x = _state(disc.size)
    by_parts = paper_scene()
    distributed = Scene({"bending": Bending(), "lifted": _DistributedGravity(G),
                         "magnet": Dipole(M, D)})
    model = FIXED
    for name in ("energy", "gradient", "hessian"):
        a = _call(model, name, x, 0.0, (by_parts, disc))
        b = _call(model, name, x, 0.0, (distributed, disc))
        # int_0^1 r . e3 = int (1 - s) d3 . e3 (spectrally exact on the quadrature grid)
        assert np.max(np.abs(a - b)) <= 1e-12 * (1 + np.max(np.abs(a))), name


def assert_planar_forms_equal_director_forms(planar: Scene) -> None:
    """The planar scene's energy, gradient and Hessian at a state equal those of the same
    terms on the 3D rod at v2 = 0 (the v1 block)."""
    director = Scene(planar.terms, geometry="3d")
    disc, d3 = planar_discretisation(N), director_discretisation(N)
    x = _state(disc.size)
    y = d3.from_planar(x)
    m = disc.size
    e1 = _call(FIXED, "energy", x, 0.0, (planar, disc))
    e3 = _call(FIXED, "energy", y, 0.0, (director, d3))
    assert abs(e1 - e3) <= 1e-13 * abs(e3)
    g1, g3 = (_call(FIXED, "gradient", x, 0.0, (planar, disc)),
              _call(FIXED, "gradient", y, 0.0, (director, d3))[:m])
    assert np.max(np.abs(g1 - g3)) <= 1e-12 * (1 + np.max(np.abs(g3)))
    h1, h3 = (_call(FIXED, "hessian", x, 0.0, (planar, disc)),
              _call(FIXED, "hessian", y, 0.0, (director, d3))[:m, :m])
    assert np.max(np.abs(h1 - h3)) <= 1e-11 * (1 + np.max(np.abs(h3)))


def test_the_planar_forms_agree_with_the_director_forms():
    """On the planar rod the terms use their forms in theta (smaller programs); on the 3D rod
    at v2 = 0 the director forms give the same energy, gradient and Hessian (v1 block)."""
    terms = {"field": Anisotropy(1.3, jnp.array([0.6, 0.0, 0.8])),
             "spring": TipSpring(0.3, jnp.array([0.1, 0.0, 0.9]))}
    tilted = Gravity(G, jnp.array([0.6, 0.0, -0.8]))
    for extra in ({}, terms):
        planar = paper_scene("planar", 0.4, 0.3, **extra).replace("gravity.direction.0", 0.6)
        planar = Scene({**planar.terms, "gravity": tilted})
        assert_planar_forms_equal_director_forms(planar)


def test_the_papers_scenes_are_their_printed_energies():
    """The paper's scenes against their energies written out:
    E_perm = 1/2 int theta'^2 + G int (1 - s) cos theta + M Phi(X) and E_unif with
    A/2 int sin^2 theta (whole functionals), and the 3D classes against 3D scenes."""
    disc = planar_discretisation(N)
    x = _state(disc.size)
    for alpha in (0.0, 0.7):
        th, dth = disc.at_quadrature(x)
        w, s = disc.quad_weights, disc.quad_nodes
        X = jnp.stack([jnp.dot(w, jnp.sin(th)), jnp.dot(w, jnp.cos(th))])
        p = jnp.array([math.sin(alpha), math.cos(alpha)])
        r = X - D * p
        printed = (0.5 * jnp.dot(w, dth**2) + G * jnp.dot(w, (1 - s) * jnp.cos(th))
                   + M * jnp.dot(p, r) / jnp.dot(r, r) ** 1.5)
        assert abs(DipoleMagnet(G, M, D, alpha).energy(x, disc) - printed) <= 1e-14
        a = _call(ALPHA_MODEL, "hessian", x, alpha, (DipoleMagnet(G, M, D, 0.0), disc))
        b = jax.hessian(lambda z: DipoleMagnet(G, M, D, alpha).energy(z, disc))(x)
        assert np.max(np.abs(a - b)) <= 1e-12 * np.max(np.abs(b))
    th, dth = disc.at_quadrature(x)
    w, s = disc.quad_weights, disc.quad_nodes
    printed = (0.5 * jnp.dot(w, dth**2) + G * jnp.dot(w, (1 - s) * jnp.cos(th))
               + 1.5 * jnp.dot(w, jnp.sin(th) ** 2))
    assert abs(UniformField(G, 3.0).energy(x, disc) - printed) <= 1e-14
    # the written-out planar forms against the same scenes as terms
    for old in (DipoleMagnet(G, M, D, 0.7), UniformField(G, 3.0)):
        a = _call(FIXED, "hessian", x, 0.0, (old, disc))
        b = _call(FIXED, "hessian", x, 0.0, (old.scene, disc))
        assert np.max(np.abs(a - b)) <= 1e-13 * np.max(np.abs(b))
        assert abs(old.energy(x, disc) - old.scene.energy(x, disc)) <= 1e-14
    d3 = director_discretisation(N)
    y = _state(d3.size, 0.2)
    for scene, old in ((paper_scene("3d", 0.5, 0.2),
                        DipoleMagnet3D(G, M, D, magnet_position(0.5, 0.2))),
                       (Scene({"bending": Bending(), "gravity": Gravity(G),
                               "field": Anisotropy(3.0)}, geometry="3d"),
                        UniformField3D(G, 3.0))):
        assert abs(_call(FIXED, "energy", y, 0.0, (scene, d3)) - old.energy(y, d3)) <= 1e-14
        assert np.allclose(_call(FIXED, "hessian", y, 0.0, (scene, d3)),
                           _call(FIXED, "hessian", y, 0.0, (old, d3)), rtol=0, atol=1e-12)


def test_inputs_by_name():
    scene = spring_scene()
    assert scene.inputs() == ["gravity.G", "gravity.direction.0", "gravity.direction.1",
                              "gravity.direction.2", "magnet.M", "magnet.D", "magnet.alpha",
                              "magnet.beta", "spring.k", "spring.anchor.0", "spring.anchor.1",
                              "spring.anchor.2"]
    assert float(scene.replace("spring.anchor.2", 0.5).value("spring.anchor.2")) == 0.5
    assert float(scene.replace("magnet.D", 1.3).value("magnet.D")) == 1.3
    with pytest.raises(SceneError, match="did you mean magnet.alpha"):
        scene.replace("magnet.alhpa", 1.0)
    with pytest.raises(SceneError, match="not a scalar input"):
        scene.check_key("spring.anchor")
    with pytest.raises(SceneError, match="geometry"):
        Scene({"bending": Bending()}, geometry="2d")
    assert {"bending", "gravity", "anisotropy", "dipole", "tip_spring"} <= set(TERMS)


def test_the_generic_folds_of_the_papers_scene_agree_with_its_diagram_and_fast_path():
    found = jr.folds(jr.magnet_scene(G, M, D), n=N).folds
    generic = jr.folds(paper_scene(), "magnet.alpha", 0.0, math.pi / 2, n=N)
    # met in order along the branch: the upper fold first, then the lower one
    assert len(generic) == len(found) == 2 and generic[0].value > generic[1].value
    for f, ref in zip(generic[::-1], found):
        assert abs(math.degrees(f.value) - ref.alpha_deg) <= 1e-10
        assert abs(f.tip_angle_deg - ref.tip_deg) <= 1e-9
        # both in radians: alpha - alpha* ~ c (q - q*)^2
        assert abs(f.normal_form_c - ref.normal_form_c) <= 1e-7 * abs(ref.normal_form_c)
        assert abs(f.tip_parabola_c - ref.tip_parabola_c) <= 1e-7 * abs(ref.tip_parabola_c)
        # the Hessians of the two energies at the fold: one eigenvalue zero, the next equal
        assert abs(f.hessian_smallest[0]) <= 1e-9
        assert abs(f.hessian_smallest[1] - ref.hessian_smallest[1]) <= 1e-9
    fast = jr.fold_pairs(np.array([G]), np.array([M]), np.array([D]), n=N)
    assert np.allclose(sorted(math.degrees(f.value) for f in generic), fast.alpha_deg[0],
                       rtol=0, atol=1e-9)


@pytest.mark.parametrize("inside, n", [(5e-4, 12), (1e-4, 16)])
def test_two_folds_within_one_step_near_the_cusp_are_found(inside, n):
    """Within 0.05% of the cusp in the track radius the two folds lie under 0.01 degrees
    apart, inside one continuation step: the branch traced at the default step mostly
    detects none (in both cases when written). ``folds`` sees the branch
    come near singular, traces it again with finer steps and finds both, agreeing with the
    fast path (one-mode brackets, then Moore-Spence on the paper's own energy) to 1e-9
    degrees."""
    # the paper's rig with its track radius inside the cusp's (0.1201910 m)
    G_c, M_c, D_c = jr.default_point().replace(
        "track-radius", 0.12019102566157 * (1.0 - inside)).groups()
    found = jr.folds(DipoleMagnet(G_c, M_c, D_c, 0.0).scene, "magnet.alpha", 0.0,
                     math.pi / 2, n=n)
    fast = jr.fold_pairs(np.array([G_c]), np.array([M_c]), np.array([D_c]), n=n)
    assert len(found) == 2 and bool(fast.bistable[0])
    assert fast.alpha_deg[0, 1] - fast.alpha_deg[0, 0] < 0.01
    assert np.allclose(sorted(math.degrees(f.value) for f in found), fast.alpha_deg[0],
                       rtol=0, atol=1e-9)


def test_a_new_term_runs_through_branch_folds_fold_curve_and_map():
    scene = spring_scene(0.05)
    b = jr.branch(scene, "magnet.alpha", 0.0, math.pi / 2, n=N)
    assert b.complete and b.vary == "magnet.alpha" and len(b.fold_indices) == 2
    folds = jr.folds(scene, "magnet.alpha", 0.0, math.pi / 2, n=N)
    assert len(folds) == 2 and all(f.converged for f in folds)
    # independent derivatives: Moore-Spence on the autodiff of the whole energy
    disc = planar_discretisation(N)
    model = _whole(Input("magnet.alpha"))
    for f in folds:
        args = (scene, disc, 0.0, 1.0)
        ref = moore_spence_solve(model, jnp.asarray(f.state), f.value,
                                 jnp.asarray(f.null_vector), args)
        assert bool(ref.newton.converged) and abs(float(ref.lam) - f.value) <= 1e-11
    # the spring holds the rod up: both folds move towards the vertical, continuously in k
    weak = jr.folds(spring_scene(1e-6), "magnet.alpha", 0.0, math.pi / 2, n=N)
    bare = jr.folds(paper_scene(), "magnet.alpha", 0.0, math.pi / 2, n=N)
    assert all(abs(a.value - b.value) <= 1e-5 for a, b in zip(weak, bare))
    assert folds[0].value < bare[0].value and folds[1].value < bare[1].value
    curve = jr.fold_curve(scene, "magnet.alpha", (0.0, math.pi / 2), "spring.k", (0.0, 0.3),
                          n=N)
    # each end refined onto the range of k it leaves: the fold of the scene at that k
    ends = sorted((p for p in curve.special_points if p.kind == "end"),
                  key=lambda p: p.along_value)
    assert [p.converged for p in ends] == [True, True]
    assert abs(ends[0].along_value) <= 1e-12 and abs(ends[1].along_value - 0.3) <= 1e-12
    assert curve.along_values.min() == ends[0].along_value
    at_end = jr.folds(spring_scene(0.3), "magnet.alpha", 0.0, math.pi / 2, n=N)[0].value
    assert abs(ends[1].value - at_end) <= 1e-10
    k = 0.2
    on_curve = np.interp(k, curve.along_values, curve.values)
    direct = jr.folds(spring_scene(k), "magnet.alpha", 0.0, math.pi / 2, n=N)[0].value
    assert abs(on_curve - direct) <= 1e-4
    fmap = jr.fold_map(scene, "magnet.alpha", (0.0, math.pi / 2),
                       ("spring.k", np.array([0.0, 0.2])), ("magnet.D", np.array([1.2, 1.3])),
                       n=N, progress=False)
    assert np.all(fmap.status == int(Status.SUCCESS))
    assert fmap.count[0, 0] == 2 and abs(fmap.first[0, 0] - bare[0].value) <= 1e-10
    assert abs(fmap.first[0, 1] - direct) <= 1e-10


def test_a_fold_curve_starts_from_a_fold_of_a_branch():
    """Codimension two from a special point: the curve from the branch's first fold (no
    branch traced again) is the curve from the first fold that ``folds`` finds; a fold at
    another N, or in another input, is refused by name."""
    scene, span = paper_scene(), (0.0, math.pi / 2)
    b = jr.branch(scene, "magnet.alpha", *span, n=N)
    fold = next(p for p in b.special_points if p.kind == "fold")
    given = jr.fold_curve(scene, "magnet.alpha", span, "magnet.D", (D, 1.25), n=N, start=fold)
    found = jr.fold_curve(scene, "magnet.alpha", span, "magnet.D", (D, 1.25), n=N)
    assert given.converged and abs(given.start.value - found.start.value) <= 1e-12
    np.testing.assert_allclose(given.values, found.values, rtol=0, atol=1e-11)
    np.testing.assert_allclose(given.along_values, found.along_values, rtol=0, atol=1e-11)
    other_n = jr.folds(scene, "magnet.alpha", *span, n=N + 2)[0]
    with pytest.raises(jr.ParameterError, match="start: .* same n"):
        jr.fold_curve(scene, "magnet.alpha", span, "magnet.D", (D, 1.25), n=N, start=other_n)
    with pytest.raises(jr.ParameterError, match="start: a fold in magnet.alpha"):
        jr.fold_curve(scene, "magnet.D", (1.1, 1.3), "gravity.G", (2.0, 2.5), n=N,
                      start=fold)


def test_the_equilibrium_is_the_one_reached_by_ramping_the_loads():
    at_zero = jr.equilibrium(paper_scene(), n=N)
    assert at_zero.status is Status.SUCCESS and abs(at_zero.tip_angle_deg) <= 1e-12
    assert at_zero.stable
    # a magnet at 60 degrees: the ramp pulls the rod away from the vertical, continuously
    e = jr.equilibrium(paper_scene(alpha=math.radians(60)), n=N)
    assert e.converged and e.stable and e.tip_angle_deg > 0
    again = jr.equilibrium(paper_scene(alpha=math.radians(60)), n=N, state=e.state)
    assert abs(again.tip_angle_deg - e.tip_angle_deg) <= 1e-12
    d = e.as_dict()
    assert set(d) >= {"tip_angle_deg", "tip_position", "stable", "converged"}


def test_bad_requests_are_named():
    with pytest.raises(jr.ParameterError, match="two different finite values"):
        jr.branch(paper_scene(), "magnet.alpha", 0.3, 0.3)
    with pytest.raises(SceneError, match="not an input"):
        jr.folds(paper_scene(), "magnet.angle", 0.0, 1.0)
    with pytest.raises(jr.ParameterError, match="fold"):
        jr.fold_curve(paper_scene(), "magnet.alpha", (0.0, 0.2), "magnet.D", (1.1, 1.3), n=N)
    with pytest.raises(ValueError, match="shape"):
        jr.equilibrium(paper_scene(), n=N, state=np.zeros(3))
    with pytest.raises(SolverError):
        from jaxrod.status import check

        check(int(Status.STEP_TOO_SMALL), throw=True)
    assert not Status.NOT_CONVERGED.ok and Status.REACHED_BOUND.ok
    assert all(s.message for s in Status)


def test_a_quasi_static_sweep_snaps_just_past_the_folds():
    """The magnet moved from 0 to 60 degrees and back on the paper's scene with a tip spring:
    the rod follows the magnet, lets go at the first value past the upper fold, and is
    captured at the first value past the lower fold on the way back."""
    scene = spring_scene(0.05)
    upper, lower = jr.folds(scene, "magnet.alpha", 0.0, math.pi / 2, n=N)
    up = np.radians(np.arange(0.0, 60.0 + 1e-9, 0.5))
    values = np.concatenate([up, up[::-1][1:]])
    s = jr.sweep(scene, "magnet.alpha", values, n=N, progress=False)
    assert s.complete and s.converged and s.snapped.sum() == 2
    release, capture = np.nonzero(s.snapped)[0]
    assert values[release - 1] < upper.value < values[release]
    assert values[capture] < lower.value < values[capture - 1] and capture > up.size
    # between the snaps the tip moves continuously, and jumps at them
    steps = np.abs(np.diff(s.tip_angle_deg))
    assert steps[release - 1] > 10 * np.max(np.delete(steps, [release - 1, capture - 1]))
    assert s.snaps[0]["tip_before_deg"] > s.snaps[0]["tip_after_deg"]


@pytest.mark.parametrize("top", [1.5, 1.45])
def test_the_generic_fold_curve_of_the_papers_scene_passes_its_cusp(top):
    """The generic fold curve (any scene, its inputs by name) of the paper's scene, followed
    in magnet.D, against the design point's fold curves (the same engine on another path
    and scaling, started elsewhere; their cusp is checked independently in
    test_fold_curves): its cusp bracket holds their refined cusp, and its points are folds
    of the paper's diagram (locate_folds, the hand-written energy) at their D. Up to
    D = 1.45 the cusp lies beyond both points around it in D: it is still refined and
    converged (it was once flagged not converged there)."""
    cusp = jr.fold_curves(jr.DesignPoint.from_groups(G, M, D), "D", 1.5, n=N)[0].cusps[0]
    curve = jr.fold_curve(paper_scene(), "magnet.alpha", (0.0, math.pi / 2), "magnet.D",
                          (D, top), n=N)
    (i,) = curve.cusp_indices
    # the folds merge where D is largest: no point of the curve lies beyond the cusp's D (D
    # and alpha are both stationary at the cusp: it need not lie within the range of either
    # over the two points around the sign change of F_qq)
    assert curve.along_values.max() <= cusp.along_value + 1e-12
    # refined, the generic cusp is the design point's (one regular cusp system on two paths,
    # each Newton to a residual of 1e-13: measured 3e-15 in D, 1e-13 deg)
    (refined,) = curve.cusps
    assert refined.converged and abs(refined.along_value - cusp.along_value) <= 1e-11
    assert abs(math.degrees(refined.value) - cusp.value) <= 1e-9
    assert refined.cubic_coefficient == pytest.approx(cusp.cubic_coefficient, rel=1e-8)
    for j in (0, i // 2, (i + len(curve.values)) // 2):  # both folds, away from the cusp
        at = jr.folds(jr.magnet_scene(G, M, float(curve.along_values[j])), n=N).folds
        assert min(abs(f.alpha_deg - math.degrees(curve.values[j])) for f in at) <= 1e-9
