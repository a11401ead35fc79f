"""Moore-Spence augmented system for a fold (saddle-node) of E(x, lam).

At a simple fold of the equilibria F(x, lam) = grad_x E = 0 the Hessian H = F_x has a one-
dimensional kernel span{phi}. The fold is a regular solution of the extended system
(Moore & Spence, SIAM J. Numer. Anal. 17 (1980) 567)

    F(x, lam) = 0,      H(x, lam) phi = 0,      l . phi - 1 = 0,

in 2m + 1 unknowns (x, phi, lam), l a fixed vector with l . phi != 0 (the null-vector
estimate from the branch). It is solved by ``jaxrod.solvers.newton`` with the exact Jacobian
assembled from the energy's derivatives (``jaxrod.derivatives``),

    [ H          0    F_lam         ]
    [ D^3E[phi]  H    (H phi)_lam   ]
    [ 0          l^T  0             ].

At the fold, with phi normalised to int phi = 1 (the paper's reduced coordinate q = int x),
the Lyapunov-Schmidt reduced function F(q, lam) of the paper has

    dF/dlam = phi . F_lam,      d2F/dq2 = D^3E[phi, phi, phi],

(the kernel direction is theta_q at the fold, which makes both independent of the chosen
complement), so the branch is lam(q) = lam* + c (q - q*)^2 + ..., c = -d2F/dq2 / (2 dF/dlam)
(Proposition "Planar saddle-node bifurcation").
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp

from jaxrod.derivatives import EnergyModel, FoldJet, as_model
from jaxrod.solvers import dense
from jaxrod.solvers.newton import NewtonResult, implicit_newton, newton

#: An ``EnergyModel`` (assembled derivatives) or a plain energy function E(x, lam, args).
Energy = EnergyModel | Callable[[jax.Array, jax.Array, Any], jax.Array]


class FoldPoint(NamedTuple):
    """A converged fold: state, parameter, null vector (int-normalised), diagnostics."""

    x: jax.Array
    lam: jax.Array
    null_vector: jax.Array
    newton: NewtonResult


def moore_spence_residual(z, data):
    """[grad E(x, lam); H(x, lam) phi; l . phi - 1] for z = (x, phi, lam), data =
    (energy, l, args)."""
    energy, ell, args = data
    model = as_model(energy)
    m = ell.shape[0]
    x, phi, lam = z[:m], z[m:2 * m], z[-1]
    F, Hphi = _directional_gradient(model, x, lam, args, phi)  # H phi without H
    return jnp.concatenate([F, Hphi, jnp.atleast_1d(ell @ phi - 1.0)])


def moore_spence_system(blocks: FoldJet, phi, ell):
    """(R, J): the Moore-Spence residual [F; H phi; l . phi - 1] and its Jacobian, laid out
    from the blocks of ``EnergyModel.fold_blocks`` at the null-vector estimate phi:

        [ H          0    F_lam        (F_u)       ]
        [ D^3E[phi]  H    (H phi)_lam  ((H phi)_u) ]
        [ 0          l^T  0            (0)         ],

    with the u column where the blocks carry a second parameter (the fold-curve system)."""
    H = blocks.H
    m = H.shape[0]
    columns = [(blocks.F_lam, blocks.Hphi_lam)]
    if blocks.F_u is not None:
        columns.append((blocks.F_u, blocks.Hphi_u))
    top = jnp.hstack([H, jnp.zeros_like(H), *[f[:, None] for f, _ in columns]])
    mid = jnp.hstack([blocks.third, H, *[h[:, None] for _, h in columns]])
    bottom = jnp.concatenate([jnp.zeros(m, H.dtype), ell,
                              jnp.zeros(len(columns), H.dtype)])[None, :]
    R = jnp.concatenate([blocks.F, H @ phi, jnp.atleast_1d(ell @ phi - 1.0)])
    return R, jnp.vstack([top, mid, bottom])


def moore_spence_linearisation(z, data):
    """(``moore_spence_residual``, its exact Jacobian in z) from one assembly of the
    Hessian's blocks (module docstring)."""
    energy, ell, args = data
    model = as_model(energy)
    m = ell.shape[0]
    x, phi, lam = z[:m], z[m:2 * m], z[-1]
    return moore_spence_system(model.fold_blocks(x, lam, args, phi), phi, ell)


