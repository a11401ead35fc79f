"""Design for a target shape: the inputs of a planar scene (a remanence profile's
coefficients, a field, a stiffness group) whose equilibrium takes a target shape.

The target is the tangent angle theta*(s_i) at points s_i in [0, 1] (degrees, from +z toward
+x). The free inputs p (keys of the scene or rig) minimise

    0.5 sum_i ((theta(s_i; p) - theta*(s_i)) / sigma)^2 + 0.5 smoothing |p - p0|^2 / |p0|^2,

where theta(.; p) is the equilibrium grad E(x; p) = 0 continued from the last accepted one
by Newton, differentiated implicitly (dx/dp = -H^-1 d(grad E)/dp: exact gradients, never
finite differences), with the least squares of ``jaxrod.solvers.least_squares`` (L-BFGS
directions in Gauss-Newton scaling, Armijo line search; one compiled program for every
target of the scene's structure). Bounds, a magnet within the rod's reach, and an unstable
equilibrium (the Hessian not positive definite: a design the rod would snap away from)
reject a trial point. The answer is
checked: the Hessian's smallest eigenvalue (``stable``) and the equilibrium reached by
ramping the loads of the designed scene from zero (``jaxrod.equilibrium``): ``reachable``
where it is the designed one.

For a hard magnetisation mu(s) along the tangent in a uniform field at angle a, the moment
balance theta'' + load mu(s) sin(a - theta) = 0, theta'(1) = 0 gives the profile of a
target in closed form, mu = -theta*'' / (load sin(a - theta*)) (checked in the tests).
"""

from __future__ import annotations

import dataclasses
import math

import jax
import jax.numpy as jnp
import numpy as np

from jaxrod import spectral
from jaxrod.discretise.tail import tail_estimate
from jaxrod.equilibria.equilibrium import DEFAULT_N, MODEL, discretise, equilibrium
from jaxrod.equilibria.resolution import TOLERANCE
from jaxrod.inverse.scene_fit import magnet_margins, with_values
from jaxrod.params import ParameterError, check_value
from jaxrod.programs import jit
from jaxrod.scenes.files import FileScene
from jaxrod.scenes.path import along
from jaxrod.scenes.scene import Scene
from jaxrod.solvers.least_squares import forward_mode, least_squares_run
from jaxrod.solvers.newton import implicit_newton
from jaxrod.status import Status

#: Fewest target points.
MIN_POINTS = 3
#: The stability margin's penalty: a residual MARGIN_WEIGHT (margin - lambda_min) where the
#: Hessian's smallest eigenvalue falls short of it (beside residuals in units of sigma).
MARGIN_WEIGHT = 1e4
#: A margin that binds is met to this, relative (the penalty leaves ~1e-5 of it).
MARGIN_TOLERANCE = 1e-4


@dataclasses.dataclass(frozen=True)
class ShapeDesign:
    """A design for a target shape: ``values`` (key -> value of each free input),
    ``tangent_deg`` the designed equilibrium's tangent angle at the target's ``s``,
    ``shape_error_deg`` its largest difference from the target, ``stable`` (the Hessian's
    smallest eigenvalue ``smallest_eigenvalue`` > 0; ``margin_met``: at least the margin
    asked), ``reached`` (the shape within ``REACHED`` sigma of the target: else the bounds,
    the margin or the basis keep the design from it, said in ``reason``), ``reachable``
    (ramping the designed scene's loads from zero reaches this equilibrium, to 1e-8 rad),
    ``error_estimate`` (the tail of its Chebyshev series, radians: above
    ``jaxrod.equilibria.resolution.TOLERANCE`` the status is UNDER_RESOLVED, raise n),
    ``converged`` (the least squares converged and the equilibrium solves did),
    ``iterations``, ``status``, ``scene`` the designed scene (or rig) and ``state`` its
    equilibrium."""

    values: dict
    s: np.ndarray
    target_deg: np.ndarray
    tangent_deg: np.ndarray
    shape_error_deg: float
    stable: bool
    smallest_eigenvalue: float
    reachable: bool
    margin_met: bool
    reached: bool
    error_estimate: float
    converged: bool
    iterations: int
    status: Status
    scene: object
    state: np.ndarray
    reason: str = ""

    def as_dict(self) -> dict:
        return {"values": self.values, "s": self.s.tolist(),
                "target_deg": self.target_deg.tolist(), "tangent_deg": self.tangent_deg.tolist(),
                "shape_error_deg": self.shape_error_deg, "stable": self.stable,
                "smallest_eigenvalue": self.smallest_eigenvalue, "reachable": self.reachable,
                "margin_met": self.margin_met, "reached": self.reached, "reason": self.reason,
                "error_estimate": self.error_estimate,
                "converged": self.converged, "iterations": self.iterations,
                "status": self.status.name.lower()}


