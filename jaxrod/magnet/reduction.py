"""The paper's Lyapunov-Schmidt reduction of the permanent-magnet scene: a second,
independent route to the folds.

Paper, Lemmas "Mode decomposition" and "Properties of the normalized mode": with
delta = D - 1, a0(s) = 2M/delta^3 - G (1 - s) and V = {v in H^1: v(0) = 0},

    B0(u, v) = int [u' v' + a0 u v] + (3M/delta^4) (int u)(int v),

the normalised mode psi = argmin {B0(phi, phi): phi in V, int phi = 1} solves the linear BVP

    -psi'' + a0 psi = lambda_psi,   psi(0) = 0,  psi'(1) = 0,  int psi = 1,
    lambda_psi = int (psi'^2 + a0 psi^2),

and mu_perp = inf {int v'^2 / int v^2 : v in Y} is the Poincare constant of the mean-zero
space Y = {v in V: int v = 0} (paper: 20.1907; exactly k^2 with tan k = k).

Every theta in V splits as theta = q psi + w, q = int theta, w in Y. Proposition
"Construction and error estimate for the mean-zero correction" fixes w(q, alpha) by

    dE_alpha[q psi + w](v) = 0   for every v in Y,                        (projected)

and Proposition "Scalar reduction" turns the planar equilibria into the zeros of

    F(q, alpha) = dE_alpha[q psi + w(q, alpha)](psi).                     (reduced)

F is the q-derivative of the reduced energy e(q, alpha) = E_alpha(q psi + w(q, alpha))
(dE[theta](d_q w) = 0 because d_q w lies in Y), so the reduced problem is a one-degree-of-
freedom energy. The folds solve F = dF/dq = 0, a 2 x 2
system that stays well conditioned at the fold (the w-problem is coercive on Y); its starting
point is the fold (q0, alpha0) of the one-mode function F0(q, alpha) = dE[q psi](psi) (w
dropped), itself located on the one-mode diagram.

Discretely (planar Chebyshev discretisation, free nodal values): psi from the KKT system of
the constrained quadratic minimisation; Y spanned by an orthonormal basis Z of the null space
of the mean functional m (m . v = int v); w = Z y with y from Newton on Z^T grad E = 0; its
derivatives in (q, alpha) by implicit differentiation (``implicit_newton``: one solve with
the coercive matrix Z^T H Z per tangent, Newton's iterations are never differentiated). The
fold system's derivatives of F come in closed form (``reduced_jet``).
"""

from __future__ import annotations

import dataclasses
import math

import jax
import jax.numpy as jnp
import numpy as np

from jaxrod.discretise.planar import PlanarDiscretisation, planar_discretisation
from jaxrod.equilibria.folds import Fold as SceneFold
from jaxrod.magnet.folds import PaperNames
from jaxrod.params import ParameterError
from jaxrod.programs import jit
from jaxrod.scenes.dipole import ALPHA_MODEL, DipoleMagnet, tip_angle, tip_position
from jaxrod.scenes.functionals import bending_energy
from jaxrod.solvers import dense
from jaxrod.solvers.continuation import ContinuationOptions, continuation_run
from jaxrod.solvers.eigen import smallest_generalised_eigenvalue
from jaxrod.solvers.newton import implicit_newton, newton
from jaxrod.status import Status
from jaxrod.stored import StoredProgram


def mean_functional(disc: PlanarDiscretisation) -> jax.Array:
    """Row vector m with m . v = int_0^1 v ds for free nodal values v."""
    return disc.quad_weights @ disc.to_quad


@jit
def stiffness_matrix(disc: PlanarDiscretisation) -> jax.Array:
    """Matrix of int u' v' (the Hessian of the bending energy): the Gram matrix of ||.||_Y."""
    return jax.hessian(bending_energy)(jnp.zeros(disc.size, disc.quad_weights.dtype), disc)


