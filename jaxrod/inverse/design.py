"""Inverse design: the inputs whose folds capture and release at target angles.

"Capture at 20 degrees, release at 45 degrees: which track radius and magnet diameter?"
The targets are the folds of the planar branch, alpha_lower = capture and alpha_upper =
release (a sweep of increasing magnet angle captures the rod at -alpha_lower and releases
it at alpha_upper; the offset is zero). The inputs named in ``vary`` are solved for by the
generic design (``jaxrod.inverse.scene_fit.design_folds``: the fit's least-squares program
with the four angles as targets, on the shipped rig or the paper's scene of the groups,
``jaxrod.scenes.dipole.rig_of``) within bounds; its line search rejects every trial point
where the magnet would touch the rod, an input leaves its bounds or the branch has no two
folds (only bistable designs). It starts from the given point and from a grid of points
inside the bounds, so that separate solutions are each found; every solution is verified
by a fresh continuation from the straight rod and Moore-Spence (``jaxrod.folds``) at the
answer.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from jaxrod.design_point import DesignPoint, range_of
from jaxrod.inverse.fit import MODEL_N, OFFSET, READOUT, _check_names, check_bounds
from jaxrod.inverse.scene_fit import design_folds, with_values
from jaxrod.params import UNITS, ParameterError, check_degree, check_value
from jaxrod.scenes.dipole import rig_of

#: The fresh continuation at a design must agree with the model's folds to this (deg).
VERIFY_DEG = 1e-6
#: Default bounds of a varied input: a factor of this either side of its given value.
DEFAULT_FACTOR = 3.0


@dataclasses.dataclass(frozen=True)
class Design:
    """One design: the varied inputs' values, the folds reached by the model and by the
    independent check (a fresh continuation), and whether both hit the targets."""

    values: dict
    capture_deg: float
    release_deg: float
    verified_capture_deg: float | None
    verified_release_deg: float | None
    converged: bool
    verified: bool
    iterations: int
    #: what the independent check found, in words, when it is not the two folds
    check: str | None = None

    def as_dict(self) -> dict:
        return self.values | {"capture_deg": self.capture_deg,
                              "release_deg": self.release_deg,
                              "verified_capture_deg": self.verified_capture_deg,
                              "verified_release_deg": self.verified_release_deg,
                              "converged": self.converged, "verified": self.verified,
                              "iterations": self.iterations, "check": self.check}


@dataclasses.dataclass(frozen=True)
class DesignResult:
    """Every distinct design found for the targets (best first), and the search."""

    capture_deg: float
    release_deg: float
    vary: tuple[str, ...]
    bounds: dict
    designs: list
    starts: int
    point: DesignPoint
    n: int = 12
    verify_n: int = 16

    @property
    def family(self) -> int:
        """How many dimensions the designs span: the varied inputs beyond the two targets
        (0: isolated designs; more: a family, of which ``designs`` are samples)."""
        return max(len(self.vary) - 2, 0)

    def as_dict(self) -> dict:
        best = self.designs[0].as_dict() if self.designs else {}
        return best | {"targets": {"capture_deg": self.capture_deg,
                                   "release_deg": self.release_deg},
                       "vary": list(self.vary),
                       "units": {n: UNITS[n] for n in self.vary},
                       "bounds": {k: list(v) for k, v in self.bounds.items()},
                       "solutions": [d.as_dict() for d in self.designs],
                       "starts": self.starts, "point": self.point.as_dict(),
                       "n": self.n, "verify_n": self.verify_n, "family": self.family,
                       "converged": bool(self.designs) and self.designs[0].verified}


def check_targets(capture_deg: float, release_deg: float) -> tuple[float, float]:
    """Validate the target angles: 0 < capture < release < 90 degrees."""
    capture = check_value("capture", capture_deg, lambda x: -90.0 < x < 90.0,
                          "an angle in (0, 90) degrees")
    release = check_value("release", release_deg, lambda x: -90.0 < x < 90.0,
                          "an angle in (0, 90) degrees (a release beyond 90 degrees is past "
                          "the horizontal)")
    if not capture > 0.0:
        raise ParameterError(f"capture: the capture angle is the lower fold, in (0, 90) "
                             f"degrees, got {capture_deg!r}")
    if not release > capture:
        raise ParameterError(f"release: the release angle (upper fold) must exceed the "
                             f"capture angle {capture:g} deg (the loop opens between them), "
                             f"got {release_deg!r}")
    return capture, release


def default_bounds(point: DesignPoint, vary) -> dict:
    """A factor ``DEFAULT_FACTOR`` either side of each varied input, within its range."""
    out = {}
    for name in vary:
        v = point.values[point.index(name)]
        r = range_of(name)
        lo, hi = max(v / DEFAULT_FACTOR, r.low), min(v * DEFAULT_FACTOR, r.high)
        if name == "D":
            lo = max(lo, 1.0 + point.radius() + 1e-9)
        out[name] = (lo, hi)
    return out


def design(point: DesignPoint, capture_deg: float, release_deg: float, vary,
           bounds: dict | None = None, starts_per_axis: int = 3,
           n: int = MODEL_N) -> DesignResult:
    """Designs whose folds capture and release at the targets (module docstring).

    ``point``: the design to start from and the values of the inputs not varied (groups
    or physical); ``vary``: the inputs to solve for (names of ``point``); ``bounds``: name
    -> (lo, hi) (default ``default_bounds``); ``n``: the Chebyshev degree of the model's
    folds (each design is verified by a fresh continuation at max(n, 16)). Raises ParameterError
    when no bistable design within the bounds reaches the targets (the closest found is in
    the message).

    Targets: the lower fold at ``capture_deg`` and the upper at ``release_deg`` (Proposition
    ``thm:planar_fold``; the design rule of section ``s.discussion`` of the paper).
    """
    capture, release = check_targets(capture_deg, release_deg)
    degree = check_degree(n, "N-magnet")  # (``n`` names inputs below)
    vary = _check_names(vary, point.names, "vary")
    if not vary:
        raise ParameterError("vary: name at least one input to solve for")
    if OFFSET in vary:
        raise ParameterError("vary: the offset is not a design input")
    given = check_bounds(dict(bounds or {}), point.names)
    unknown = [n for n in given if n not in vary]
    if unknown:
        raise ParameterError(f"bounds: {', '.join(unknown)} not varied (vary: "
                             f"{', '.join(vary)})")
    for name, (lo, hi) in given.items():
        r = range_of(name)
        if not (r.contains(lo) and r.contains(hi)):
            raise ParameterError(f"bounds {name}: ({lo:g}, {hi:g}) must lie within the valid "
                                 f"range {r.interval()}")
        if name == "D" and lo <= 1.0 + point.radius():
            raise ParameterError(f"bounds D: the lower bound {lo:g} must exceed 1 + magnet "
                                 f"radius / L = {1.0 + point.radius():g} (the magnet would "
                                 "touch the rod)")
    bounds = default_bounds(point, vary) | given
    if not all(bounds[n][0] <= point.values[point.index(n)] <= bounds[n][1] for n in vary):
        # start inside the bounds: the geometric centre of the box
        values = list(point.values)
        for n in vary:
            values[point.index(n)] = math.sqrt(bounds[n][0] * bounds[n][1])
        point = dataclasses.replace(point, values=tuple(values))
    scene, angle, span, degrees, keys = rig_of(point)
    outcomes = design_folds(
        scene, angle, span, np.array([-capture, release, capture, -release]) / degrees,
        [keys[n][0] for n in vary], {keys[n][0]: (lo / keys[n][1], hi / keys[n][1])
                                     for n, (lo, hi) in bounds.items()},
        n=degree, readout=READOUT, starts=starts_per_axis)
    values = lambda d: {n: d.estimates[keys[n][0]] * keys[n][1] for n in vary}
    found = [d for d in outcomes if d.converged]
    if not found:
        raise ParameterError(_infeasible(capture, release, vary, bounds, outcomes[:1],
                                         values, degrees))
    designs = [_verified(scene, angle, span, keys, values(d), d, degrees, capture, release,
                         max(degree, 16)) for d in found]
    designs.sort(key=lambda d: (not d.verified, _distance(point, d.values)))
    return DesignResult(capture, release, vary, bounds, designs,
                        1 + starts_per_axis ** len(vary), point, degree, max(degree, 16))


def _distance(point: DesignPoint, values: dict) -> float:
    return sum(math.log(v / point.values[point.index(n)]) ** 2 for n, v in values.items())


def _verified(scene, angle, span, keys, values, fit, degrees, capture, release,
              degree: int) -> Design:
    """The design checked by a fresh continuation from the straight rod at N = ``degree``
    (the folds along the magnet's angle: the upper met first, then the lower)."""
    from jaxrod.equilibria.folds import folds as fresh_folds

    at = with_values(scene, {keys[n][0]: v / keys[n][1] for n, v in values.items()})
    report = fresh_folds(at, angle, *span, n=degree, throw=False)
    angles = [f.value * degrees for f in report]
    folds = sorted(angles) if len(report) == 2 else None
    check = None
    if folds is None:
        listed = ", ".join(f"{a:.6g}" for a in angles)
        check = (f"a fresh continuation finds {len(report)} folds on the branch through the "
                 f"straight rod ({listed} deg), not two: the sweep's capture and release are "
                 "not the model's pair of folds" if report else
                 "a fresh continuation finds no fold on the branch through the straight rod")
    verified = (folds is not None and all(f.converged for f in report)
                and abs(folds[0] - capture) <= VERIFY_DEG
                and abs(folds[1] - release) <= VERIFY_DEG)
    return Design(values=values, capture_deg=float(fit.model[2] * degrees),
                  release_deg=float(fit.model[1] * degrees),
                  verified_capture_deg=None if folds is None else folds[0],
                  verified_release_deg=None if folds is None else folds[1],
                  converged=fit.converged, verified=verified, iterations=fit.iterations,
                  check=check)


def _infeasible(capture, release, vary, bounds, closest, values, degrees) -> str:
    box = ", ".join(f"{n} in [{lo:.6g}, {hi:.6g}]" for n, (lo, hi) in bounds.items())
    text = (f"capture/release: no bistable design with {box} has its folds at "
            f"{capture:g} and {release:g} deg")
    if closest:
        at = ", ".join(f"{n} = {v:.6g}" for n, v in values(closest[0]).items())
        text += (f"; the closest reached capture {closest[0].model[2] * degrees:.4g} and "
                 f"release {closest[0].model[1] * degrees:.4g} deg at {at}")
    return text + " (widen the bounds, vary other inputs, or move the targets)"