def _program(path, disc, x0, p0, free, cases, rows, target, sigma, smoothing, limits,
             magnets, margin, max_iter):
    """The least squares over p (the path's inputs after the load scale, scaled by |p0|)
    from the equilibria x0 (K, m) of the K load cases at p0: case k sets the path's last
    inputs to ``cases[k]``; target (K, points); limits = (A, lo, hi): lo <= A p <= hi (the
    bounds of inputs and of profiles' values); ``magnets``: term name -> (its radius in rod
    lengths at the start, its exponents in the path's inputs)."""
    unit = jnp.where(p0 == 0.0, 1.0, jnp.abs(p0))
    start = jnp.concatenate([p0, cases[0]])

    def clear(q):
        """Every magnet beyond the rod's reach at the inputs q (free, then the case's)."""
        scene = path.at(jnp.concatenate([jnp.ones(1), q]))
        safe = jnp.where(start == 0.0, 1.0, start)
        gaps = [jnp.linalg.norm(scene.terms[t].centre()) - 1.0
                - margin * jnp.prod(jnp.where(k == 0, 1.0, (q / safe) ** k))
                for t, (margin, k) in magnets.items()]
        return jnp.all(jnp.stack(gaps) > 0.0) if gaps else jnp.asarray(True)

    def args(p, case):
        return (path, disc, 1.0, 1.0, jnp.concatenate([p, case]))

    def solve(p, x, case):
        ok = clear(jnp.concatenate([p, case]))
        x_new, stats = implicit_newton(
            lambda y, q: MODEL.gradient(y, 0.0, args(q, case)), x, p, tol=1e-12,
            jacobian=lambda y, q: MODEL.hessian(y, 0.0, args(q, case)))
        smallest = jnp.linalg.eigvalsh(MODEL.hessian(x_new, 0.0, args(p, case)))[0]
        return x_new, ok & (stats[0] == 1.0) & (smallest > 0.0), smallest  # stable only

    def residuals(u, x):
        p = u * unit
        x_new, ok, smallest = jax.vmap(lambda xk, ck: solve(p, xk, ck))(x, cases)
        A, lo, hi = limits
        ok = jnp.all(ok) & jnp.all((A @ p >= lo) & (A @ p <= hi))
        r = ((x_new @ rows.T - target) / sigma).reshape(-1)
        short = MARGIN_WEIGHT * jnp.maximum(margin - smallest, 0.0) * (margin > 0.0)
        return jnp.concatenate([r, short, smoothing * (u - p0 / unit) * free]), x_new, ok

    res = least_squares_run(forward_mode(residuals), p0 / unit, x0, free,
                            target.size + cases.shape[0] + p0.shape[0], True, max_iter)
    return res._replace(p=res.p * unit, J=res.J / unit)


_design_program = jit(_program, static_argnames=("max_iter",))


