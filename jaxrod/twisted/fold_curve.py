"""The fold curve of a twisted rod in two of its inputs, point by point.

A fold of a branch in the end rotation (``jaxrod.twisted.folds``) moves as another input
(the shortening, the tension, a load) changes: the folds make a curve in the plane of the
two. At a point of that curve the state is a fold whichever of the two is varied, so the
curve is traced across the turns: at each of the given turns the state is taken from a
branch in the turns (``twisted_equilibrium`` from its nearest point), then the other input
is continued from there until the branch turns back, and that fold is refined. Each point
is one continuation, compiled once for all of them; a point whose branch finds no fold
(the curve not crossed within ``to``) is reported, not guessed.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from jaxrod.params import ParameterError
from jaxrod.status import Status
from jaxrod.twisted.branch import TwistBranch, twist_branch, twisted_equilibrium
from jaxrod.twisted.folds import TwistFold

__all__ = ["TwistFoldCurve", "twist_fold_curve"]


@dataclasses.dataclass(frozen=True)
class TwistFoldCurve:
    """``turns`` (the given end rotations), ``folds`` (a TwistFold per turns, its
    ``value`` the fold's value of ``vary``; None where the branch found none), ``vary``,
    and each point's branch (``branches``: its status says why a fold was not found)."""

    vary: str
    turns: list[float]
    folds: list[TwistFold | None]
    branches: list[TwistBranch]

    @property
    def complete(self) -> bool:
        """Every point found, refined and resolved (its state's status SUCCESS: an
        under-resolved fold is not counted)."""
        return all(f is not None and f.converged and f.state.status == Status.SUCCESS
                   for f in self.folds)

    def column(self, name: str) -> np.ndarray:
        """A field of the folds' states (``value``, ``tension``, ``twist_moment``...), NaN
        where no fold was found."""
        return np.array([getattr(f.state, name) if f is not None else math.nan
                         for f in self.folds])


def twist_fold_curve(branch: TwistBranch, turns, vary: str, to: float, **options
                     ) -> TwistFoldCurve:
    """The folds in ``vary`` (an input of the branch's rod: "shortening", "tension", a
    load's "term.field") at each of ``turns``, starting from ``branch`` (a branch in the
    turns whose points before its first fold span them) and continuing ``vary`` toward
    ``to`` (module docstring); ``options`` go to each ``twist_branch`` (``ds``, ``ds_max``,
    ``max_points``)."""
    if branch.vary != "turns":
        raise ParameterError(f"branch: a branch in the turns, got one in {branch.vary}")
    if vary == "turns":
        raise ParameterError("vary: the input other than the turns (the curve is traced "
                             "across the turns)")
    points = branch.points[:branch.folds[0]] if branch.folds else branch.points
    values = np.array([p.turns for p in points])
    folds, branches = [], []
    for r in (float(v) for v in np.atleast_1d(turns)):
        if not values.min() <= r <= values.max():
            raise ParameterError(f"turns: {r:g} is outside the branch's "
                                 f"[{values.min():g}, {values.max():g}] (before its first "
                                 "fold)")
        nearest = points[int(np.argmin(np.abs(values - r)))]
        state = twisted_equilibrium(branch.rod, r, start=nearest)
        along = twist_branch(state.rod, to, vary=vary, start=state, turns=r,
                             **{"max_folds": 1, **options})
        branches.append(along)
        folds.append(along.fold_points[0] if along.fold_points else None)
    return TwistFoldCurve(vary, [float(v) for v in np.atleast_1d(turns)], folds, branches)