def mean_zero_basis(disc: PlanarDiscretisation) -> jax.Array:
    """Z (n, n - 1): orthonormal (Euclidean) basis of the discrete Y = {v : int v = 0}."""
    Q, _ = jnp.linalg.qr(mean_functional(disc)[:, None], mode="complete")
    return Q[:, 1:]


def poincare_mean_zero(disc: PlanarDiscretisation) -> jax.Array:
    """mu_perp: smallest int v'^2 / int v^2 over v(0) = 0, int v = 0 (clamped discretisation)."""
    Z = mean_zero_basis(disc)
    K = Z.T @ stiffness_matrix(disc) @ Z
    M = Z.T @ disc.mass_matrix() @ Z
    return smallest_generalised_eigenvalue(K, M)


def b0_matrix(G, M, D, disc: PlanarDiscretisation) -> jax.Array:
    """Matrix of the bilinear form B0 (the planar second variation at theta = 0, alpha = 0)."""
    delta = D - 1.0
    m = mean_functional(disc)
    a0 = 2.0 * M / delta**3 - G * (1.0 - disc.quad_nodes)
    P = disc.to_quad
    return stiffness_matrix(disc) + P.T @ ((disc.quad_weights * a0)[:, None] * P) \
        + (3.0 * M / delta**4) * jnp.outer(m, m)


def normalised_mode(G, M, D, disc: PlanarDiscretisation):
    """(psi, lambda_psi, ||psi||^2): the minimiser of B0 with int psi = 1.

    Solves the KKT system [B0 m^T; m 0] [psi; -mult] = [0; 1].
    """
    delta = D - 1.0
    m = mean_functional(disc)
    B = b0_matrix(G, M, D, disc)
    n = m.shape[0]
    kkt = jnp.block([[B, m[:, None]], [m[None, :], jnp.zeros((1, 1), B.dtype)]])
    psi = dense.solve(kkt, jnp.zeros(n + 1, B.dtype).at[-1].set(1.0))[:n]
    pq, dpq = disc.at_quadrature(psi)
    a0 = 2.0 * M / delta**3 - G * (1.0 - disc.quad_nodes)
    lam = disc.integrate(dpq**2 + a0 * pq**2)
    return psi, lam, disc.integrate(pq**2)


@jax.tree_util.register_dataclass
@dataclasses.dataclass(frozen=True)
class Reduction:
    """The fixed ingredients of the reduction for one scene (G, M, D) and discretisation.

    psi: nodal values of the normalised mode; Z: orthonormal basis of the mean-zero space;
    lambda_psi, psi_norm2 (= ||psi||_L2^2), mu_perp: the scalars of the paper's Lemma.
    """

    psi: jax.Array
    Z: jax.Array
    lambda_psi: jax.Array
    psi_norm2: jax.Array
    mu_perp: jax.Array


@jit
def reduction(scene: DipoleMagnet, disc: PlanarDiscretisation) -> Reduction:
    """Build the ``Reduction`` of a scene (traceable; differentiable in G, M, D).

    theta = q psi + w, int psi = 1, w mean-zero. Paper: Lemma ``lem:mode_decomposition``
    (eq. ``theta_mode_decomposition``), Lemma ``lem:mode_properties`` (eq. ``psi_BVP``).
    """
    psi, lam, norm2 = normalised_mode(scene.G, scene.M, scene.D, disc)
    return Reduction(psi, mean_zero_basis(disc), lam, norm2, poincare_mean_zero(disc))


def _energy(theta, alpha, scene: DipoleMagnet, disc: PlanarDiscretisation):
    return ALPHA_MODEL.energy(theta, alpha, (scene, disc))


def _gradient(theta, alpha, scene, disc):
    return ALPHA_MODEL.gradient(theta, alpha, (scene, disc))


