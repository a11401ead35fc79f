"""Independent one-mode folds (q0, alpha0): psi from scipy's solve_bvp, integrals by adaptive
Gauss-Kronrod quadrature (scipy.integrate.quad), the 2 x 2 system by scipy's fsolve with a
central difference for dF0/dq. Shares no code with jaxrod."""

import numpy as np
from scipy.integrate import quad, solve_bvp
from scipy.optimize import fsolve


def mode(G, M, D):
    """psi and psi' as callables (solve_bvp on -u'' + a0 u = 1, psi = u / int u)."""
    delta = D - 1.0
    a0 = lambda s: 2 * M / delta**3 - G * (1 - s)
    sol = solve_bvp(lambda s, y: np.vstack([y[1], a0(s) * y[0] - 1.0, y[0]]),
                    lambda ya, yb: np.array([ya[0], yb[1], ya[2]]),
                    np.linspace(0, 1, 200), np.zeros((3, 200)), tol=1e-11, max_nodes=200000)
    assert sol.success
    mean = sol.sol(1.0)[2]
    return (lambda s: sol.sol(s)[0] / mean), (lambda s: sol.sol(s)[1] / mean)


def one_mode_folds(G, M, D, guesses_deg):
    psi, dpsi = mode(G, M, D)
    integral = lambda f: quad(f, 0.0, 1.0, epsabs=1e-13, epsrel=1e-13, limit=200)[0]
    bend = integral(lambda s: dpsi(s) ** 2)

    def F0(q, alpha):
        X = np.array([integral(lambda s: np.sin(q * psi(s))),
                      integral(lambda s: np.cos(q * psi(s)))])
        p = np.array([np.sin(alpha), np.cos(alpha)])
        r = X - D * p
        grad = p / (r @ r) ** 1.5 - 3 * (p @ r) * r / (r @ r) ** 2.5
        n_int = np.array([integral(lambda s: np.cos(q * psi(s)) * psi(s)),
                          -integral(lambda s: np.sin(q * psi(s)) * psi(s))])
        gravity = integral(lambda s: (1 - s) * np.sin(q * psi(s)) * psi(s))
        return q * bend - G * gravity + M * grad @ n_int

    def system(x):
        q, a = x
        h = 1e-5
        return [F0(q, a), (F0(q + h, a) - F0(q - h, a)) / (2 * h)]

    out = []
    for q, a in guesses_deg:
        x = fsolve(system, [q, np.radians(a)], xtol=1e-13)
        out.append((x[0], np.degrees(x[1])))
    return out
