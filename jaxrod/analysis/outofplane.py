"""Out-of-plane checks at planar equilibria of the permanent-magnet scene, computed in 3D
(paper, Lemma "Planar splitting of the full second variation", Proposition "Conditional
out-of-plane stability").

At a planar equilibrium theta the 3D Hessian H of the discrete energy on the director
discretisation (exponential chart, ``jaxrod.discretise.director``) is assembled by autodiff
and split into blocks [H11 H12; H21 H22] for the in-plane (v1) and out-of-plane (v2)
unknowns. Reported:

  coupling        max |H12| (zero by the splitting lemma; here by the e2 -> -e2 symmetry),
  min_eig_perp    smallest eigenvalue of the out-of-plane block as a form in b = sinc(theta)
                  dv2 (generalised eigenproblem with the mass matrix of int b^2),
  min_eig_perp_formula  the same from the paper's formula on the planar discretisation,
                  Q_perp[b] = int (b'^2 - lambda_theta b^2) + M d22Phi(X) (int b)^2,
                  lambda_theta = theta'^2 + G (1 - s) cos(theta) + M g . d_theta,
                  with b itself the polynomial unknown (an independent discretisation),
  min_eig_plane   smallest eigenvalue of the in-plane block (metric int a^2),
  theta_in_0_pi   0 < theta(s) < pi on (0, 1] (the paper's sign condition), and g_1 < 0.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from jaxrod.discretise.director import director_discretisation
from jaxrod.discretise.planar import PlanarDiscretisation
from jaxrod.scenes.dipole import DipoleMagnet, dipole_potential, magnet_direction
from jaxrod.scenes.three_d import DipoleMagnet3D, magnet_position


def _smallest_generalised(H, W):
    L = jnp.linalg.cholesky(W)
    solve_l = lambda b: jax.scipy.linalg.solve_triangular(L, b, lower=True)
    C = solve_l(solve_l(H).T).T
    return jnp.linalg.eigvalsh(0.5 * (C + C.T))[0]


def _sinc(x):
    small = jnp.abs(x) < 1e-4
    xs = jnp.where(small, 1.0, x)
    return jnp.where(small, 1.0 - x * x / 6.0, jnp.sin(xs) / xs)


def out_of_plane(theta, alpha, scene: DipoleMagnet, disc: PlanarDiscretisation) -> dict:
    """The checks at the planar equilibrium ``theta`` (free nodal values) at angle alpha."""
    ddisc = director_discretisation(disc.n, disc.support)
    scene3 = DipoleMagnet3D(scene.G, scene.M, scene.D, magnet_position(alpha))
    H = jax.hessian(scene3.energy)(ddisc.from_planar(theta), ddisc)
    m = disc.size
    H11, H12, H22 = H[:m, :m], H[:m, m:], H[m:, m:]
    P, w = disc.to_quad, disc.quad_weights
    th, dth = disc.at_quadrature(theta)
    W_b = P.T @ ((w * _sinc(th) ** 2)[:, None] * P)
    W_a = disc.mass_matrix()
    # the paper's formula, b the polynomial unknown
    X = jnp.stack([disc.integrate(jnp.sin(th)), disc.integrate(jnp.cos(th))])
    p = magnet_direction(alpha)
    g = jax.grad(dipole_potential)(X, p, scene.D)
    r = X - scene.D * p
    d22 = -3.0 * jnp.dot(p, r) / jnp.dot(r, r) ** 2.5
    lam = dth**2 + scene.G * (1.0 - disc.quad_nodes) * jnp.cos(th) \
        + scene.M * (g[0] * jnp.sin(th) + g[1] * jnp.cos(th))
    mean = w @ P
    K = disc.to_quad_diff.T @ (w[:, None] * disc.to_quad_diff)
    Q = K - P.T @ ((w * lam)[:, None] * P) + scene.M * d22 * jnp.outer(mean, mean)
    theta_full = disc.full_values(theta)
    return {
        "coupling": jnp.max(jnp.abs(H12)),
        "min_eig_perp": _smallest_generalised(H22, W_b),
        "min_eig_perp_formula": _smallest_generalised(Q, W_a),
        "min_eig_plane": _smallest_generalised(H11, W_a),
        "theta_in_0_pi": jnp.all((theta_full[1:] > 0.0) & (theta_full[1:] < jnp.pi)),
        "g1": g[0],
        "d22_phi": d22,
    }


out_of_plane_batch = jax.jit(jax.vmap(out_of_plane, in_axes=(0, 0, None, None)))