def correction(q, alpha, red: Reduction, scene: DipoleMagnet, disc: PlanarDiscretisation,
               tol: float = 1e-13):
    """(w, stats): the mean-zero correction w(q, alpha) (nodal values) solving (projected),
    and the inner Newton's (converged as 0/1, residual norm, iterations) as floats.

    Newton from w = 0 on Z^T grad E(q psi + Z y) = 0; derivatives of w in q, alpha (and in
    the scene) by implicit differentiation (``implicit_newton``: one solve with the
    coercive matrix Z^T H Z per tangent).
    """
    def projected(y, p):
        q, alpha, red, scene, disc = p
        return red.Z.T @ _gradient(q * red.psi + red.Z @ y, alpha, scene, disc)

    def projected_linearisation(y, p):
        q, alpha, red, scene, disc = p
        H = ALPHA_MODEL.hessian(q * red.psi + red.Z @ y, alpha, (scene, disc))
        return projected(y, p), red.Z.T @ H @ red.Z

    y0 = jnp.zeros(red.Z.shape[1], dtype=red.psi.dtype)
    y, stats = implicit_newton(projected, y0, (q, alpha, red, scene, disc), tol,
                               linearise=projected_linearisation)
    return red.Z @ y, stats


def reduced_state(q, alpha, red, scene, disc):
    """theta = q psi + w(q, alpha) and the inner-solve statistics."""
    w, stats = correction(q, alpha, red, scene, disc)
    return q * red.psi + w, stats


def reduced_function(q, alpha, red: Reduction, scene: DipoleMagnet,
                     disc: PlanarDiscretisation):
    """F(q, alpha) = dE_alpha[q psi + w(q, alpha)](psi) (paper, eq. reduced_equation)."""
    theta, _ = reduced_state(q, alpha, red, scene, disc)
    return jnp.dot(_gradient(theta, alpha, scene, disc), red.psi)


def _jet(theta, xi, theta_alpha, alpha, red: Reduction, scene, disc):
    """(F, dF/dq, dF/dalpha, d2F/dq2, d2F/dq dalpha) at theta = theta(q, alpha), given its
    q- and alpha-derivatives xi and theta_alpha with Z^T H xi = 0 (xi - psi in Y):

        F = psi . g,   F_q = xi^T H xi,   F_alpha = psi . (H theta_alpha + g_alpha),
        F_qq = D^3E[xi, xi, xi],   F_q alpha = D^3E[xi, xi, theta_alpha] + xi . (H xi)_alpha,

    with g = grad E, H = Hess E. The terms with d_q xi and d_alpha xi drop out because they
    lie in Y and H xi is orthogonal to Y (one assembly of the Hessian, two tangents of it)."""
    args = (scene, disc)
    b = ALPHA_MODEL.fold_blocks(theta, alpha, args, xi)
    Txi = b.third @ xi
    return jnp.stack([jnp.dot(red.psi, b.F), xi @ b.H @ xi,
                      jnp.dot(red.psi, b.H @ theta_alpha + b.F_lam), jnp.dot(Txi, xi),
                      jnp.dot(Txi, theta_alpha) + jnp.dot(xi, b.Hphi_lam)])


def _state_derivatives(theta, alpha, red: Reduction, scene, disc):
    """(xi, theta_alpha) = (d theta/dq, d theta/dalpha) on the w-manifold Z^T g = 0:
    xi = psi - Z A^-1 Z^T H psi and theta_alpha = -Z A^-1 Z^T g_alpha, A = Z^T H Z
    (coercive on Y, so a Cholesky solve)."""
    H, g_alpha = ALPHA_MODEL.hessian_and_gradient_lam(theta, alpha, (scene, disc))
    Z = red.Z
    factor = jax.scipy.linalg.cho_factor(Z.T @ H @ Z)
    y = jax.scipy.linalg.cho_solve(factor, Z.T @ jnp.stack([H @ red.psi, g_alpha], axis=1))
    dtheta = -Z @ y
    return red.psi + dtheta[:, 0], dtheta[:, 1]