def design_shape(scene: Scene | FileScene, free, s, target_deg, n: int = DEFAULT_N,
                 bounds: dict | None = None, sigma_deg: float = 1.0, smoothing: float = 0.0,
                 max_iter: int = 80, cases: dict | None = None,
                 margin: float = 0.0) -> ShapeDesign:
    """The inputs ``free`` (keys) of a planar scene or rig whose equilibrium's tangent angle
    at ``s`` is ``target_deg`` (module docstring). The scene's values of the free inputs are
    the start; ``bounds``: key -> (lo, hi), an input's, or a profile's values along s by its
    list's key (``magnetisation.strength_profile``: mu(s), at 101 points; every coefficient
    free); ``smoothing`` > 0 pulls the inputs towards the
    start (relative); ``sigma_deg`` scales the residuals. ``cases``: several load cases at
    once, key -> its K values (e.g. two field directions, {"field.0.angle_deg": [90, 45]}),
    with one target row per case, ``target_deg`` (K, len(s)). ``margin`` > 0: a stability
    margin, the Hessian's smallest eigenvalue at least ``margin`` in every case (a penalty
    ``MARGIN_WEIGHT`` (margin - lambda_min) where it falls short; ``margin_met`` says
    whether it holds to ``MARGIN_TOLERANCE`` of it). A target no design reaches
    returns ``converged`` True with its ``shape_error_deg`` (the least-squares answer),
    never an error."""
    inner = scene.scene if isinstance(scene, FileScene) else scene
    if inner.geometry != "planar":
        raise ParameterError("scene: shape targets are tangent angles of a planar rod "
                             f"(geometry = \"planar\"), got {inner.geometry!r}")
    free = tuple(free)
    if not free or len(set(free)) != len(free):
        raise ParameterError(f"free: one or more distinct inputs, got {free}")
    case_keys, case_values = _cases(cases, free)
    s = np.asarray(s, float).reshape(-1)
    target = np.atleast_2d(np.asarray(target_deg, float))
    if target.shape != (len(case_values), s.size) or s.size < MIN_POINTS:
        raise ParameterError(f"target: at least {MIN_POINTS} points (s, tangent_deg), one row "
                             f"of len(s) = {s.size} angles per load case "
                             f"({len(case_values)}), got {np.shape(target_deg)}")
    if not (np.all(np.isfinite(s)) and np.all(np.isfinite(target))):
        raise ParameterError("target: s and the angles must be finite (no NaN)")
    if np.any((s < 0.0) | (s > 1.0)):
        raise ParameterError(f"target: s must lie in [0, 1], got {s.min():g} to {s.max():g}")
    check_value("sigma_deg", sigma_deg, lambda v: v > 0, "a number > 0")
    check_value("smoothing", smoothing, lambda v: v >= 0, "a number >= 0")
    check_value("margin", margin, lambda v: v >= 0, "a number >= 0 (the Hessian's smallest "
                "eigenvalue to keep)")
    path = along(scene, ("load_scale", *free, *case_keys))
    p0 = np.asarray(path.start[1:1 + len(free)], float)
    limits = _limits(dict(bounds or {}), free, p0)
    at_case = lambda sc, k: with_values(sc, dict(zip(case_keys, case_values[k])))
    starts = [equilibrium(at_case(scene, k), n=n, throw=False) for k in range(len(target))]
    for k, start in enumerate(starts):
        if not start.converged:
            raise ParameterError(f"scene: its equilibrium at the start (load case {k}) did "
                                 f"not converge ({start.status.message})")
    disc = discretise(path.template, n)
    rows = spectral.interpolation_matrix(disc.n, s) @ np.asarray(disc.to_full)
    res = jax.device_get(_design_program(
        path, disc, jnp.asarray(np.stack([e.state for e in starts])), jnp.asarray(p0),
        jnp.ones(p0.size, bool), jnp.asarray(case_values), jnp.asarray(rows),
        jnp.radians(jnp.asarray(target)), math.radians(sigma_deg), float(smoothing),
        tuple(jnp.asarray(v) for v in limits),
        magnet_margins(scene, free + case_keys, np.r_[p0, case_values[0]]), float(margin),
        max_iter))
    values = dict(zip(free, (float(v) for v in res.p)))
    designed = with_values(scene, values)
    x = np.asarray(res.aux)
    tangent = np.degrees(x @ rows.T)
    eig = min(float(np.linalg.eigvalsh(np.asarray(MODEL.hessian(
        jnp.asarray(x[k]), 0.0, (path, disc, 1.0, 1.0,
                                 jnp.concatenate([res.p, case_values[k]])))))[0])
        for k in range(len(x)))
    reachable = True
    for k in range(len(x)):
        ramped = equilibrium(at_case(designed, k), n=n, throw=False)
        reachable &= bool(ramped.converged) and float(np.max(np.abs(ramped.state - x[k]))) \
            <= 1e-8
    converged = bool(res.converged) and bool(res.ok)
    error_estimate = tail_estimate(disc, x)
    status = Status.NOT_CONVERGED if not converged else (
        Status.UNDER_RESOLVED if error_estimate > TOLERANCE else Status.SUCCESS)
    one = (lambda a: a[0]) if cases is None else (lambda a: a)
    error = float(np.max(np.abs(tangent - target)))
    reached = error <= REACHED * sigma_deg
    A, lo, hi = limits
    held = A @ np.asarray(res.p)
    # the line search rejects points beyond a bound: it stops short of it by its last step
    at_bound = bool(np.any(np.minimum(held - lo, hi - held)
                           <= 1e-3 * np.maximum(1.0, np.abs(held))))
    reason = "" if reached else (
        f"the target is not reached: the largest shape error is {error:.3g} deg ("
        + ("the design stops at its bounds" if at_bound else
           "the margin or the profiles' degree keep the design from it") + ")")
    return ShapeDesign(values=values, s=s, target_deg=one(target), tangent_deg=one(tangent),
                       shape_error_deg=error, reached=reached, reason=reason,
                       stable=eig > 0.0, smallest_eigenvalue=eig, reachable=reachable,
                       margin_met=eig >= margin * (1.0 - MARGIN_TOLERANCE),
                       converged=converged, iterations=int(res.iterations),
                       error_estimate=error_estimate, status=status,
                       scene=designed, state=one(x))


