"""Branches of a twisted rod along its turns or any other input, their branch points and
the branches that leave them, and its equilibrium at given turns
(``jaxrod.twisted.equations``: the equations and programs). A run without a start begins,
under shortening control, at the Euler-buckled rod, and under tension control at the
straight rod."""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import jax.numpy as jnp
import numpy as np

from jaxrod import spectral
from jaxrod.discretise import grid_map
from jaxrod.discretise.framed import FramedDiscretisation
from jaxrod.params import ParameterError
from jaxrod.solvers.arclength import StepControl
from jaxrod.solvers.continuation import STATUS_MESSAGES
from jaxrod.status import Status
from jaxrod.twisted.branch_points import TwistBranchPoint, _refine
from jaxrod.twisted.equations import FLOOR_TOL, _Path, _run_program, _solve_program
from jaxrod.twisted.folds import refine_fold
from jaxrod.twisted.rod import TwistedRod
from jaxrod.twisted.state import TwistState, _states

__all__ = ["TwistBranch", "TwistBranchPoint", "TwistState", "switch_branch", "twist_branch",
           "twisted_equilibrium", "folds_along"]


@dataclasses.dataclass(frozen=True)
class TwistBranch:
    """A branch of a twisted rod along one of its inputs (``vary``; the end rotation in
    turns by default): ``points`` (TwistState, in order), ``folds`` (the indices where the
    input's direction along the branch changes sign: the point after the turn),
    ``fold_points`` (TwistFold, each fold refined: ``jaxrod.twisted.folds``),
    ``branch_points`` (TwistBranchPoint, refined), ``status`` and its message."""

    rod: TwistedRod
    points: list[TwistState]
    folds: list[int]
    status: int
    vary: str = "turns"
    branch_points: list = dataclasses.field(default_factory=list)
    fold_points: list = dataclasses.field(default_factory=list)

    @property
    def message(self) -> str:
        return STATUS_MESSAGES.get(self.status, Status(self.status).message)

    @property
    def complete(self) -> bool:
        from jaxrod.solvers.continuation import REACHED_BOUND

        return self.status == int(REACHED_BOUND)

    def column(self, name: str) -> np.ndarray:
        return np.array([getattr(p, name) for p in self.points])


def _seed(rod: TwistedRod, disc: FramedDiscretisation, turns: float, lam: float
          ) -> np.ndarray:
    """The start w = (x, mu, nu, lam) of a rod without one: under shortening control its
    first Euler mode, v1 = 2 sqrt(e) sin(2 pi s) (height 1 - e to first order), thrust
    4 pi^2; under tension control the straight rod."""
    x = np.zeros(disc.size)
    if rod.shortening is None:
        return np.concatenate([x, np.zeros(rod.constraints), [0.0, lam]])
    nodes = np.asarray(disc.field.nodes)[1:rod.n]
    x[:disc.free] = 2.0 * math.sqrt(rod.shortening) * np.sin(2.0 * math.pi * nodes)
    return np.concatenate([x, [0.0, 0.0, 1.0, 0.0, lam]])


def _regrid(rod: TwistedRod, state: TwistState, lam: float) -> np.ndarray:
    """The start ``state`` on ``rod``'s grid (barycentric interpolation of each field in
    the old grid's coordinate, ``jaxrod.discretise.grid_map``), its path parameter
    ``lam``."""
    old = state.rod
    if old.n == rod.n and old.layer_width == rod.layer_width:
        w = np.array(state.w)
    else:
        disc_old = old.discretisation()
        full = np.asarray(disc_old.field.to_full) @ state.x.reshape(3, -1).T
        values = spectral.interpolation_matrix(old.n, grid_map.grid_coordinate(
            np.asarray(rod.discretisation().field.nodes), old.layer_width)) @ full
        x = values[1:1 + rod.free_values].T.ravel()
        w = np.concatenate([x, state.w[3 * old.free_values:]])
    if rod.constraints == 2 and old.constraints == 3:
        # held at its height -> pulled by the tension that held it there: the same state
        w = np.concatenate([w[:3 * rod.free_values + 2], w[-2:]])
    elif rod.constraints != old.constraints:
        raise ParameterError("start: a state under tension control cannot start a rod "
                             "under shortening control (give a state of the same rod)")
    w[-1] = lam
    return w


def _path(rod: TwistedRod, vary: str, turns: float, to: float) -> _Path:
    """The path of ``vary`` from its value on ``rod`` (or ``turns``) to ``to``: lam is the
    turns themselves, or another input scaled to lam in [0, 1]."""
    if vary == "turns":
        return _Path(("turns",), (0.0,), (1.0,))
    value = rod.value(vary)
    if to == value:
        raise ParameterError(f"to: must differ from {vary}'s value on the rod ({value:g})")
    return _Path((vary,), (float(value),), (float(to) - float(value),))


