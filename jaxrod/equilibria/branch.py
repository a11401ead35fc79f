"""The branch of any scene along any input, with its special points: the record a user gets.

``branch`` traces the equilibria (``jaxrod.equilibria.trace``: pseudo-arclength continuation
of grad E(x; v) = 0 from the ramped equilibrium at the range's start) and refines the
special points met on the way, as BifurcationKit's continuation result holds them: the folds
(Moore-Spence, with their normal form: ``jaxrod.equilibria.folds``) and the branch points
(Moore's augmented system: ``jaxrod.equilibria.branch_points``), in the order met, each with
its ``kind`` ("fold" or "branch_point") and ``value``.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from jaxrod.equilibria.branch_points import refine_branch_points, stability_changes
from jaxrod.equilibria.equilibrium import DEFAULT_N
from jaxrod.equilibria.folds import refine, traced_with_folds
from jaxrod.equilibria.record import Branch, checked
from jaxrod.scenes.files import FileScene
from jaxrod.scenes.scene import Scene
from jaxrod.solvers.continuation import ContinuationOptions


def with_special_points(scene: Scene | FileScene, b: Branch, n: int = DEFAULT_N,
                        folds: list | None = None, met=None) -> Branch:
    """``b`` with its folds (``folds`` detected at the branch indices ``met``, or refined
    here) and branch points refined, in the order met along it."""
    if folds is None:
        folds, met = refine(scene, b, n), b.fold_indices
    points = folds + refine_branch_points(scene, b, n)
    met = np.concatenate([np.asarray(met, float), stability_changes(b)])
    return dataclasses.replace(b, special_points=tuple(
        points[i] for i in np.argsort(met, kind="stable")))


def branch(scene: Scene | FileScene, vary: str, start: float, stop: float,
           n: int = DEFAULT_N, state=None, options: ContinuationOptions | None = None,
           margins: dict | None = None, throw: bool = True) -> Branch:
    """The equilibria of ``scene`` (a ``Scene``, or a rig from ``jaxrod.load_scene``) as the
    input ``vary`` goes from ``start`` to ``stop`` (for a rig, any of its numbers, in the
    file's units: ``rod.youngs_modulus``, ``rod.length``; ``jaxrod.scenes.path``), with its
    special points refined (``Branch.special_points``: folds and branch points in the order
    met, each with ``kind`` and ``value``).

    Equilibria solve grad E(x; v) = 0 (the discrete Euler-Lagrange equations); stability is
    the Hessian's inertia (``Branch.stable``). ``Branch.status`` says why it ended; a path
    that brings a magnet within the rod's reach ends there (``MAGNET_IN_REACH``, the part
    before kept). ``throw``: raise ``SolverError`` for a special point whose refinement did
    not converge (else its ``converged`` and ``status`` say so).
    """
    b, found, met = traced_with_folds(scene, vary, start, stop, n, state, options, margins)
    b = with_special_points(scene, b, n, found, met)
    checked(list(b.special_points), "special point", throw)
    return b
