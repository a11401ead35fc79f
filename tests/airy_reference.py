"""Independent reference values from closed forms in Airy functions (scipy.special).

With x = 1 - s the eigenproblem -u'' - G (1 - s) u = beta u becomes u_xx + (G x + beta) u = 0,
solved by u = c1 Ai(z) + c2 Bi(z), z(x) = -(G^(1/3) x + beta G^(-2/3)). The free end s = 1
(x = 0) has u_x = 0; the support s = 0 (x = 1) has u = 0 (clamped) or u_x = 0 (pinned). The
characteristic equations are

    clamped:  Ai'(z0) Bi(z1)  - Bi'(z0) Ai(z1)  = 0,
    pinned:   Ai'(z0) Bi'(z1) - Bi'(z0) Ai'(z1) = 0,     z0 = z(0), z1 = z(1).

The principal eigenvalue is the first sign change of the characteristic function scanned
upward from beta = -G (a lower bound, paper Prop. "Explicit bounds"), polished by brentq.
"""

import numpy as np
from scipy.integrate import quad
from scipy.optimize import brentq
from scipy.special import airy


def characteristic(beta, G, support):
    g13 = G ** (1.0 / 3.0)
    z0 = -beta / g13**2
    z1 = -(g13 + beta / g13**2)
    _, ap0, _, bp0 = airy(z0)
    a1, ap1, b1, bp1 = airy(z1)
    # divide by the positive |(Ai'(z0), Bi'(z0))| to keep the function O(1) without poles
    scale = np.hypot(ap0, bp0)
    if support == "clamped":
        return (ap0 * b1 - bp0 * a1) / scale
    return (ap0 * bp1 - bp0 * ap1) / scale


def principal_eigenvalue(G, support):
    lo = -G - 1e-9 * max(G, 1.0)
    step = 2e-3 * max(G ** (2.0 / 3.0), 1.0)
    f_lo = characteristic(lo, G, support)
    for _ in range(100000):
        hi = lo + step
        f_hi = characteristic(hi, G, support)
        if np.sign(f_hi) != np.sign(f_lo):
            return brentq(lambda b: characteristic(b, G, support), lo, hi, xtol=1e-15,
                          rtol=1e-15, maxiter=500)
        lo, f_lo = hi, f_hi
    raise RuntimeError("no eigenvalue found")


def greenhill_load_paper_formula():
    """Root of the paper's Ai(-G^(1/3)) + Bi(-G^(1/3)) / sqrt(3) = 0 (Lemma 'Greenhill')."""
    f = lambda G: airy(-G ** (1.0 / 3.0))[0] + airy(-G ** (1.0 / 3.0))[2] / np.sqrt(3.0)
    return brentq(f, 7.0, 9.0, xtol=1e-15, rtol=1e-15)


def eigenfunction(G, support):
    """(beta0, u) with u callable on [0, 1], int u^2 = 1, u > 0 inside."""
    beta = principal_eigenvalue(G, support)
    g13 = G ** (1.0 / 3.0)
    z = lambda s: -(g13 * (1.0 - s) + beta / g13**2)
    z0 = z(1.0)
    _, ap0, _, bp0 = airy(z0)
    # u_x(0) = 0 at the free end: c1 Ai'(z0) + c2 Bi'(z0) = 0
    c1, c2 = bp0, -ap0

    def raw(s):
        a, _, b, _ = airy(z(s))
        return c1 * a + c2 * b

    norm2 = quad(lambda s: raw(s) ** 2, 0.0, 1.0, epsabs=0, epsrel=1e-13, limit=200)[0]
    sign = np.sign(quad(raw, 0.0, 1.0, limit=200)[0])
    return beta, lambda s: sign * raw(s) / np.sqrt(norm2)


def pitchfork_coefficient(G, support):
    """A2 = 1/6 int (4 A_crit - G (1 - s)) u^4 by adaptive quadrature of the Airy solution."""
    beta, u = eigenfunction(G, support)
    integrand = lambda s: (4.0 * (-beta) - G * (1.0 - s)) * u(s) ** 4
    return quad(integrand, 0.0, 1.0, epsabs=0, epsrel=1e-12, limit=200)[0] / 6.0


def straight_rod_branch_loads(load, support, G_max, count):
    """The first ``count`` gravity groups G in (0, G_max] at which the straight heavy rod
    under a field along it (a stabilising load ``load``: -u'' - G (1 - s) u + load u = 0)
    has a kernel: the zeros in G of the characteristic function at beta = -load, located
    by a scan and polished by brentq."""
    f = lambda G: characteristic(-load, G, support)
    grid = np.linspace(0.5, G_max, 4000)  # the first kernel lies above G = 0.5 here
    values = np.array([f(G) for G in grid])
    roots = [brentq(f, a, b, xtol=1e-14, rtol=1e-15, maxiter=500)
             for a, b, fa, fb in zip(grid[:-1], grid[1:], values[:-1], values[1:])
             if np.sign(fa) != np.sign(fb)]
    if len(roots) < count:
        raise RuntimeError(f"found {len(roots)} branch loads below G = {G_max}")
    return roots[:count]