def _follow(rod: TwistedRod, path: _Path, turns: float, w0, lam_to: float, orient,
            ds, ds_max, ds_min, max_points, max_folds, vary: str) -> TwistBranch:
    disc = rod.discretisation()
    data = path.data(rod, turns, disc)
    lo, hi = sorted((float(w0[-1]), float(lam_to)))
    control = StepControl(ds, ds_min, ds_max, 1.5, FLOOR_TOL, max_folds)
    out = _run_program(disc.size, rod.constraints, path.keys, path.phase(rod), max_points,
                       data, jnp.asarray(w0), jnp.asarray(orient),
                       jnp.array([lo - 1e-12, hi + 1e-12]), control)
    num = int(out.num_points)
    # the whole fixed-capacity record (NaN beyond num): one measuring program per capacity
    W = np.column_stack([np.asarray(out.x), np.asarray(out.lam)])
    index = np.asarray(out.morse_index)
    points = _states(rod, path, data, W, np.ones(max_points, bool),
                     np.asarray(out.residual_norm), np.asarray(out.newton_iterations),
                     index)[:num]
    dlam = np.asarray(out.tangent_lam[:num])
    folds = [i for i in range(1, num) if dlam[i] * dlam[i - 1] < 0]
    found = [_refine(rod, path, data, points[i - 1], points[i]) for i in range(1, num)
             if points[i].unstable != points[i - 1].unstable and i not in folds
             and points[i].converged and points[i - 1].converged]
    turns_back = [refine_fold(rod, path, data, points[i - 1], points[i]) for i in folds]
    return TwistBranch(rod, points, folds, int(out.status), vary, found, turns_back)


def twist_branch(rod: TwistedRod, to: float, *, vary: str = "turns",
                 start: TwistState | None = None, turns: float | None = None,
                 ds: float = 0.05, ds_max: float = 0.5, ds_min: float = 1e-6,
                 max_points: int = 400, max_folds: int = 10) -> TwistBranch:
    """Follow the equilibria of ``rod`` along ``vary`` (the far end's turns, or an input of
    the rod: "tension" or "shortening" (its control), "twist_ratio", "bending_ratio", or a
    load's "term.field[.i]") from ``start`` to ``to``, through folds (module docstring);
    the other inputs are the rod's, the turns ``turns`` (default: the start's, or 0).
    Without a start: under shortening control the Euler-buckled rod, under tension control
    the straight rod. The arclength is measured by the RMS change of the unknowns plus the
    change of lam (the turns, or the input scaled to [0, 1]); ``ds``, ``ds_max``,
    ``ds_min`` bound its steps. The count of unstable directions is read at every point;
    where it changes without a fold the branch point is refined (``branch_points``)."""
    if not math.isfinite(to):
        raise ParameterError(f"to: a finite number, got {to!r}")
    if vary == "turns" and rod.control == "free":
        raise ParameterError("vary: a rod with a free end has no far clamp to turn; vary a "
                             "load's input or load_scale")
    turns = (start.turns if start is not None else 0.0) if turns is None else float(turns)
    path = _path(rod, vary, turns, to)
    disc = rod.discretisation()
    lam0 = turns if vary == "turns" else 0.0
    w0 = _seed(rod, disc, turns, lam0) if start is None else _regrid(rod, start, lam0)
    lam_to = path.lam(to)
    orient = np.zeros(len(w0))
    orient[-1] = 1.0 if lam_to > lam0 else -1.0
    return _follow(rod, path, turns, w0, lam_to, orient, ds, ds_max, ds_min, max_points,
                   max_folds, vary)


def switch_branch(point: TwistBranchPoint, to: float, *, amplitude: float = 0.02,
                  ds: float = 0.05, ds_max: float = 0.5, ds_min: float = 1e-6,
                  max_points: int = 400, max_folds: int = 10) -> TwistBranch:
    """The branch that leaves ``point`` along its kernel: started at the branch point's
    state displaced by ``amplitude`` (RMS of the fields, radians) along the crossing
    eigenvector, its first point solved in the hyperplane through there normal to that
    direction (any one of the kernel's directions, where the symmetry makes it a circle),
    then followed toward ``to`` (in the branch's input) as ``twist_branch`` does."""
    state, path = point.state, point.path
    rod = state.rod
    phi = point.kernel / np.sqrt(np.mean(point.kernel ** 2))
    w0 = np.array(state.w)
    w0[:len(phi)] += amplitude * phi
    orient = np.zeros(len(w0))
    orient[:len(phi)] = phi
    lam_to = path.lam(to)
    # the path sets its own input, so the branch point's rod serves as the path's base
    return _follow(rod, path, state.turns, w0, lam_to, orient, ds, ds_max, ds_min,
                   max_points, max_folds, path.keys[0])


