"""Peer methods for the permanent-magnet fold pair, each run as its users would run it.

``solve_bvp_fold``: scipy's ``solve_bvp`` (collocation, residual tolerance ``tol``) on the
Euler-Lagrange BVP with the tip X as two unknown parameters, followed along the branch by
natural-parameter continuation in alpha (each solve starts from the previous solution); a
failed solve or a jump of the tip angle by more than ``JUMP_DEG`` halves the step, and the
fold is the last alpha reached when the step falls below ``step_min_deg``.

``sine_series_fold``: the paper's own method, Rayleigh-Ritz with the sine series
theta = sum_k A_k sin((k - 1/2) pi s) (the modes satisfy theta(0) = 0, theta'(1) = 0), the
energy by Gauss-Legendre quadrature and minimised with scipy's BFGS (analytic gradient) at
each alpha from the previous minimiser; the fold is where the minimiser jumps to the other
branch, bracketed by the same step halving.

Upper folds are approached along the engaged branch from alpha = 0 upwards, lower folds
along the disengaged branch from alpha = 89 degrees downwards.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.integrate import solve_bvp
from scipy.optimize import minimize

#: A change of the tip angle larger than this in one step is a jump to the other branch.
JUMP_DEG = 3.0


def grad_phi(x, p, D):
    r = x - D * p
    r2 = r @ r
    return p / r2**1.5 - 3.0 * (p @ r) * r / r2**2.5


def _direction(alpha):
    return np.array([math.sin(alpha), math.cos(alpha)])


def _natural_continuation(solve, tip, start_deg, direction, step_min_deg, step_deg=2.0):
    """Follow a branch in alpha until the step is below step_min_deg; return the last alpha."""
    alpha = start_deg
    state = solve(math.radians(alpha), None)
    if state is None:
        raise RuntimeError(f"no solution at the start alpha = {alpha} deg")
    step = step_deg
    while step > step_min_deg:
        trial = alpha + direction * step
        new = solve(math.radians(trial), state) if 0.0 < trial < 90.0 else None
        if new is not None and abs(tip(new) - tip(state)) < JUMP_DEG:
            alpha, state = trial, new
        else:
            step *= 0.5
    return alpha


def solve_bvp_fold(G, M, D, kind: str, tol: float, step_min_deg: float) -> float:
    def rhs(s, y, p):
        g = grad_phi(p, _direction(rhs.alpha), D)
        th = y[0]
        return np.vstack([y[1], -G * (1 - s) * np.sin(th) + M * (g[0] * np.cos(th)
                                                                  - g[1] * np.sin(th)),
                          np.sin(th), np.cos(th)])

    def bc(ya, yb, p):
        return np.array([ya[0], yb[1], ya[2], ya[3], yb[2] - p[0], yb[3] - p[1]])

    def solve(alpha, state):
        rhs.alpha = alpha
        if state is None:
            s = np.linspace(0.0, 1.0, 11)
            y0 = np.vstack([np.zeros_like(s), np.zeros_like(s), np.zeros_like(s), s])
            guess = (s, y0, np.array([0.0, 1.0]))
        else:
            guess = (state.x, state.y, state.p)
        sol = solve_bvp(rhs, bc, guess[0], guess[1], p=guess[2], tol=tol, max_nodes=20000)
        return sol if sol.success else None

    tip = lambda sol: math.degrees(math.atan2(sol.p[0], sol.p[1]))
    start, direction = (0.0, 1.0) if kind == "upper" else (89.0, -1.0)
    return _natural_continuation(solve, tip, start, direction, step_min_deg)


def sine_series_fold(G, M, D, kind: str, modes: int, step_min_deg: float,
                     quadrature: int = 64) -> float:
    x, w = np.polynomial.legendre.leggauss(quadrature)
    s, w = 0.5 * (x + 1.0), 0.5 * w
    k = (np.arange(1, modes + 1) - 0.5) * np.pi
    B = np.sin(np.outer(s, k))
    stiffness = 0.5 * np.diag(k**2)  # int phi_i' phi_j' = k_i^2 / 2 delta_ij
    lever = 1.0 - s

    def energy_and_gradient(A, p):
        th = B @ A
        S, C = np.sin(th), np.cos(th)
        X = np.array([w @ S, w @ C])
        r = X - D * p
        r2 = r @ r
        phi = (p @ r) / r2**1.5
        g = p / r2**1.5 - 3.0 * (p @ r) * r / r2**2.5
        e = 0.5 * A @ stiffness @ A + G * (w @ (lever * C)) + M * phi
        grad = stiffness @ A + B.T @ (w * (-G * lever * S + M * (g[0] * C - g[1] * S)))
        return e, grad

    def solve(alpha, state):
        A0 = np.zeros(modes) if state is None else state
        res = minimize(energy_and_gradient, A0, args=(_direction(alpha),), jac=True,
                       method="BFGS", options={"gtol": 1e-11, "maxiter": 2000})
        return res.x

    def tip(A):
        th = B @ A
        return math.degrees(math.atan2(w @ np.sin(th), w @ np.cos(th)))

    start, direction = (0.0, 1.0) if kind == "upper" else (89.0, -1.0)
    return _natural_continuation(solve, tip, start, direction, step_min_deg)