#: A shape within this many sigma of the target everywhere is reached.
REACHED = 1e-6


#: A profile's basis by its list's key: Chebyshev in 2 s - 1, or powers of s (degrees).
PROFILES = {"magnetisation.strength_profile": "chebyshev", "rod.stiffness_profile":
            "chebyshev", "magnetisation.profile_deg": "powers"}


def _limits(bounds: dict, free, p0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(A, lo, hi) with lo <= A p <= hi: a free input's bounds a row of the identity, a
    profile's bounds its basis at 101 points of s times its free coefficients."""
    rows, lo, hi = [], [], []
    for key, pair in bounds.items():
        try:
            a, b = (float(v) for v in pair)
        except (TypeError, ValueError):
            raise ParameterError(f"bounds {key}: a pair (lo, hi), got {pair!r:.60}") from None
        if not a < b:
            raise ParameterError(f"bounds {key}: lo < hi, got ({a:g}, {b:g})")
        if key in free:
            rows.append(np.eye(len(free))[free.index(key)][None])
        elif key in PROFILES:
            idx = [i for i, k in enumerate(free) if k.startswith(key + ".")]
            if not idx:
                raise ParameterError(f"bounds {key}: free its coefficients ({key}.0, ...)")
            order = [int(free[i].rsplit(".", 1)[1]) for i in idx]
            if sorted(order) != list(range(len(order))):
                raise ParameterError(f"bounds {key}: bounds on the profile's values need all "
                                     f"its coefficients free ({key}.0 to .{len(order) - 1})")
            s = np.linspace(0.0, 1.0, 101)
            basis = (np.polynomial.chebyshev.chebvander(2 * s - 1, len(idx) - 1)
                     if PROFILES[key] == "chebyshev" else np.vander(s, len(idx), True))
            block = np.zeros((s.size, len(free)))
            block[:, idx] = basis[:, order]
            rows.append(block)
        else:
            raise ParameterError(f"bounds: {key!r} is not free ({', '.join(free)}) nor a "
                                 f"profile of free coefficients ({', '.join(PROFILES)})")
        lo += [a] * len(rows[-1])
        hi += [b] * len(rows[-1])
    A = np.concatenate(rows) if rows else np.zeros((0, len(free)))
    lo, hi = np.array(lo, float), np.array(hi, float)
    if np.any(A @ p0 < lo) or np.any(A @ p0 > hi):
        raise ParameterError("bounds: the start (the scene's values) lies outside them")
    return A, lo, hi


def _cases(cases: dict | None, free) -> tuple[tuple, np.ndarray]:
    """(the load cases' keys, their values (K, keys)); one case of no keys without cases."""
    if cases is None:
        return (), np.zeros((1, 0))
    keys = tuple(cases)
    counts = {len(np.atleast_1d(cases[k])) for k in keys}
    if not keys or len(counts) != 1 or min(counts) < 1:
        raise ParameterError("cases: key -> its values, one per load case, as many for every "
                             f"key, got {cases!r:.80}")
    for key in keys:
        if key in free:
            raise ParameterError(f"cases: {key} is free; a load case's inputs are given")
    values = np.array([np.atleast_1d(np.asarray(cases[k], float)) for k in keys]).T
    if not np.all(np.isfinite(values)):
        raise ParameterError("cases: the load cases' values must be finite")
    return keys, values
