"""One status language: every result's ``status`` is a ``Status`` code with a message (what
happened, the likely cause, what to try), and ``throw`` decides what a failure does.

Traced code carries the status as an integer array (``int(Status.X)``), so a batch never
stops on one bad member; on the host, ``check(status, throw=True)`` raises ``SolverError``
with the message (the un-jitted entry points' default), ``throw=False`` leaves the status
on the result for the caller (the batches' default).
"""

from __future__ import annotations

import enum

import numpy as np


class Status(enum.IntEnum):
    """What a solver or an analysis ended with. ``ok`` says whether the result is usable;
    ``str(status)`` is its message. Newton's codes are 0-3, a curve's (continuation, fold
    curve) 4-8; a map point's certificates NO_FOLD_PAIR and FOLD_OUT_OF_RANGE are answers
    (``ok``); RUNNING (-1) marks a loop that has not stopped."""

    RUNNING = -1
    SUCCESS = 0
    MAX_STEPS = 1
    NONFINITE = 2
    LINE_SEARCH_FAILED = 3
    REACHED_BOUND = 4
    FOLDS_FOUND = 5
    CAPACITY_FULL = 6
    STEP_TOO_SMALL = 7
    CUSP_PASSED = 8
    SNAPPED_WHILE_LOADING = 9
    INVALID_INPUT = 10
    NOT_CONVERGED = 11
    MAGNET_IN_REACH = 12
    UNDER_RESOLVED = 13
    NO_FOLD_PAIR = 14
    FOLD_OUT_OF_RANGE = 15

    @property
    def ok(self) -> bool:
        return self in _OK

    @classmethod
    def of(cls, converged: bool) -> Status:
        """A refinement's status from its converged flag: SUCCESS or NOT_CONVERGED."""
        return cls.SUCCESS if converged else cls.NOT_CONVERGED

    @property
    def message(self) -> str:
        return MESSAGES[self]

    def __str__(self) -> str:
        return MESSAGES[self]


_OK = {Status.SUCCESS, Status.REACHED_BOUND, Status.FOLDS_FOUND, Status.CUSP_PASSED,
       Status.SNAPPED_WHILE_LOADING, Status.NO_FOLD_PAIR, Status.FOLD_OUT_OF_RANGE}

MESSAGES = {
    Status.RUNNING: "running",
    Status.SUCCESS: "converged",
    Status.MAX_STEPS: "the iteration budget ran out before convergence: the start may be far "
    "from a solution or the solution sits at a fold (singular Jacobian); try a start closer "
    "to it, or continuation from a known state",
    Status.NONFINITE: "the residual or a step became NaN/inf: a singular Jacobian (a fold or a "
    "branch point) or inputs out of range; check the inputs, or start away from the fold",
    Status.LINE_SEARCH_FAILED: "no step length reduced the residual: stuck at a local minimum "
    "of the residual; try another start",
    Status.REACHED_BOUND: "reached the end of the range (of the varied input, or of the "
    "magnet angle)",
    Status.FOLDS_FOUND: "passed the number of folds asked for (max_folds)",
    Status.CAPACITY_FULL: "stopped before the end of the range: max_points reached (raise "
    "max_points or ds_max)",
    Status.STEP_TOO_SMALL: "stopped before the end of the range: the corrector failed even at "
    "the minimum step ds_min (a branch point, a singular bordered Jacobian or too coarse a "
    "discretisation); try a larger N or a smaller ds_min",
    Status.CUSP_PASSED: "ended at a cusp (the fold curve turns back there)",
    Status.SNAPPED_WHILE_LOADING: "the loads, ramped from zero, passed a fold: the rod snapped "
    "on the way and the state is the one it snapped to (continue from a given state for "
    "another)",
    Status.INVALID_INPUT: "an input is outside its valid range",
    Status.NOT_CONVERGED: "the solver did not converge (see the residual and iterations); "
    "try a larger N, or a start closer to the solution",
    Status.MAGNET_IN_REACH: "stopped where the path brings a magnet within the rod's reach "
    "(closer to the clamp than the rod's length, where the energy is singular): the part "
    "before it is kept; shorten the range or move the path away",
    Status.UNDER_RESOLVED: "converged, but the discretisation does not resolve the answer "
    "(its a posteriori error estimate is above round-off): raise N",
    Status.NO_FOLD_PAIR: "certified: fewer than two folds on the branch over the whole range "
    "(no hysteresis loop there)",
    Status.FOLD_OUT_OF_RANGE: "certified: a fold of the pair lies outside the range asked for "
    "(the paper's rig: beyond 90 degrees, outside the magnet's sweep)",
}


class SolverError(RuntimeError):
    """A solver or analysis failed; ``status`` is its ``Status``."""

    def __init__(self, status: Status, what: str = ""):
        self.status = Status(status)
        super().__init__(f"{what}: {self.status.message}" if what else self.status.message)


def check(status, throw: bool, what: str = "") -> Status:
    """The ``Status`` of a (host) status code; raises ``SolverError`` when ``throw`` and the
    status is a failure."""
    code = Status(int(np.asarray(status)))
    if throw and not code.ok:
        raise SolverError(code, what)
    return code