def twisted_equilibrium(rod: TwistedRod, turns: float, *, start: TwistState | None = None,
                        **options: Any) -> TwistState:
    """The equilibrium at ``turns``. Without ``start``: under shortening control the one
    reached by turning the far end while it approaches (turns and shortening raised
    together from 5% of theirs, from the Euler-buckled rod: how PyElastica loads its
    helical buckling case); under tension control by turning the straight rod; with a free
    end (turns 0) by raising the loads from the straight rod (the load scale). With a
    ``start``, by turning its far end from there (``twist_branch``; its ``options``), or at
    the same turns (another n, say) by Newton alone. The state's ``path_tail`` is the
    largest Chebyshev tail along the path that reached it."""
    if not math.isfinite(turns):
        raise ParameterError(f"turns: a finite number, got {turns!r}")
    if rod.control == "free" and turns != 0.0:
        raise ParameterError("turns: a rod with a free end has no far clamp to turn (0)")
    disc = rod.discretisation()
    path_tail = 0.0  # Newton alone: no path
    if start is not None and abs(start.turns - turns) <= 1e-12:
        path = _Path(("turns",), (0.0,), (1.0,))
        w = _regrid(rod, start, turns)
        lam = turns
    else:
        steps = (options.get("ds", 0.05), options.get("ds_max", 0.5),
                 options.get("ds_min", 1e-6), options.get("max_points", 400),
                 options.get("max_folds", 10))
        if start is None and rod.control != "tension":
            if rod.control == "free":  # the load ramp from the straight rod
                path = _Path(("load_scale",), (0.0,), (rod.load_scale,))
                w0, name = _seed(rod, disc, 0.0, 0.0), "load_scale"
            else:  # turned while it approaches
                first = 0.05
                path = _Path(("turns", "shortening"), (0.0, 0.0),
                             (float(turns), rod.shortening))
                seed = dataclasses.replace(rod, shortening=first * rod.shortening)
                w0, name = _seed(seed, disc, first * turns, first), "approach"
            orient = np.zeros(len(w0))
            orient[-1] = 1.0
            branch = _follow(rod, path, 0.0, w0, 1.0, orient, *steps, name)
            lam = 1.0
        else:
            branch = twist_branch(rod, turns, start=start, **options)
            path = _Path(("turns",), (0.0,), (1.0,))
            lam = turns
        values = np.array([p.w[-1] for p in branch.points])
        sign = np.sign(lam - values[0])
        past = np.nonzero(sign * (values - lam) >= 0)[0]
        if not len(past):
            raise _not_reached(branch, turns)
        i = int(past[0])
        path_tail = max(p.tail for p in branch.points[:i + 1])
        a, b = branch.points[i - 1], branch.points[i]
        f = (lam - a.w[-1]) / (b.w[-1] - a.w[-1])
        w = (1 - f) * a.w + f * b.w
        w[-1] = lam
    data = path.data(rod, turns, disc)
    res, eig, _, _ = _solve_program(disc.size, rod.constraints, path.keys, path.phase(rod),
                                    data, jnp.asarray(w))
    full = np.append(np.asarray(res.x), lam)
    state = _states(rod, path, data, full, [res.converged], [res.residual_norm],
                    [res.iterations], [np.sum(np.asarray(eig) < 0)])[0]
    return dataclasses.replace(state, path_tail=float(path_tail))


def folds_along(rod: TwistedRod, vary: str, vary_range: tuple[float, float], turns: float,
                count: int, start: TwistState | None = None, **options: Any
                ) -> tuple[list, TwistState | None, TwistBranch | None]:
    """(the refined folds in the order met, each with its ``converged`` report, the state at
    the range's start, the branch) along ``vary`` from ``vary_range[0]`` to
    ``vary_range[1]``, ending at the ``count``-th fold: the
    start reached by ``twisted_equilibrium`` (from ``start``, a state at the range's start
    of a nearby rod, by Newton alone; None: by the rod's own path), the far end at
    ``turns`` where ``vary`` is another input. No branch (None) where the start fails
    (its state then not converged, or None where its path stopped short)."""
    from jaxrod.status import SolverError

    a, b = vary_range
    try:
        if vary == "turns":
            first = twisted_equilibrium(rod, a, start=start)
        else:
            first = twisted_equilibrium(rod.replace(vary, a), turns, start=start)
    except SolverError:
        return [], None, None
    if not first.converged:
        return [], first, None
    branch = twist_branch(first.rod, b, vary=vary, start=first, turns=first.turns,
                          **{"max_folds": count, **options})
    return list(branch.fold_points), first, branch


def _not_reached(branch: TwistBranch, turns: float) -> Exception:
    from jaxrod.status import SolverError

    last = branch.points[-1].turns if branch.points else float("nan")
    return SolverError(f"turns: the branch stopped at {last:.6g} turns before {turns:.6g} "
                       f"({branch.message})")