def reduced_jet(q, alpha, red: Reduction, scene, disc):
    """(F, dF/dq, dF/dalpha, d2F/dq2, d2F/dq dalpha) at (q, alpha), in closed form from the
    energy's assembled derivatives at theta = q psi + w(q, alpha) (``_jet``), theta, the
    inner w-solve's statistics, and xi = psi + dw/dq (the Hessian's kernel at a fold)."""
    theta, stats = reduced_state(q, alpha, red, scene, disc)
    xi, theta_alpha = _state_derivatives(theta, alpha, red, scene, disc)
    return _jet(theta, xi, theta_alpha, alpha, red, scene, disc), theta, stats, xi


def one_mode_jet(q, alpha, red: Reduction, scene, disc):
    """(F0, dF0/dq, dF0/dalpha, d2F0/dq2, d2F0/dq dalpha) of the one-mode function
    F0(q, alpha) = dE[q psi](psi): ``_jet`` with xi = psi, theta_alpha = 0."""
    return _jet(q * red.psi, red.psi, jnp.zeros_like(red.psi), alpha, red, scene, disc)


JET_NAMES = ("F", "dF_dq", "dF_dalpha", "d2F_dq2", "d2F_dq_dalpha")


def reduced_energy(x, alpha, args):
    """e(q, alpha) = E_alpha(q psi + w(q, alpha)) with x = [q]; args = (red, scene, disc).
    Its q-derivative is F: a one-unknown energy for the generic continuation."""
    red, scene, disc = args
    theta, _ = reduced_state(x[0], alpha, red, scene, disc)
    return _energy(theta, alpha, scene, disc)


def one_mode_energy(x, alpha, args):
    """e0(q, alpha) = E_alpha(q psi) with x = [q]; its q-derivative is F0."""
    red, scene, disc = args
    return _energy(x[0] * red.psi, alpha, scene, disc)


def one_mode_function(q, alpha, red: Reduction, scene, disc):
    """F0(q, alpha) = dE_alpha[q psi](psi): the reduced function with w dropped."""
    return jnp.dot(_gradient(q * red.psi, alpha, scene, disc), red.psi)


def _fold_newton(jet, x0, args, tol):
    """Newton on (F, dF/dq)(q, alpha) = 0 from x0 = (q, alpha), with the exact Jacobian
    [[F_q, F_alpha], [F_qq, F_q alpha]] from the same closed-form jet."""
    def linearise(x, a):
        d = jet(x[0], x[1], *a)[0]
        return d[:2], d[jnp.array([[1, 2], [3, 4]])]

    return newton(None, x0, args, tol=tol, linearise=linearise)


def one_mode_fold(red, scene, disc, q_guess, alpha_guess, tol: float = 1e-14):
    """Newton on F0 = dF0/dq = 0: the paper's initial approximation (q0, alpha0) of a fold."""
    jet = lambda q, a, *args: (one_mode_jet(q, a, *args),)
    return _fold_newton(jet, jnp.stack([q_guess, alpha_guess]), (red, scene, disc), tol)


def reduced_fold(red, scene, disc, q_guess, alpha_guess, tol: float = 1e-13):
    """Newton on F = dF/dq = 0 (the paper's 2 x 2 fold system) from (q_guess, alpha_guess)."""
    return _fold_newton(reduced_jet, jnp.stack([q_guess, alpha_guess]), (red, scene, disc),
                        tol)


#: Capacity of the one-mode continuation that brackets the folds (one unknown: cheap).
ONE_MODE_CAPACITY = 256


def _one_mode_guesses(red, scene, disc):
    """(q, alpha) at the first two folds of the one-mode diagram for alpha > 0, and whether
    two were found: continuation of e0 from the straight rod, stopped after the second fold."""
    options = ContinuationOptions(ds=0.02, ds_min=1e-9, ds_max=0.05, lam_min=-0.1,
                                  lam_max=math.pi / 2, tol=1e-13, max_folds=2.0)
    raw = continuation_run(one_mode_energy, jnp.zeros(1), 0.0, (red, scene, disc), options,
                           ONE_MODE_CAPACITY, 1.0)
    t = raw.tangent_lam
    change = t[:-1] * t[1:] < 0.0
    i = jnp.nonzero(change, size=2, fill_value=0)[0]
    j = jnp.where(jnp.abs(t[i]) <= jnp.abs(t[i + 1]), i, i + 1)
    return raw.x[j, 0], raw.lam[j], jnp.sum(change) >= 2


