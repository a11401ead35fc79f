"""Independent fold angles of the permanent-magnet scene by shooting (scipy).

The planar Euler-Lagrange equation (paper, Lemma "Existence of planar equilibria")

    theta'' = -G (1 - s) sin(theta) + M grad Phi(X) . (cos theta, -sin theta),
    theta(0) = 0,  theta'(1) = 0,  X = int_0^1 (sin theta, cos theta) ds,

is integrated from s = 0 with theta'(0) = kappa and a guessed tip X, together with
X(s) = int_0^s (sin, cos). For fixed kappa the three unknowns (alpha, X1, X3) solve
theta'(1) = 0, X(1) = X. Along the branch alpha(kappa) is smooth and a fold is an extremum of
alpha(kappa), found by Brent's method; the error of alpha* is quadratic in that of kappa.
"""

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import fsolve, minimize_scalar


def grad_phi(x, p, D):
    r = x - D * p
    r2 = r @ r
    return p / r2**1.5 - 3.0 * (p @ r) * r / r2**2.5


def _shoot(kappa, alpha, X, G, M, D):
    p = np.array([np.sin(alpha), np.cos(alpha)])
    g = grad_phi(np.asarray(X), p, D)

    def rhs(s, y):
        th, dth = y[0], y[1]
        ddth = -G * (1 - s) * np.sin(th) + M * (g[0] * np.cos(th) - g[1] * np.sin(th))
        return [dth, ddth, np.sin(th), np.cos(th)]

    sol = solve_ivp(rhs, (0.0, 1.0), [0.0, kappa, 0.0, 0.0], method="DOP853", rtol=1e-13,
                    atol=1e-14)
    y = sol.y[:, -1]
    return np.array([y[1], y[2] - X[0], y[3] - X[1]])


def alpha_of_kappa(kappa, guess, G, M, D):
    """(alpha, X1, X3) on the branch with theta'(0) = kappa, by fsolve from ``guess``."""
    f = lambda z: _shoot(kappa, z[0], z[1:], G, M, D)
    z, info, ier, msg = fsolve(f, guess, xtol=1e-14, full_output=True)
    if ier != 1 and np.max(np.abs(info["fvec"])) > 1e-11:
        raise RuntimeError(msg)
    return z


def fold_alpha(G, M, D, kappa_bracket, guess, kind):
    """alpha* (radians) of the fold: min of alpha(kappa) for 'lower', max for 'upper'."""
    state = {"guess": np.asarray(guess, float)}

    def objective(kappa):
        z = alpha_of_kappa(kappa, state["guess"], G, M, D)
        state["guess"] = z
        return z[0] if kind == "lower" else -z[0]

    res = minimize_scalar(objective, bracket=kappa_bracket, tol=1e-10)
    return res.fun if kind == "lower" else -res.fun
