"""Assembled derivatives (``jaxrod.derivatives.Structured``) against plain autodiff of each
scene's whole energy (``scene.energy``, built from the energy terms): energy, gradient,
Hessian, D^3E[phi], and the parameter derivatives, to round-off."""


import dataclasses

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxrod.derivatives import Autodiff, Structured
from jaxrod.discretise.director import director_discretisation
from jaxrod.discretise.planar import planar_discretisation
from jaxrod.programs import jit
from jaxrod.scenes import DipoleMagnet, UniformField
from jaxrod.scenes.dipole import ALPHA_MODEL
from jaxrod.scenes.three_d import DipoleMagnet3D, UniformField3D, magnet_position
from jaxrod.solvers.fold_curve import fold_linearisation
from jaxrod.solvers.folds import moore_spence_linearisation, moore_spence_residual

D_EXP = 11.25 / 9.2


def _uniform_at(A, args):
    G, disc = args
    return UniformField(G, A), disc


def _uniform3_at(A, args):
    G, disc = args
    return UniformField3D(G, A), disc


def _magnet3_at(alpha, args):
    disc, = args
    return DipoleMagnet3D(2.2, 0.0236, D_EXP, magnet_position(alpha, 0.3)), disc


def _magnet_energy(x, alpha, args):
    scene, disc = args
    return scene.with_alpha(alpha).energy(x, disc)


_REFERENCES = {}


def _reference(scene_at):
    """Autodiff of ``scene.energy`` (one object per scene_at, so the jit cache is reused)."""
    if scene_at in _REFERENCES:
        return _REFERENCES[scene_at]
    def energy(x, lam, args):
        scene, disc = scene_at(lam, args)
        return scene.energy(x, disc)
    _REFERENCES[scene_at] = Autodiff(energy)
    return _REFERENCES[scene_at]


CASES = {
    "magnet planar": (ALPHA_MODEL, (DipoleMagnet(2.2, 0.0236, D_EXP, 0.0),
                                    planar_discretisation(12)), 0.6),
    "uniform clamped": (Structured(_uniform_at), (10.0, planar_discretisation(16)), 3.0),
    "uniform pinned": (Structured(_uniform_at), (10.0, planar_discretisation(16, "pinned")), 3.0),
    "uniform 3D": (Structured(_uniform3_at), (5.0, director_discretisation(10)), 2.0),
    "magnet 3D": (Structured(_magnet3_at), (director_discretisation(10),), 0.5),
}


def _state(size, scale, shift=0.0):
    return scale * jnp.sin(1.3 * jnp.arange(size) + shift)


def _relative(a, b):
    return float(jnp.max(jnp.abs(a - b)) / (1.0 + jnp.max(jnp.abs(b))))


@jit(static_argnums=(0, 1))  # compiled as jaxrod's own programs are (jaxrod.programs)
def _both(model, reference, x, phi, lam, args):
    """Each quantity assembled and by plain autodiff of the whole energy, in one program."""
    E = reference.fn
    hess = lambda z, l: jax.hessian(E)(z, l, args)
    F, H, g_lam, T, Hphi_lam, _, _ = model.fold_blocks(x, lam, args, phi)
    F_lin, H_lin, g_lam_lin = model.linearisation(x, lam, args)
    return {
        "energy": (model.energy(x, lam, args), E(x, lam, args)),
        "gradient": (model.gradient(x, lam, args), jax.grad(E)(x, lam, args)),
        "hessian": (model.hessian(x, lam, args), hess(x, lam)),
        "third": (model.third(x, lam, args, phi), jax.jacfwd(lambda z: hess(z, lam) @ phi)(x)),
        "fold gradient": (F, jax.grad(E)(x, lam, args)),
        "fold hessian": (H, hess(x, lam)),
        "linearisation gradient": (F_lin, jax.grad(E)(x, lam, args)),
        "linearisation hessian": (H_lin, hess(x, lam)),
        "linearisation gradient_lam": (g_lam_lin, jax.jacfwd(jax.grad(E), 1)(x, lam, args)),
        "fold third": (T, jax.jacfwd(lambda z: hess(z, lam) @ phi)(x)),
        "gradient_lam": (g_lam, jax.jacfwd(jax.grad(E), 1)(x, lam, args)),
        "hessian_vector_lam": (Hphi_lam, jax.jacfwd(lambda l: hess(x, l) @ phi)(lam)),
    }


@pytest.mark.parametrize("name", CASES)
def test_assembled_derivatives_match_autodiff(name):
    model, args, lam = CASES[name]
    if name == "magnet planar":
        reference = Autodiff(_magnet_energy)
    else:
        reference = _reference(model.scene_at)
    size = args[-1].size
    phi = _state(size, 1.0, 0.4)
    for scale in (0.0, 0.3):
        out = _both(model, reference, _state(size, scale), phi, jnp.asarray(lam), args)
        for quantity, (assembled, autodiff) in out.items():
            error = _relative(assembled, autodiff)
            assert error < (1e-12 if "third" in quantity else 1e-13), (quantity, scale, error)


