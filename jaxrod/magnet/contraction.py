"""The computable constants of the paper's contraction argument for w(q, alpha), and which
hypotheses of its Propositions hold (paper, proof of Proposition "Construction and error
estimate for the mean-zero correction", and Theorem "Physical consequences of Permanent
Magnet Regime").

At (q, alpha), with the one-mode director d_q = sin(q psi) e1 + cos(q psi) e3, its normal
n_q = cos(q psi) e1 - sin(q psi) e3, X_q = int d_q, g = grad Phi_alpha(X_q):

    rho    = G (1 - s)(q psi - sin(q psi)) + M g . n_q - (2M/delta^3) q psi
    eta    = ||rho||_{Y*}                                  (dual of ||v||_Y = ||v'||_L2)
    S      = |q| sqrt(||psi||^2 - 1) + 2 eta / sqrt(mu_perp)
    E      = (2 eta / sqrt(mu_perp)) (|q| sqrt(||psi||^2 - 1) + eta / sqrt(mu_perp))
    Delta  = |X_q - D p(alpha)| - E
    H      = || G (1 - s)(1 - cos(q psi)) - M g . d_q - 2M/delta^3 ||_Linf
    K      = (1/mu_perp) [H + 2 (G + M |g|) eta + (6M / Delta^4)(E + S^2)]
    eps    = eta / (1 - K)       (the bound on ||w||_Y and ||w||_Linf; inf unless K < 1/2)

Hypotheses: Delta > 0 and K < 1/2 at (q, alpha) (the correction exists, is unique and
smooth); 2M/delta^3 > G and beta0^cl(G) > sqrt(6) M / (9 delta^3) (scene-wide: the mode
decomposition and out-of-plane stability).

Numerically: eta is computed exactly on the discrete space through the Riesz representer
r in Y (int r' v' = int rho v for all v in Y, eta = ||r'||_L2), a Galerkin approximation that
converges spectrally in N (from below); the L-infinity norm in H is a maximum over a dense
grid (2049 points) of the spectral interpolant.
"""

from __future__ import annotations

import dataclasses
from functools import lru_cache

import jax
import jax.numpy as jnp
import numpy as np

from jaxrod import spectral
from jaxrod.discretise.planar import PlanarDiscretisation, planar_discretisation
from jaxrod.magnet.reduction import Reduction, mean_zero_basis, stiffness_matrix
from jaxrod.programs import jit
from jaxrod.scenes.dipole import DipoleMagnet, dipole_potential, magnet_direction
from jaxrod.uniform.greenhill import principal_eigenpair

#: Points of the dense grid on which the L-infinity norm of H is taken.
SUP_GRID = 2049


@lru_cache(maxsize=16)
def _dense_grid(n: int, support: str):
    s = np.linspace(0.0, 1.0, SUP_GRID)
    first = 1 if support == "clamped" else 0
    return s, spectral.interpolation_matrix(n, s)[:, first:]


def dual_norm(rho_quad, disc: PlanarDiscretisation) -> jax.Array:
    """||rho||_{Y*} = sup_{v in Y} int rho v / ||v'||_L2, exactly on the discrete Y."""
    Z = mean_zero_basis(disc)
    b = Z.T @ (disc.to_quad.T @ (disc.quad_weights * rho_quad))
    K = Z.T @ stiffness_matrix(disc) @ Z
    return jnp.sqrt(jnp.dot(b, jnp.linalg.solve(K, b)))


@jit
def contraction_constants(q, alpha, red: Reduction, scene: DipoleMagnet,
                          disc: PlanarDiscretisation) -> dict:
    """eta, S, E, Delta, H, K, epsilon at (q, alpha) (formulas in the module docstring)."""
    G, M, D = scene.G, scene.M, scene.D
    delta = D - 1.0
    c2m = 2.0 * M / delta**3
    th = q * (disc.to_quad @ red.psi)
    X = jnp.stack([disc.integrate(jnp.sin(th)), disc.integrate(jnp.cos(th))])
    p = magnet_direction(alpha)
    g = jax.grad(dipole_potential)(X, p, D)
    s = disc.quad_nodes
    rho = G * (1.0 - s) * (th - jnp.sin(th)) + M * (g[0] * jnp.cos(th) - g[1] * jnp.sin(th)) \
        - c2m * th
    eta = dual_norm(rho, disc)
    rmu = jnp.sqrt(red.mu_perp)
    spread = jnp.abs(q) * jnp.sqrt(jnp.maximum(red.psi_norm2 - 1.0, 0.0))
    S = spread + 2.0 * eta / rmu
    E = 2.0 * eta / rmu * (spread + eta / rmu)
    separation = jnp.linalg.norm(X - D * p)
    Delta = separation - E
    s_dense, interp = _dense_grid(disc.n, disc.support)
    thd = q * (jnp.asarray(interp) @ red.psi)
    h = G * (1.0 - jnp.asarray(s_dense)) * (1.0 - jnp.cos(thd)) \
        - M * (g[0] * jnp.sin(thd) + g[1] * jnp.cos(thd)) - c2m
    H = jnp.max(jnp.abs(h))
    g_norm = jnp.linalg.norm(g)
    K = (H + 2.0 * (G + M * g_norm) * eta + 6.0 * M / Delta**4 * (E + S**2)) / red.mu_perp
    return {"eta": eta, "S": S, "E": E, "Delta": Delta, "H": H, "K": K,
            "epsilon": jnp.where(K < 0.5, eta / (1.0 - K), jnp.inf), "g_norm": g_norm,
            "separation": separation}


