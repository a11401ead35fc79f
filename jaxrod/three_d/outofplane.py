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
from jaxrod.solvers.eigen import smallest_generalised_eigenvalue
from jaxrod.stored import StoredProgram


def _sinc(x):
    small = jnp.abs(x) < 1e-4
    xs = jnp.where(small, 1.0, x)
    return jnp.where(small, 1.0 - x * x / 6.0, jnp.sin(xs) / xs)


def out_of_plane(theta, alpha, scene: DipoleMagnet, disc: PlanarDiscretisation) -> dict:
    """The checks at the planar equilibrium ``theta`` (free nodal values) at angle alpha.

    The full second variation splits into the planar form and Q_perp[v2] = int [v2'^2 +
    lambda_theta v2^2] + nonlocal terms. Paper: Lemma ``prop:second_variation_splitting``
    (eq. ``Qperp_def``), Proposition ``thm:conditional_out_of_plane_stability`` (eq.
    ``out_of_plane_sign_conditions``).
    """
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
        "min_eig_perp": smallest_generalised_eigenvalue(H22, W_b),
        "min_eig_perp_formula": smallest_generalised_eigenvalue(Q, W_a),
        "min_eig_plane": smallest_generalised_eigenvalue(H11, W_a),
        "theta_in_0_pi": jnp.all((theta_full[1:] > 0.0) & (theta_full[1:] < jnp.pi)),
        "g1": g[0],
        "d22_phi": d22,
    }


def _out_of_plane_rows(theta, alpha, scene: DipoleMagnet, disc: PlanarDiscretisation) -> dict:
    """``out_of_plane`` at each row of theta and alpha."""
    return jax.vmap(out_of_plane, in_axes=(0, 0, None, None))(theta, alpha, scene, disc)


out_of_plane_batch = StoredProgram("out-of-plane", _out_of_plane_rows)


def out_of_plane_at_rows(theta, alpha, scene: DipoleMagnet, disc: PlanarDiscretisation) -> dict:
    """``out_of_plane_batch`` on rows padded (with the last row) to a power of two, so that
    branches of other lengths reuse the compiled program; the padding is dropped again."""
    import numpy as np

    k = theta.shape[0]
    size = 1 << max(k - 1, 0).bit_length()
    pad = lambda v: np.concatenate([v, np.repeat(v[-1:], size - k, axis=0)])
    rows = out_of_plane_batch(pad(np.asarray(theta)), pad(np.asarray(alpha)), scene, disc)
    return {key: np.asarray(v)[:k] for key, v in rows.items()}


def branch_verdict(scene: DipoleMagnet, branch, folds=(), n: int | None = None) -> dict:
    """Out-of-plane verdict for a traced planar diagram (``jaxrod.equilibria.record.Branch``):
    the smallest out-of-plane eigenvalue over its planar-stable points with |alpha| <= 90
    degrees (where it is
    attained), the largest in/out-of-plane coupling, the agreement of the 3D Hessian with the
    paper's formula, the sign conditions on the engaged branch (from alpha = 0 to the upper
    fold), and at each fold (``Fold`` objects) whether the smallest 3D eigenvalue is in-plane.
    ``stable_out_of_plane`` is True when Q_perp > 0 at every planar-stable point."""
    import numpy as np

    from jaxrod.discretise.planar import planar_discretisation

    disc = planar_discretisation(n or branch.theta.shape[1], "clamped")
    r = out_of_plane_at_rows(branch.theta, branch.alpha, scene, disc)
    stable = branch.stable & (np.abs(branch.alpha) <= np.pi / 2)  # the track's range
    i = int(np.argmin(np.where(stable, r["min_eig_perp"], np.inf)))
    e = branch.engaged
    engaged = slice(e.start + 1, e.stop)  # theta = 0 at the straight rod itself
    fold_rows = []
    if folds:
        c = out_of_plane_at_rows(np.stack([f.theta for f in folds]),
                                 np.radians([f.alpha_deg for f in folds]), scene, disc)
        for i, f in enumerate(folds):
            plane, perp = float(c["min_eig_plane"][i]), float(c["min_eig_perp"][i])
            fold_rows.append({"kind": f.kind, "alpha_deg": f.alpha_deg, "min_eig_plane": plane,
                              "min_eig_perp": perp, "smallest_is_in_plane": abs(plane) < perp})
    rel = np.abs(r["min_eig_perp"] - r["min_eig_perp_formula"]) / np.abs(r["min_eig_perp"])
    return {
        "min_eig_perp_on_stable": float(r["min_eig_perp"][i]),
        "at_alpha_deg": float(np.degrees(branch.alpha[i])),
        "max_coupling": float(r["coupling"].max()),
        "max_rel_diff_formula": float(rel.max()),
        "engaged_theta_in_0_pi": bool(r["theta_in_0_pi"][engaged].all()),
        "engaged_g1_negative": bool((r["g1"][engaged] < 0).all()),
        "folds": fold_rows,
        "stable_out_of_plane": bool(r["min_eig_perp"][i] > 0.0),
        "points": int(len(branch.alpha)),
    }
