"""Vibration modes of an equilibrium of any scene.

The inextensible Kirchhoff rod's kinetic energy, lateral inertia only (rotary inertia
neglected: it is (radius / length)^2 smaller), is

    T = 1/2 int_0^1 |dr/dt|^2 ds,   r(s) = int_0^s d3,

in the nondimensional time t / (L^2 sqrt(rho A_c / (E I))). On the discretisation r at the
quadrature nodes is the cumulative integral of d3(x), so T = 1/2 xdot^T M(x) xdot with the
mass matrix M = J^T W J (J = dr(s_j)/dx by forward-mode autodiff, W the quadrature weights).
Small oscillations about an equilibrium x* solve the generalised eigenproblem

    H v = omega^2 M v,   H = the Hessian of the energy at x*,

for the angular frequencies omega (ascending) and the mode shapes v. A negative omega^2 is
an unstable direction (omega reported as NaN); at a fold the lowest omega^2 goes to zero
(the snap's soft mode). Frequencies in Hz follow from physical inputs by ``in_hertz``.
"""

from __future__ import annotations

import dataclasses
import math

import jax
import jax.numpy as jnp
import numpy as np

from jaxrod.equilibria.equilibrium import DEFAULT_N, FIXED, discretise, equilibrium
from jaxrod.params import ParameterError
from jaxrod.programs import jit
from jaxrod.scenes.path import along
from jaxrod.scenes.scene import Scene
from jaxrod.status import Status


def positions(scene: Scene, x, disc):
    """r(s_j) = int_0^{s_j} d3 at the quadrature nodes (rod lengths), (n_q, 3)."""
    return scene.positions(x, disc)


def mass_matrix(scene: Scene, x, disc):
    """M = J^T W J: the kinetic energy 1/2 int |dr/dt|^2 ds as a form in xdot."""
    J = jax.jacfwd(lambda y: positions(scene, y, disc))(x)  # (n_q, 3, m)
    return jnp.einsum("j,jkm,jkn->mn", disc.quad_weights, J, J)


def _inverse_cholesky(A):
    L = jnp.linalg.cholesky(A)
    return jax.scipy.linalg.solve_triangular(L, jnp.eye(L.shape[0]), lower=True)


@jit
def _modes(scene, disc, x):
    """omega^2 (ascending) and M-orthonormal shapes. M is an integral operator (its small
    eigenvalues fall as N^-4), so H v = omega^2 M v is solved as the well-conditioned
    M v = mu (H + sigma M) v, omega^2 = 1 / mu - sigma, with the shift sigma making H + sigma
    M positive definite (from a first estimate in M's own Cholesky factor)."""
    H = FIXED.hessian(x, 0.0, (scene, disc))
    M = mass_matrix(scene, x, disc)
    Li = _inverse_cholesky(M)
    rough = jnp.linalg.eigvalsh(Li @ H @ Li.T)[0]
    sigma = 1.0 + 2.0 * jnp.maximum(-rough, 0.0)
    Ri = _inverse_cholesky(H + sigma * M)
    mu, U = jnp.linalg.eigh(Ri @ M @ Ri.T)
    mu, U = mu[::-1], U[:, ::-1]  # the largest mu: the lowest frequencies
    V = Ri.T @ U / jnp.sqrt(mu)  # M-orthonormal
    Jk = jax.jacfwd(lambda y: scene.curvatures(y, disc))(x)  # (n_q, 3, m)
    K = jnp.einsum("j,jkm,jkn->mn", disc.quad_weights, Jk, Jk)
    return 1.0 / mu - sigma, V, jnp.einsum("mk,mn,nk->k", V, K, V)


@dataclasses.dataclass(frozen=True)
class Modes:
    """``omega_squared`` (ascending) and ``omega`` (NaN where omega^2 < 0: unstable);
    ``shapes``: the mode shapes as states (columns, M-orthonormal); ``state``: the
    equilibrium they are about; ``curvature_rates``: v_k . K v_k, the Kelvin-Voigt
    dissipation's form K (``jaxrod.dynamics.integrate``) on each shape."""

    omega_squared: np.ndarray
    shapes: np.ndarray
    state: np.ndarray
    curvature_rates: np.ndarray | None = None

    @property
    def omega(self) -> np.ndarray:
        w2 = self.omega_squared
        return np.where(w2 >= 0.0, np.sqrt(np.abs(w2)), np.nan)

    @property
    def stable(self) -> bool:
        return bool(self.omega_squared[0] > 0.0)

    def damping_ratios(self, damping: float, kelvin_voigt: float = 0.0) -> np.ndarray:
        """zeta_k = (c + eta v_k . K v_k) / (2 omega_k) for a linear drag c per unit length
        (the drag force c dr/dt acts on every mode alike, as the mass does) and the
        Kelvin-Voigt damping eta (on the unloaded rod K = H: eta omega_k / 2); the modes'
        coupling by the damping neglected."""
        return (damping + kelvin_voigt * self.curvature_rates) / (2.0 * self.omega)

    def as_dict(self, count: int | None = None) -> dict:
        k = slice(0, count)
        return {"omega": [None if math.isnan(w) else float(w) for w in self.omega[k]],
                "omega_squared": self.omega_squared[k].tolist(), "stable": self.stable}