@dataclasses.dataclass(frozen=True)
class Verdict:
    """Which hypotheses hold, with margins (positive = holds)."""

    name: str
    holds: bool
    margin: float
    detail: str

    def as_dict(self) -> dict:
        return dataclasses.asdict(self)


def scene_hypotheses(scene: DipoleMagnet, n: int = 32) -> list[Verdict]:
    """The scene-wide hypotheses: 2M/delta^3 > G and beta0^cl(G) > sqrt(6) M / (9 delta^3)."""
    G, M, D = float(scene.G), float(scene.M), float(scene.D)
    delta = D - 1.0
    beta0 = float(principal_eigenpair(G, planar_discretisation(n, "clamped"))[0])
    bound = float(np.sqrt(6.0) * M / (9.0 * delta**3))
    return [
        Verdict("2M/delta^3 > G", 2 * M / delta**3 > G, 2 * M / delta**3 - G,
                f"2M/delta^3 = {2 * M / delta**3:.6g}, G = {G:.6g}"),
        Verdict("beta0_cl(G) > sqrt(6) M/(9 delta^3)", beta0 > bound, beta0 - bound,
                f"beta0_cl = {beta0:.6g}, sqrt(6) M/(9 delta^3) = {bound:.6g}"),
    ]


def point_hypotheses(constants: dict) -> list[Verdict]:
    """Delta > 0 and K < 1/2 from the constants at one (q, alpha)."""
    Delta, K = float(constants["Delta"]), float(constants["K"])
    return [Verdict("Delta > 0", Delta > 0.0, Delta, f"Delta = {Delta:.6g}"),
            Verdict("K < 1/2", K < 0.5, 0.5 - K, f"K = {K:.6g}")]


#: Capacity of the fine continuation along which ``certify`` checks the branch (step <= 0.01).
BRANCH_POINTS = 2000


def _finite_or_none(v) -> float | None:
    v = float(v)
    return v if np.isfinite(v) else None


#: ``contraction_constants`` over arrays of (q, alpha), compiled.
contraction_constants_batch = jit(
    jax.vmap(contraction_constants, in_axes=(0, 0, None, None, None)))


def certify(scene: DipoleMagnet, n: int = 16) -> dict:
    """Which hypotheses of the reduction hold, and with what margin: scene-wide, at each fold
    of the reduced route, and along the branch from the straight rod towards alpha > 0 (the
    first point, in arc length from (q, alpha) = (0, 0), where Delta > 0 or K < 1/2 fails).

    The branch is the full-space continuation (``trace_diagram`` with steps <= 0.01), so the
    check covers the branch even where the contraction argument does not; a failure is
    located between the last certified point and the first failing one.

    Paper: Proposition ``thm:mode_accuracy`` (hypotheses eq. ``mode_accuracy_hypotheses``;
    constants eqs. ``eta_qalpha_def`` to ``K_qalpha_def``).
    """
    from jaxrod.magnet.diagram import default_options, trace_diagram
    from jaxrod.magnet.reduction import reduced_folds, reduction

    disc = planar_discretisation(n, "clamped")
    out = {"scene": [v.as_dict() for v in scene_hypotheses(scene)], "folds": [], "branch": None}
    if not out["scene"][0]["holds"]:
        out["all_hold"] = False
        out["note"] = ("2M/delta^3 <= G: B0 is not coercive, the mode psi and the reduction "
                       "are undefined; nothing else to check")
        return out
    red = reduction(scene, disc)
    for f in reduced_folds(scene, n):
        c = contraction_constants(f.q, np.radians(f.alpha_deg), red, scene, disc)
        out["folds"].append({
            "kind": f.kind, "alpha_deg": f.alpha_deg, "q": f.q, "q0": f.q0,
            "alpha0_deg": f.alpha0_deg, "converged": f.converged,
            "constants": {k: _finite_or_none(v) for k, v in c.items()},
            "hypotheses": [v.as_dict() for v in point_hypotheses(c)]})
    branch = trace_diagram(scene, n, default_options(BRANCH_POINTS)._replace(ds_max=0.01))
    start = branch.straight_index
    q, alpha = branch.q[start:], branch.alpha[start:]
    c = contraction_constants_batch(q, alpha, red, scene, disc)
    c = {k: np.asarray(v) for k, v in c.items()}
    ok = (c["Delta"] > 0.0) & (c["K"] < 0.5)
    first_bad = int(np.argmin(ok)) if not ok.all() else None
    out["branch"] = {
        "points": int(q.size), "points_certified": int(ok.sum()),
        "K_max": float(c["K"].max()), "Delta_min": float(c["Delta"].min()),
        "first_failure": None if first_bad is None else {
            "alpha_deg": float(np.degrees(alpha[first_bad])), "q": float(q[first_bad]),
            "K": float(c["K"][first_bad]), "Delta": float(c["Delta"][first_bad]),
            "last_certified_alpha_deg": float(np.degrees(alpha[max(first_bad - 1, 0)])),
            "last_certified_q": float(q[max(first_bad - 1, 0)])},
        "arrays": {"alpha_deg": np.degrees(alpha).tolist(), "q": q.tolist(),
                   "K": c["K"].tolist(), "Delta": c["Delta"].tolist()}}
    out["all_hold"] = (all(v["holds"] for v in out["scene"])
                       and all(h["holds"] for f in out["folds"] for h in f["hypotheses"]))
    return out