def _reduced_fold_pair(scene: DipoleMagnet, disc: PlanarDiscretisation, tol):
    red = reduction(scene, disc)
    q_start, a_start, found = _one_mode_guesses(red, scene, disc)
    one = jax.vmap(lambda q, a: one_mode_fold(red, scene, disc, q, a))(q_start, a_start)
    full = jax.vmap(lambda x: reduced_fold(red, scene, disc, x[0], x[1], tol))(one.x)

    def report(x):
        jet, theta, stats, xi = reduced_jet(x[0], x[1], red, scene, disc)
        return (dict(zip(JET_NAMES, jet)), tip_angle(theta, disc), stats, theta, xi,
                tip_position(theta, disc))

    derivs, tip, inner, theta, xi, X = jax.vmap(report)(full.x)
    return found, one, full, derivs, tip, inner, theta, xi, X, red


_reduced_fold_pair_jit = StoredProgram("reduced-fold-pair", _reduced_fold_pair)


@dataclasses.dataclass(frozen=True)
class ReducedFold(PaperNames, SceneFold):
    """A fold from the reduced route: the fold record of every scene
    (``jaxrod.equilibria.folds.Fold``: ``vary`` = "magnet.alpha", ``value`` alpha* in radians,
    ``state`` theta = q* psi + w, ``null_vector`` xi = psi + dw/dq (int xi = 1), the normal
    form from F's derivatives) with the paper's names (``PaperNames``), the one-mode start
    (q0, alpha0), the other derivatives of F there and the inner w-solve's diagnostics."""

    q0: float
    alpha0_deg: float
    dF_dq: float
    d2F_dq_dalpha: float
    one_mode_converged: bool
    correction_converged: bool
    correction_residual: float
    kind: str = dataclasses.field(default="fold", kw_only=True)  # the paper's: lower, upper

    @property
    def opens(self) -> str:
        return "increasing alpha" if self.normal_form_c > 0 else "decreasing alpha"

    def as_dict(self) -> dict:
        return {"kind": self.kind, "q0": self.q0, "alpha0_deg": self.alpha0_deg, "q": self.q,
                "alpha_deg": self.alpha_deg, "tip_deg": self.tip_deg, "dF_dq": self.dF_dq,
                "dF_dalpha": self.dF_dalpha, "d2F_dq2": self.d2F_dq2,
                "d2F_dq_dalpha": self.d2F_dq_dalpha, "converged": self.converged,
                "residual_norm": self.residual_norm, "iterations": self.iterations,
                "one_mode_converged": self.one_mode_converged,
                "correction_converged": self.correction_converged,
                "correction_residual": self.correction_residual,
                "dF_dalpha_sign": int(np.sign(self.dF_dalpha)),
                "d2F_dq2_sign": int(np.sign(self.d2F_dq2)), "opens": self.opens}


def check_reducible(scene: DipoleMagnet) -> None:
    """Refuse scenes where B0 is not coercive (2M/delta^3 <= G): psi is then undefined."""
    delta = float(scene.D) - 1.0
    if not 2.0 * float(scene.M) / delta**3 > float(scene.G):
        raise ParameterError(
            f"M: the reduced route needs 2M/delta^3 > G (the mode decomposition), got "
            f"2M/delta^3 = {2.0 * float(scene.M) / delta**3:.6g} <= G = {float(scene.G):.6g}; "
            "use --method moore-spence")


