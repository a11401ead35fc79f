"""N raised until an answer is at round-off, by its a posteriori error estimate (the tail of
its Chebyshev series, ``jaxrod.discretise.tail``), or a status that says it is not.

``resolved_equilibrium`` raises N through ``DEGREES`` until the equilibrium's tail is at most
``TOLERANCE``; ``resolved_branch`` does the same for a branch and its refined folds and
branch points (the command line's ``equilibrium``, ``folds`` and ``branch`` on scene files).
"""

from __future__ import annotations

import dataclasses

from jaxrod.discretise.tail import tail_estimate
from jaxrod.equilibria.branch_points import refine_branch_points
from jaxrod.equilibria.equilibrium import DEFAULT_N, Equilibrium, discretise, equilibrium
from jaxrod.equilibria.folds import refine
from jaxrod.equilibria.record import Branch
from jaxrod.equilibria.trace import trace
from jaxrod.scenes.scene import Scene
from jaxrod.status import Status

#: The degrees tried in turn (each ~1.3-1.5x the last): a state resolved at one of them is at
#: round-off there.
DEGREES = (16, 24, 32, 48, 64)

#: Resolved: the tail of the angles' Chebyshev coefficients at most this (radians): the
#: angles along the rod to ~1e-8 rad, and the tip's angles and folds' values, which converge
#: faster, far below 1e-9 degrees (a hard-magnetic cantilever at load 5, N = 16: tail 2e-10,
#: tip tangent within 1e-14 degrees of N = 32's; its folds in the field's angle, tail 2e-9:
#: 3e-14 degrees from N = 24's; the paper's folds at N = 12, tail 5e-9: 2e-12 degrees).
TOLERANCE = 1e-8


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
        if not eq.converged or error <= tol:  # a failure says so itself
            return ResolvedEquilibrium(eq, d, error, eq.status)
    return ResolvedEquilibrium(eq, d, error, Status.UNDER_RESOLVED)


@dataclasses.dataclass(frozen=True)
class ResolvedBranch:
    """A branch along an input, its refined folds and branch points, at the degree ``n``
    that resolves them (or the largest tried); ``error_estimate``: the largest tail of the
    branch's states and its points' (radians); ``resolved``: at most ``TOLERANCE``."""

    branch: Branch
    folds: list
    branch_points: list
    n: int
    error_estimate: float
    resolved: bool


def resolved_branch(scene: Scene, vary: str, start: float, stop: float, n: int = DEFAULT_N,
                    margins: dict | None = None, n_max: int = DEGREES[-1],
                    tol: float = TOLERANCE, points: bool = True) -> ResolvedBranch:
    """The branch of ``scene`` along ``vary`` from ``start`` to ``stop`` with its folds (and,
    with ``points``, its branch points), N raised through ``DEGREES`` from ``n`` until the
    largest tail of the branch's states and its special points' is at most ``tol``."""
    degrees = [n] + [d for d in DEGREES if n < d <= n_max]
    for d in degrees:
        b = trace(scene, vary, start, stop, d, margins=margins)
        folds = refine(scene, b, d)
        bps = refine_branch_points(scene, b, d) if points else []
        disc = discretise(scene, d)
        error = max([tail_estimate(disc, b.theta)] + [p.error_estimate for p in folds + bps])
        if error <= tol:
            break
    return ResolvedBranch(b, folds, bps, d, error, error <= tol)