def test_moore_spence_linearisation_is_the_residual_and_its_jacobian():
    model, args, lam = CASES["magnet planar"]
    m = args[1].size
    z = jnp.concatenate([_state(m, 0.3), _state(m, 1.0, 0.4), jnp.array([lam])])
    data = (model, _state(m, 1.0, 0.9), args)
    plain = (Autodiff(_magnet_energy), data[1], args)
    both = jit(lambda z, ell, args: (
        moore_spence_linearisation(z, (model, ell, args)),
        (moore_spence_residual(z, plain), jax.jacfwd(moore_spence_residual)(z, plain))))
    (R, J), (R_ref, J_ref) = both(z, data[1], args)
    np.testing.assert_allclose(R, R_ref, atol=1e-13)
    np.testing.assert_allclose(J, J_ref, atol=1e-12)


def _with_D(D, args):
    """The dipole scene with its clearance D as the second parameter of a fold curve."""
    scene, disc = args
    return dataclasses.replace(scene, D=D), disc


def test_fold_curve_jacobian_is_the_residual_and_its_jacobian_in_both_parameters():
    """The fold-curve system's Jacobian (one assembly, with the second parameter's column)
    against forward-mode autodiff of the plain Moore-Spence residual in (x, phi, lam, u)."""
    model, args, lam = CASES["magnet planar"]
    m = args[1].size
    w = jnp.concatenate([_state(m, 0.3), _state(m, 1.0, 0.4), jnp.array([lam, 1.15])])
    ell = _state(m, 1.0, 0.9)

    def plain(w):
        return moore_spence_residual(w[:-1], (Autodiff(_magnet_energy), ell,
                                              _with_D(w[-1], args)))

    both = jit(lambda w, ell, args: (fold_linearisation(w, ell, model, _with_D, args),
                                     (plain(w), jax.jacfwd(plain)(w))))
    (R, J), (R_ref, J_ref) = both(w, ell, args)
    assert J.shape == (2 * m + 1, 2 * m + 2)
    np.testing.assert_allclose(R, R_ref, atol=1e-13)
    np.testing.assert_allclose(J, J_ref, atol=1e-12)


def test_fold_coefficients_from_the_moore_spence_jacobian():
    """dF/dlam and d2F/dq2 read off the Jacobian Newton ends with (no new assembly) equal
    those assembled afresh at the fold (D^3E[phi] by a tangent of the Hessian)."""
    from jaxrod.magnet.diagram import trace_diagram
    from jaxrod.solvers.folds import fold_coefficients, moore_spence_solve

    model, args, _ = CASES["magnet planar"]
    disc = args[1]
    # a start near the paper's upper fold (alpha ~ 39.3 deg), from the diagram
    branch = trace_diagram(args[0], n=disc.n)
    i = int(branch.fold_indices[-1])
    H = model.hessian(jnp.asarray(branch.theta[i]), branch.alpha[i], args)
    fp = jax.jit(lambda x, a, p: moore_spence_solve(model, x, a, p, args))(
        jnp.asarray(branch.theta[i]), branch.alpha[i], jnp.linalg.eigh(H)[1][:, 0])
    assert bool(fp.newton.converged)
    from_jacobian = fold_coefficients(None, fp.x, fp.lam, fp.null_vector, args, disc.mean,
                                      jacobian=fp.newton.jacobian)
    assembled = fold_coefficients(model, fp.x, fp.lam, fp.null_vector, args, disc.mean)
    for a, b in zip(from_jacobian, assembled):
        np.testing.assert_allclose(a, b, rtol=1e-10, atol=1e-12)


@pytest.mark.parametrize("where", ["away from the fold", "at the fold"])
def test_bordered_moore_spence_step_is_the_newton_step(where):
    """The block-eliminated step (bordered matrix [H phi; l^T 0], D^3E[phi] applied to
    vectors) equals the dense solve with the assembled Moore-Spence Jacobian, also at the
    fold, where H itself is singular."""
    from jaxrod.magnet.batch import fold_pair_states
    from jaxrod.solvers.folds import moore_spence_blocks, moore_spence_step

    model, args, lam = CASES["magnet planar"]
    scene, disc = args
    m = disc.size
    if where == "at the fold":
        z = fold_pair_states(scene.G, scene.M, scene.D, disc)[0][1]
        rhs = _state(2 * m + 1, 1.0, 0.7)  # any right-hand side
    else:
        z = jnp.concatenate([_state(m, 0.3), _state(m, 1.0, 0.4), jnp.array([lam])])
        rhs = None
    ell = z[m:2 * m] / jnp.dot(z[m:2 * m], z[m:2 * m])

    def steps(z, ell, rhs):
        data = (model, ell, args)
        R, J = moore_spence_linearisation(z, data)
        R2, blocks = moore_spence_blocks(z, data)
        b = -R if rhs is None else rhs
        return R, R2, jnp.linalg.solve(J, b), moore_spence_step(blocks, b, data), J

    R, R2, dense_step, bordered_step, J = jit(steps)(z, ell, rhs)
    if where == "at the fold":  # H is singular there: the bordered matrix is not
        H = J[:m, :m]
        assert np.linalg.cond(np.asarray(H)) > 1e8
    np.testing.assert_allclose(R2, R, atol=1e-12)
    scale = float(jnp.max(jnp.abs(dense_step)))
    np.testing.assert_allclose(bordered_step, dense_step, atol=1e-10 * scale)
