"""The a posteriori error estimate of a discrete state: the tail of its Chebyshev series.

A state's angles (theta, or the director chart's v1 and v2) are polynomials of degree N on
the Chebyshev grid; the Chebyshev coefficients c_k of a smooth solution decay
geometrically, so the first neglected ones are of the size of the last kept:

    e(N) = max over the angles of max(|c_{N-2}|, |c_{N-1}|, |c_N|)   (radians)

estimates the discretisation's error in the angles along the whole rod, boundary layers
included. Newton's residual says nothing about it (a hard-magnetic rod at a load of 1000 has
a layer of width 1 / sqrt(1000) at the clamp: converged to 1e-13 at N = 16, its tip 6e-5
degrees off, e = 7e-4). The tip's angles and a fold's value converge faster (a fold's value
as e^2, as the Ritz method's eigenvalues do).
"""

from __future__ import annotations

import numpy as np

from jaxrod import spectral


def tail_estimate(disc, x) -> float:
    """e(N) of the state(s) x (one state, or a stack of them: the largest) of the
    discretisation ``disc`` (module docstring), radians. Host side."""
    planar = getattr(disc, "planar", disc)
    to_coefficients = np.asarray(spectral.values_to_coefficients_matrix(planar.n))
    angles = np.asarray(x, float).reshape(-1, planar.size)
    c = to_coefficients @ (np.asarray(planar.to_full) @ angles.T)
    return float(np.max(np.abs(c[-3:]))) if c.size else 0.0
