"""Branch points of a twisted rod's branch: where its count of unstable directions changes
without a fold, refined to the crossing of the bordered Hessian's eigenvalue."""

from __future__ import annotations

import dataclasses

import jax.numpy as jnp
import numpy as np

from jaxrod.twisted.equations import _Path, _solve_program
from jaxrod.twisted.rod import TwistedRod
from jaxrod.twisted.state import TwistState, _states


@dataclasses.dataclass(frozen=True)
class TwistBranchPoint:
    """Where a branch's count of unstable directions changes without a fold: ``state``
    (refined: the point where the bordered Hessian's eigenvalue crosses zero), ``unstable``
    (the count before and after; a jump of 2 at a straight rod: the rotational symmetry's
    two-dimensional kernel), ``converged`` (the refinement's report), ``kernel`` (the
    x part of the crossing eigenvector, for ``switch_branch``)."""

    state: TwistState
    unstable: tuple[int, int]
    converged: bool
    kernel: np.ndarray
    path: _Path

    @property
    def value(self) -> float:
        return self.state.value

    def as_dict(self) -> dict:
        return {"value": self.value, **self.state.as_dict(), "unstable": list(self.unstable),
                "kernel_dimension": abs(self.unstable[1] - self.unstable[0]),
                "converged": self.converged}


def illinois(f, a: float, b: float, ftol: float, xtol: float, steps: int = 60
             ) -> tuple[float, float]:
    """(x, f(x)): a root of f between a and b (f(a) f(b) < 0; f evaluated at a and b
    first, then at each iterate) by the Illinois variant of false position, to |f| <= ftol
    or a bracket below xtol (relative to max(1, |x|)); the last iterate."""
    fa, fb = f(a), f(b)
    x, fx, side = a, fa, 0
    for _ in range(steps):
        x = (a * fb - b * fa) / (fb - fa)
        fx = f(x)
        if abs(fx) <= ftol or abs(b - a) <= xtol * max(1.0, abs(x)):
            break
        if fx * fa > 0:
            a, fa = x, fx
            fb = 0.5 * fb if side == -1 else fb
            side = -1
        else:
            b, fb = x, fx
            fa = 0.5 * fa if side == 1 else fa
            side = 1
    return x, fx


def _refine(rod: TwistedRod, path: _Path, data, a: TwistState, b: TwistState
            ) -> TwistBranchPoint:
    """The branch point between the neighbours a and b: the path parameter where the
    bordered Hessian's eigenvalue number q (q = a's negative count, a the side with fewer)
    crosses zero, by the Illinois variant of false position on Newton's states at fixed
    lam (from the chord between a and b)."""
    disc = data[0]
    lo, hi = (a, b) if a.unstable < b.unstable else (b, a)
    bordering = rod.constraints + int(path.phase(rod) and np.linalg.norm(
        lo.w[:2 * disc.free]) > 1e-10)
    q = lo.unstable + bordering

    def at(lam):
        f = (lam - a.w[-1]) / (b.w[-1] - a.w[-1])
        w = (1 - f) * a.w + f * b.w
        w[-1] = lam
        res, eig, vec, _ = _solve_program(disc.size, rod.constraints, path.keys,
                                          path.phase(rod), data, jnp.asarray(w))
        return res, float(eig[q]), np.asarray(vec[:, q]), lam

    found = {}

    def crossing(lam):
        res, g, vec, _ = at(lam)
        found[lam] = (res, g, vec, lam)
        return g

    lam, _ = illinois(crossing, lo.w[-1], hi.w[-1], ftol=1e-12, xtol=1e-13)
    res, g, vec, lam = found[lam]
    eig_count = np.sum(np.asarray(_solve_program(
        disc.size, rod.constraints, path.keys, path.phase(rod), data,
        jnp.asarray(np.append(np.asarray(res.x), lam)))[1]) < 0)
    state = _states(rod, path, data, np.append(np.asarray(res.x), lam)[None], [res.converged],
                    [res.residual_norm], [res.iterations], [eig_count])[0]
    converged = bool(res.converged) and abs(g) <= 1e-8
    return TwistBranchPoint(state, (a.unstable, b.unstable), converged, vec[:disc.size],
                            path)


