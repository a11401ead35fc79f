"""``Branch``: a traced equilibrium branch on the host, with stability and folds (any scene,
any input)."""

from __future__ import annotations

import csv
import dataclasses
import math
from pathlib import Path

import numpy as np

from jaxrod.solvers.continuation import RawBranch
from jaxrod.status import SolverError, Status


@dataclasses.dataclass(frozen=True)
class Branch:
    """Equilibria along an input (struct of arrays, first axis = branch point).

    Attributes:
      value: the varied input (``vary``; the magnet angle alpha in radians for the paper's
        diagram, ``alpha`` naming it there).
      theta: discrete states (free nodal values).
      q, tip, energy: recorded observables (q = int theta, tip angle in radians).
      min_eig, morse_index: smallest Hessian eigenvalue and number of negative ones.
      tangent_value: parameter component of the unit tangent (changes sign at folds).
      newton_iterations, residual_norm: corrector diagnostics per point.
      status: why each traced segment stopped (``jaxrod.Status``; str() is the message).
      vary: the varied input's key; tip_position: X = int d3 per point (generic scenes).
      special_points: the refined folds and branch points, in the order met (each with
        ``kind`` and ``value``; ``jaxrod.equilibria.branch``).
    """

    value: np.ndarray
    theta: np.ndarray
    q: np.ndarray
    tip: np.ndarray
    energy: np.ndarray
    min_eig: np.ndarray
    morse_index: np.ndarray
    tangent_value: np.ndarray
    newton_iterations: np.ndarray
    residual_norm: np.ndarray
    status: tuple[Status, ...]
    complete: bool
    vary: str = "magnet.alpha"
    tip_position: np.ndarray | None = None
    special_points: tuple = ()

    @property
    def alpha(self) -> np.ndarray:
        """The varied input (the paper's magnet angle, radians, in its diagram)."""
        return self.value

    @property
    def tangent_alpha(self) -> np.ndarray:
        return self.tangent_value

    @property
    def stable(self) -> np.ndarray:
        return self.morse_index == 0

    @property
    def fold_indices(self) -> np.ndarray:
        """i such that a fold lies between points i and i + 1 (d alpha/ds changes sign)."""
        t = self.tangent_value
        return np.nonzero(np.sign(t[:-1]) * np.sign(t[1:]) < 0)[0]

    @property
    def straight_index(self) -> int:
        """Index of the straight rod (alpha = 0, q = 0), where both traced runs start."""
        return int(np.argmin(np.abs(self.alpha) + np.abs(self.q)))

    @property
    def engaged(self) -> slice:
        """The engaged branch: from the straight rod to the largest alpha (the upper fold)."""
        start = self.straight_index
        return slice(start, start + int(np.argmax(self.alpha[start:])) + 1)

    def __len__(self) -> int:
        return self.value.shape[0]

    @property
    def _in_degrees(self) -> bool:
        """The paper's diagram: the magnet angle, shown in degrees."""
        return self.vary == "magnet.alpha"

    def write_csv(self, path: Path) -> None:
        """One row per point: the varied input (alpha in degrees for the paper's diagram),
        q, tip angle (degrees), energy, smallest eigenvalue, stable."""
        first = "alpha_deg" if self._in_degrees else self.vary
        v = np.degrees(self.value) if self._in_degrees else self.value
        with open(path, "w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow([first, "q", "tip_deg", "energy", "min_eig", "stable"])
            for i in range(len(self)):
                w.writerow([f"{v[i]:.12g}", f"{self.q[i]:.12g}",
                            f"{np.degrees(self.tip[i]):.12g}", f"{self.energy[i]:.12g}",
                            f"{self.min_eig[i]:.6g}", int(self.stable[i])])

    def plot(self, ax=None, y: str = "tip"):
        """Tip angle (or q) against the varied input (alpha in degrees); stable solid,
        unstable dashed."""
        import matplotlib.pyplot as plt

        ax = ax or plt.gca()
        a = np.degrees(self.value) if self._in_degrees else self.value
        v = np.degrees(self.tip) if y == "tip" else self.q
        stable = self.stable
        for mask, style, label in ((stable, "-", "stable"), (~stable, "--", "unstable")):
            vv = np.where(mask, v, np.nan)
            ax.plot(a, vv, style, color="C0" if style == "-" else "C3", label=label)
        f = self.fold_indices
        ax.plot(a[f], v[f], "kx", label="fold (detected)")
        ax.set_xlabel("magnet angle alpha (deg)" if self._in_degrees else self.vary)
        ax.set_ylabel("tip angle (deg)" if y == "tip" else "q = int theta")
        return ax


def first_points(b: Branch, k: int) -> Branch:
    """The branch's first ``k`` points (every per-point field cut; the statuses kept)."""
    per_point = {f.name: getattr(b, f.name)[:k] for f in dataclasses.fields(b)
                 if isinstance(getattr(b, f.name), np.ndarray)}
    return dataclasses.replace(b, **per_point)


def branch_from_runs(runs: list[tuple[RawBranch, bool, tuple]]) -> Branch:
    """Concatenate continuation runs (each optionally reversed) into one ``Branch``.

    Each run comes with its observables (q, tip, energy), evaluated on the device over the
    run's whole fixed-capacity arrays (so their program never depends on the branch length).
    """
    parts, status, complete = [], [], True
    for raw, reverse, (q, tip, energy) in runs:
        k = int(raw.num_points)
        fields = {f: np.asarray(getattr(raw, f))[:k] for f in
                  ("x", "lam", "tangent_lam", "min_eig", "morse_index", "newton_iterations",
                   "residual_norm")}
        fields |= {"q": np.asarray(q)[:k], "tip": np.asarray(tip)[:k],
                   "energy": np.asarray(energy)[:k]}
        if reverse:
            fields = {f: v[::-1] for f, v in fields.items()}
            fields["tangent_lam"] = -fields["tangent_lam"]
        parts.append(fields)
        code = Status(int(raw.status))
        status.append(code)
        complete &= code in (Status.REACHED_BOUND, Status.FOLDS_FOUND)
    # runs share their starting point: drop the duplicate
    if len(parts) == 2:
        parts[1] = {f: v[1:] for f, v in parts[1].items()}
    cat = {f: np.concatenate([p[f] for p in parts]) for f in parts[0]}
    return Branch(value=cat["lam"], theta=cat["x"], q=cat["q"], tip=cat["tip"],
                  energy=cat["energy"], min_eig=cat["min_eig"], morse_index=cat["morse_index"],
                  tangent_value=cat["tangent_lam"], newton_iterations=cat["newton_iterations"],
                  residual_norm=cat["residual_norm"], status=tuple(status), complete=complete)


@dataclasses.dataclass(frozen=True)
class SpecialPoint:
    """A special point of a branch in the input ``vary`` (a fold, a branch point), refined:
    ``value`` the input there, ``tip_angle_deg`` (the tip's direction from +z toward +x) and
    ``tip_position`` of its ``state``, the Hessian's kernel ``null_vector``, the
    refinement's ``converged``, ``residual_norm``, ``iterations`` and ``status``, and the
    state's ``error_estimate`` (the tail of its Chebyshev series, radians:
    ``jaxrod.discretise.tail``; NaN where not computed)."""

    vary: str
    value: float
    tip_angle_deg: float
    tip_position: np.ndarray
    state: np.ndarray
    null_vector: np.ndarray
    converged: bool
    residual_norm: float
    iterations: int
    status: Status
    error_estimate: float = dataclasses.field(default=math.nan, kw_only=True)

    #: What the point is ("fold", "branch_point").
    kind = "special point"

    def as_dict(self) -> dict:
        """The scalars (the arrays ``state`` and ``null_vector`` left out; the error
        estimate where computed)."""
        out = {}
        for f in dataclasses.fields(self):
            v = getattr(self, f.name)
            if f.name in ("state", "null_vector", "vary", "status") or (
                    f.name == "error_estimate" and math.isnan(v)):
                continue
            out[f.name] = [float(x) for x in v] if f.name == "tip_position" else \
                list(v) if isinstance(v, tuple) else v
        return out


def checked(points: list, kind: str, throw: bool) -> list:
    """``points`` (special points); with ``throw``, ``SolverError`` for the first one whose
    refinement did not converge."""
    if throw:
        for p in points:
            if not p.converged:
                raise SolverError(p.status, f"the {kind} near {p.vary} = {p.value:.6g}")
    return points