class FoldBlocks(NamedTuple):
    """The Moore-Spence Jacobian at z = (x, phi, lam) kept in blocks: H, F_lam and
    (H phi)_lam (D^3E[phi] is applied to vectors when needed, never formed)."""

    H: jax.Array
    F_lam: jax.Array
    Hphi_lam: jax.Array
    z: jax.Array


def _directional_gradient(model, x, lam, args, v):
    """(grad E, H v) at (x, lam): one forward tangent of the gradient (no Hessian)."""
    return jax.jvp(lambda y: model.gradient(y, lam, args), (x,), (v,))


def moore_spence_blocks(z, data):
    """(``moore_spence_residual``, ``FoldBlocks``): the residual and the Jacobian's blocks
    from one Hessian assembly and forward tangents of the gradient (vectors only), for
    ``moore_spence_step``."""
    energy, ell, args = data
    model = as_model(energy)
    m = ell.shape[0]
    x, phi, lam = z[:m], z[m:2 * m], jnp.asarray(z[-1])
    F, H = model.gradient_and_hessian(x, lam, args)
    g_lam, Hphi_lam = jax.jvp(lambda l: _directional_gradient(model, x, l, args, phi), (lam,),
                              (jnp.ones_like(lam),))[1]
    R = jnp.concatenate([F, H @ phi, jnp.atleast_1d(ell @ phi - 1.0)])
    return R, FoldBlocks(H, g_lam, Hphi_lam, z)


def moore_spence_step(blocks: FoldBlocks, rhs, data):
    """The Moore-Spence Newton step J^-1 rhs by block elimination with the bordered matrix

        C = [ H    phi ]
            [ l^T  0   ],

    which stays regular at a simple fold (H's kernel is spanned by phi, and H is
    symmetric, so phi is not in its range), unlike H itself. With rhs = (r1, r2, r3) and
    sigma = l . dx, the first block row gives [dx; nu] = C^-1 [r1 - F_lam dlam; sigma] with
    the condition nu = 0, the second [dphi; mu] = C^-1 [r2 - D^3E[phi] dx - (H phi)_lam dlam;
    r3] with mu = 0: both are linear in (dlam, sigma), which a 2 x 2 system fixes. One LU
    of the (m + 1) matrix C, two triangular solves with three right-hand sides each, and
    D^3E[phi] applied to three vectors (second-order tangents of the gradient) replace the
    LU of the (2m + 1) Jacobian and the assembly of the m x m matrix D^3E[phi]; the step is
    the same to round-off."""
    energy, ell, args = data
    model = as_model(energy)
    H, g_lam, h_lam, z = blocks
    m = H.shape[0]
    x, phi, lam = z[:m], z[m:2 * m], z[-1]
    dtype = H.dtype
    C = jnp.block([[H, phi[:, None]], [ell[None, :], jnp.zeros((1, 1), dtype)]])
    lu = dense.lu_factor(C)
    r1, r2, r3 = rhs[:m], rhs[m:2 * m], rhs[-1]
    zero, one = jnp.zeros((), dtype), jnp.ones((), dtype)
    first = dense.lu_solve(lu, jnp.stack([
        jnp.append(r1, zero), jnp.append(-g_lam, zero),
        jnp.append(jnp.zeros_like(r1), one)], axis=1))
    u, nu = first[:m], first[m]

    def third(v):  # D^3E[phi] v = d/de H(x + e phi) v
        return jax.jvp(lambda y: _directional_gradient(model, y, lam, args, v)[1], (x,),
                       (phi,))[1]

    Tu = jax.vmap(third, in_axes=1, out_axes=1)(u)
    second = dense.lu_solve(lu, jnp.stack([
        jnp.append(r2 - Tu[:, 0], r3), jnp.append(-Tu[:, 1] - h_lam, zero),
        jnp.append(-Tu[:, 2], zero)], axis=1))
    p, mu = second[:m], second[m]
    # [nu1 nu2; mu1 mu2] (dlam, sigma) = -(nu0, mu0), by Cramer's rule
    det = nu[1] * mu[2] - nu[2] * mu[1]
    dlam = (-nu[0] * mu[2] + nu[2] * mu[0]) / det
    sigma = (-nu[1] * mu[0] + nu[0] * mu[1]) / det
    dx = u[:, 0] + dlam * u[:, 1] + sigma * u[:, 2]
    dphi = p[:, 0] + dlam * p[:, 1] + sigma * p[:, 2]
    return jnp.concatenate([dx, dphi, jnp.atleast_1d(dlam)])