def reduced_folds(scene: DipoleMagnet, n: int = 16, tol: float = 1e-13) -> list[ReducedFold]:
    """The folds with alpha > 0 by the reduced route (lower first; [] if the one-mode diagram
    has no pair of folds). Independent of the full-space continuation and Moore-Spence.
    Raises ``ParameterError`` when 2M/delta^3 <= G (no mode decomposition).

    A fold of the reduced equation F(q, alpha) = 0 solves F = dF/dq = 0. Paper: Proposition
    ``prop:scalar_reduction`` (eq. ``reduced_equation``), Proposition ``thm:planar_fold``.
    """
    check_reducible(scene)
    disc = planar_discretisation(n, "clamped")
    found, one, full, derivs, tip, inner, theta, xi, X, _ = _reduced_fold_pair_jit(scene, disc,
                                                                                   tol)
    if not bool(found):
        return []
    folds = []
    for i in range(2):
        d = {k: float(v[i]) for k, v in derivs.items()}
        converged = bool(full.converged[i]) and bool(inner[i, 0] == 1.0)
        folds.append(ReducedFold(
            vary="magnet.alpha", value=float(full.x[i, 1]),
            tip_angle_deg=math.degrees(float(tip[i])),
            tip_position=np.array([X[i, 0], 0.0, X[i, 1]]),
            state=np.asarray(theta[i]), null_vector=np.asarray(xi[i]), converged=converged,
            residual_norm=float(full.residual_norm[i]), iterations=int(full.iterations[i]),
            status=Status.of(converged), q=float(full.x[i, 0]), dF_dvalue=d["dF_dalpha"],
            d2F_dq2=d["d2F_dq2"], normal_form_c=-d["d2F_dq2"] / (2.0 * d["dF_dalpha"]),
            kind="", q0=float(one.x[i, 0]), alpha0_deg=math.degrees(float(one.x[i, 1])),
            dF_dq=d["dF_dq"], d2F_dq_dalpha=d["d2F_dq_dalpha"],
            one_mode_converged=bool(one.converged[i]),
            correction_converged=bool(inner[i, 0] == 1.0),
            correction_residual=float(inner[i, 1])))
    folds.sort(key=lambda f: f.alpha_deg)
    return [dataclasses.replace(f, kind=k) for f, k in zip(folds, ("lower", "upper"))]


@jit
def second_variation_checks(q, alpha, red: Reduction, scene: DipoleMagnet,
                            disc: PlanarDiscretisation) -> dict:
    """Numerical checks of the paper's Lemma "Planar stability criterion" at (q, alpha).

    Q_pl is the Hessian H of the discrete energy at theta = q psi + w(q, alpha) and
    xi = psi + d_q w. Returns a dict:

    - coercivity: min over v in Y of Q_pl(v, v) / ||v||_Y^2 (to compare with 1 - K),
    - dF_dq, Q_xi_xi: dF/dq and Q_pl(xi, xi) (equal by eq. partialqF_second_variation),
    - xi_orthogonality: max_j |Q_pl(xi, z_j)| / ||z_j||_Y over the basis z_j of Y (zero by
      eq. xi_Y_orthogonality),
    - xi_mean: int xi (= 1).
    """
    theta, _ = reduced_state(q, alpha, red, scene, disc)
    H = ALPHA_MODEL.hessian(theta, alpha, (scene, disc))
    xi = red.psi + jax.jacfwd(lambda t: correction(t, alpha, red, scene, disc)[0])(q)
    Z = red.Z
    KY = Z.T @ stiffness_matrix(disc) @ Z
    coercivity = smallest_generalised_eigenvalue(Z.T @ H @ Z, KY)
    F_q = jax.grad(lambda t: reduced_function(t, alpha, red, scene, disc))(q)
    cross = (Z.T @ (H @ xi)) / jnp.sqrt(jnp.diag(KY))
    return {"coercivity": coercivity, "dF_dq": F_q, "Q_xi_xi": xi @ H @ xi,
            "xi_orthogonality": jnp.max(jnp.abs(cross)), "xi_mean": disc.mean(xi)}