def modes(scene: Scene, state=None, n: int = DEFAULT_N) -> Modes:
    """The vibration modes about ``state`` (default: the scene's equilibrium reached by
    ramping the loads, ``jaxrod.equilibria.equilibrium``); module docstring."""
    disc = discretise(scene, n)
    if state is None:
        state = equilibrium(scene, n).state
    x = jnp.asarray(state, jnp.float64)
    if x.shape != (disc.size,):
        raise ParameterError(f"state has shape {x.shape}; degree {n} needs ({disc.size},)")
    lam, V, kv = jax.device_get(_modes(scene, disc, x))
    return Modes(np.asarray(lam), np.asarray(V), np.asarray(x), np.asarray(kv))


def resolvable(n: int) -> int:
    """How many of the lowest modes degree n resolves (n / 2 - 2: the classical cantilever's
    first n / 2 - 2 are right to 1e-8 at n = 32-96, the next ones are not)."""
    return max(n // 2 - 2, 1)


@dataclasses.dataclass(frozen=True)
class ResolvedModes:
    """``modes`` at the degree ``n`` that resolves the lowest ``count`` of them (or the
    largest tried), with ``error_estimate``: |omega_k^2(n) - omega_k^2(n')| / max(|omega_k^2|,
    1) against the coarser degree n' tried before (an upper bound on the error at n, the
    Chebyshev discretisation converging spectrally), ``resolved``: how many of the lowest
    agree to ``tol``, and ``status``: SUCCESS, or UNDER_RESOLVED when fewer than ``count``."""

    modes: Modes
    n: int
    count: int
    resolved: int
    error_estimate: np.ndarray
    status: Status

    @property
    def converged(self) -> bool:
        return self.status == Status.SUCCESS


def resolved_modes(scene: Scene, count: int, n: int = DEFAULT_N, straight: bool = False,
                   tol: float = 1e-9, n_max: int = 256) -> ResolvedModes:
    """The lowest ``count`` modes about the scene's equilibrium (the straight rod with
    ``straight``), N raised from ``n`` (at least to resolve ``count``: ``resolvable``) until
    they agree with those of the previous degree to ``tol`` relative, each degree ~1.3x the
    last, at most ``n_max``: an answer at round-off or a status that says it is not."""
    if isinstance(count, bool) or not isinstance(count, (int, np.integer)) or count < 1:
        raise ParameterError(f"count must be a whole number >= 1, got {count!r}")
    if count > resolvable(n_max):
        raise ParameterError(f"count: at most {resolvable(n_max)} modes are resolved (degree "
                             f"{n_max}), got {count}")
    n = min(max(n, 2 * count + 4), n_max - 8)  # at least one finer degree to compare
    coarse, error, resolved = None, np.full(count, np.nan), 0
    while True:
        state = np.zeros(discretise(scene, n).size) if straight else None
        m = modes(scene, state, n=n)
        w2 = np.full(count, np.nan)
        w2[:min(count, len(m.omega_squared))] = m.omega_squared[:count]
        if coarse is not None:
            error = np.abs(w2 - coarse) / np.maximum(np.abs(w2), 1.0)
            bad = np.nonzero(~(error <= tol))[0]
            resolved = int(bad[0]) if len(bad) else count
        if resolved == count or n >= n_max:
            status = Status.SUCCESS if resolved == count else Status.UNDER_RESOLVED
            return ResolvedModes(m, n, count, resolved, error, status)
        coarse, n = w2, min(n_max, n + max(8, n // 3))


@jit(static_argnames=("count",))
def _along(path, disc, states, values, count):
    return jax.vmap(lambda x, v: _modes(path.at(v), disc, x)[0][:count])(states, values)


def modes_along(scene: Scene, branch, n: int = DEFAULT_N, count: int = 3) -> np.ndarray:
    """omega^2 of the lowest ``count`` modes at every point of a branch of ``scene``
    (``jr.branch``; its states are of degree ``n``), shape (points, count): the modes as a
    row of the branch. At a fold the lowest omega^2 crosses zero (the snap's soft mode)."""
    path = along(scene, (branch.vary,))
    disc = discretise(path.template, n)
    if branch.theta.shape[1] != disc.size:
        raise ParameterError(f"the branch's states are not of degree {n}")
    if isinstance(count, bool) or not isinstance(count, (int, np.integer)) \
            or not 1 <= count <= resolvable(n):
        raise ParameterError(f"modes: degree {n} resolves the lowest 1 to {resolvable(n)} "
                             f"modes (raise N for more), got {count!r}")
    return np.asarray(_along(path, disc, jnp.asarray(branch.theta),
                             jnp.asarray(branch.value), count))


def in_hertz(omega, length: float, radius: float, youngs_modulus: float,
             density: float) -> np.ndarray:
    """Frequencies in Hz of nondimensional angular frequencies: f = omega / (2 pi T),
    T = L^2 sqrt(rho A_c / (E I)) (a solid round rod of the given radius)."""
    from jaxrod.dynamics.drag import time_scale

    T = time_scale(length, radius, youngs_modulus, density)
    return np.asarray(omega) / (2.0 * math.pi * T)