def _solve_fold(energy, x0, lam0, phi0, args, tol):
    ell = phi0 / jnp.dot(phi0, phi0)
    z0 = jnp.concatenate([x0, phi0, jnp.atleast_1d(lam0)])
    res = newton(None, z0, (energy, ell, args), tol=tol, linearise=moore_spence_linearisation,
                 keep_jacobian=True)
    m = x0.shape[0]
    return FoldPoint(res.x[:m], res.x[-1], res.x[m:2 * m], res)


def moore_spence_solve(energy: Energy, x0, lam0, phi0, args, tol: float = 1e-13) -> FoldPoint:
    """Solve the Moore-Spence system from (x0, lam0) and null-vector guess phi0 (traceable).

    The returned ``null_vector`` is normalised by l . phi = 1 with l = phi0 / |phi0|^2;
    ``newton.jacobian`` is the system's Jacobian at the fold (``fold_coefficients``).
    """
    return _solve_fold(energy, x0, lam0, phi0, args, tol)



def differentiable_fold(energy: Energy, x0, lam0, phi0, args, tol: float = 1e-13):
    """(z, stats): the fold z = (x, phi, lam), differentiable in ``args``, and the Newton
    statistics (converged as 0/1, residual norm, iterations) as a float array.

    Implicit differentiation (``jaxrod.solvers.newton.implicit_newton``): the primal is the
    Newton solve of the Moore-Spence system R(z; args) = 0 from (x0, phi0, lam0), and the
    tangent is one dense solve with dR/dz at the solution, dz = -(dR/dz)^-1 (dR/dargs) dargs.
    """
    ell = jax.lax.stop_gradient(phi0 / jnp.dot(phi0, phi0))
    z0 = jnp.concatenate([x0, phi0, jnp.atleast_1d(lam0)])
    return implicit_newton(lambda z, p: moore_spence_residual(z, (energy, *p)), z0,
                           (ell, args), tol,
                           linearise=lambda z, p: moore_spence_linearisation(z, (energy, *p)))


def fold_coefficients(energy: Energy | None, x, lam, phi, args,
                      mean: Callable[[jax.Array], Any], jacobian=None):
    """(dF/dlam, d2F/dq2, phi normalised by mean(phi) = 1) at a converged fold: the reduced
    coefficients of its normal form F(q, lam) = dF/dlam (lam - lam*) + d2F/dq2 q^2 / 2
    projected on the null vector phi, dF/dlam = phi . dgradE/dlam and
    d2F/dq2 = D^3E[phi, phi, phi]. With the Moore-Spence ``jacobian`` at the fold (its blocks
    are F_lam and D^3E[phi], phi the null vector it was taken at) they are read off it, with
    no new assembly (``energy``, ``x``, ``lam`` and ``args`` then unused); else assembled."""
    m = phi.shape[0]
    scale = mean(phi)
    phi_q = phi / scale
    if jacobian is not None:
        d_lam = jnp.dot(jacobian[:m, 2 * m], phi_q)
        d3 = phi_q @ jacobian[m:2 * m, :m] @ phi_q / scale  # D^3E is linear in phi
        return d_lam, d3, phi_q
    model = as_model(energy)
    d_lam = jnp.dot(model.gradient_lam(x, lam, args), phi_q)
    return d_lam, phi_q @ model.third(x, lam, args, phi_q) @ phi_q, phi_q
