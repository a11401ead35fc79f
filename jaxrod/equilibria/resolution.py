"""A posteriori error estimates of a discrete state, and N raised until it is at round-off.

A state's angles (theta, or the director chart's v1 and v2) are polynomials of degree N on
the Chebyshev grid; their Chebyshev coefficients c_k of a smooth solution decay
geometrically, so the first neglected ones are of the size of the last kept: the estimate

    e(N) = max over the angles of max(|c_{N-2}|, |c_{N-1}|, |c_N|)   (radians)

bounds the discretisation's error in the angles (to within the decay's ratio). A boundary
layer (a hard-magnetic rod at a load of 1000: a layer of width 1 / sqrt(1000) at the clamp)
leaves the tail large at the default N, where Newton still converges to 1e-13: the residual
says nothing about resolution, the tail does. ``resolved_equilibrium`` raises N through
``DEGREES`` until e(N) <= ``tol``, or says UNDER_RESOLVED with the estimate.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from jaxrod import spectral
from jaxrod.equilibria.equilibrium import DEFAULT_N, Equilibrium, discretise, equilibrium
from jaxrod.scenes.scene import Scene
from jaxrod.status import Status

#: The degrees tried in turn (each ~1.3-1.5x the last): a state resolved at one of them is at
#: round-off there.
DEGREES = (16, 24, 32, 48, 64)

#: Resolved: the tail of the angles' Chebyshev coefficients below this (radians). The tail
#: bounds the angles' error along the whole rod, boundary layers included; the tip's angles
#: converge faster (a hard-magnetic cantilever at load 5, N = 16: tail 2e-10 rad, tip
#: tangent within 1e-14 degrees of N = 32's), so tip angles are then right to 1e-9 degrees.
TOLERANCE = 1e-10


def tail_estimate(disc, x) -> float:
    """e(N) of the state x of the discretisation ``disc`` (module docstring), radians."""
    planar = getattr(disc, "planar", disc)
    to_coefficients = spectral.values_to_coefficients_matrix(planar.n)
    angles = np.asarray(x, float).reshape(-1, planar.size)
    c = np.asarray(to_coefficients) @ (np.asarray(planar.to_full) @ angles.T)
    return float(np.max(np.abs(c[-3:])))


@dataclasses.dataclass(frozen=True)
class ResolvedEquilibrium:
    """``equilibrium`` at the degree ``n`` that resolves it (or the largest tried), its
    ``error_estimate`` (``tail_estimate``, radians) and a ``status``: the equilibrium's own,
    or UNDER_RESOLVED where even the largest degree leaves the tail above ``TOLERANCE``."""

    equilibrium: Equilibrium
    n: int
    error_estimate: float
    status: Status

    @property
    def converged(self) -> bool:
        return self.equilibrium.converged and self.status.ok


def resolved_equilibrium(scene: Scene, n: int = DEFAULT_N, n_max: int = DEGREES[-1],
                         tol: float = TOLERANCE) -> ResolvedEquilibrium:
    """The scene's equilibrium (ramped from zero loads) at the first degree in ``DEGREES``
    from ``n`` on (``n`` itself first) whose tail estimate is at most ``tol``: an answer at
    round-off, or, at ``n_max``, a status that says it is not."""
    degrees = [n] + [d for d in DEGREES if n < d <= n_max]
    for d in degrees:
        eq = equilibrium(scene, d, throw=False)
        error = tail_estimate(discretise(scene, d), eq.state)
        if not eq.converged:
            return ResolvedEquilibrium(eq, d, error, eq.status)
        if error <= tol:
            return ResolvedEquilibrium(eq, d, error, eq.status)
    return ResolvedEquilibrium(eq, d, error, Status.UNDER_RESOLVED)
