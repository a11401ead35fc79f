"""Design for a target shape: the inputs of a planar scene (a remanence profile's
coefficients, a field, a stiffness group) whose equilibrium takes a target shape.

The target is the tangent angle theta*(s_i) at points s_i in [0, 1] (degrees, from +z toward
+x), or the centreline's points r*(s_i) = (x, z) (rod lengths from the clamp; r(s) =
int_0^s (sin theta, cos theta) ds), or both (a tip pose: s = 1). The free inputs p (keys of
the scene or rig) minimise

    0.5 sum_i ((theta(s_i; p) - theta*(s_i)) / sigma)^2 + 0.5 sum_i |(r(s_i; p) - r*(s_i))
        / sigma_length|^2 + 0.5 smoothing |p - p0|^2 / |p0|^2
        + 0.5 roughness^2 sum_profiles int_0^1 f''(s)^2 ds,

where theta(.; p) is the equilibrium grad E(x; p) = 0 continued from the last accepted one
by Newton, differentiated implicitly (dx/dp = -H^-1 d(grad E)/dp: exact gradients, never
finite differences), with the least squares of ``jaxrod.solvers.least_squares`` (L-BFGS
directions in Gauss-Newton scaling, Armijo line search; one compiled program for every
target of the scene's structure). Bounds, a magnet within the rod's reach, a step that
turns the rod by more than ``MAX_JUMP``, and an unstable equilibrium (the Hessian not
positive definite: a design the rod would snap away from) reject a trial point.

Stability is measured by the smallest eigenvalue of the second variation per unit
int dtheta^2 ds (``l2_smallest``: H v = lambda M v with M the L2 Gram matrix; independent
of N, pi^2 / 4 for the unloaded clamped-free rod of unit stiffness). A margin keeps it at
least ``margin`` along the ramp of the loads from zero to the design (a penalty at
``RAMP_POINTS`` load scales and at the vertex of the parabola through the least three). The
answer is checked: the eigenvalue along the continued ramp (``jaxrod.branch`` in
load_scale) and the equilibrium reached by ramping the loads of the designed scene from
zero (``jaxrod.equilibrium``): ``reachable`` where it is the designed one, stable all the
way.

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
from jaxrod.equilibria.branch import branch
from jaxrod.equilibria.equilibrium import DEFAULT_N, MODEL, discretise, equilibrium
from jaxrod.equilibria.resolution import TOLERANCE
from jaxrod.inverse.profile_conditions import bound_rows, roughness_rows
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
#: The most a trial step may turn the rod's tangent anywhere (radians): a design follows its
#: equilibrium by continuation and never jumps to another branch.
MAX_JUMP = 0.5
#: A margin that binds is met to this, relative (the penalty leaves ~1e-5 of it).
MARGIN_TOLERANCE = 1e-4


@dataclasses.dataclass(frozen=True)
class ShapeDesign:
    """A design for a target shape: ``values`` (key -> value of each free input),
    ``tangent_deg`` the designed equilibrium's tangent angle at the target's ``s`` and
    ``shape_error_deg`` its largest difference from ``target_deg``; ``xz`` its centreline
    there and ``position_error`` its largest distance from ``target_xz`` (rod lengths; None
    where not targeted); ``stable`` (``smallest_eigenvalue`` > 0, the smallest eigenvalue
    of the second variation per unit int dtheta^2 ds, ``l2_smallest``),
    ``path_smallest_eigenvalue`` (the smallest along the ramp of the loads from zero;
    ``margin_met``: at least the margin asked there), ``reached``
    (the shape within ``REACHED`` sigma of the target: else the bounds, the margin or the
    basis keep the design from it, said in ``reason``), ``reachable`` (ramping the designed
    scene's loads from zero reaches this equilibrium, stable all the way, to 1e-8 rad),
    ``error_estimate`` (the tail of its Chebyshev series, radians: above
    ``jaxrod.equilibria.resolution.TOLERANCE`` the status is UNDER_RESOLVED, raise n),
    ``converged`` (the least squares converged and the equilibrium solves did),
    ``iterations``, ``status``, ``scene`` the designed scene (or rig) and ``state`` its
    equilibrium."""

    values: dict
    s: np.ndarray
    target_deg: np.ndarray | None
    tangent_deg: np.ndarray | None
    shape_error_deg: float | None
    target_xz: np.ndarray | None
    xz: np.ndarray | None
    position_error: float | None
    stable: bool
    smallest_eigenvalue: float
    path_smallest_eigenvalue: float
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
    n: int = DEFAULT_N

    def as_dict(self) -> dict:
        listed = lambda a: None if a is None else np.asarray(a).tolist()
        return {"values": self.values, "s": self.s.tolist(),
                "target_deg": listed(self.target_deg), "tangent_deg": listed(self.tangent_deg),
                "shape_error_deg": self.shape_error_deg, "target_xz": listed(self.target_xz),
                "xz": listed(self.xz), "position_error": self.position_error,
                "stable": self.stable, "smallest_eigenvalue": self.smallest_eigenvalue,
                "path_smallest_eigenvalue": self.path_smallest_eigenvalue,
                "reachable": self.reachable, "margin_met": self.margin_met,
                "reached": self.reached, "reason": self.reason,
                "error_estimate": self.error_estimate,
                "converged": self.converged, "iterations": self.iterations,
                "status": self.status.name.lower()}


def shape_of(readout, x):
    """The shape read from a state x: the tangent angles ``rows @ x`` (radians), then the
    centreline's x and z at the points, r(s_i) = int_0^{s_i} (sin theta, cos theta) ds
    (``points`` @ (sin, cos) of theta at the fine quadrature nodes, ``to_quad @ x``)."""
    rows, to_quad, points = readout
    theta = to_quad @ x
    return jnp.concatenate([rows @ x, points @ jnp.sin(theta), points @ jnp.cos(theta)])


def l2_metric(disc) -> np.ndarray:
    """G^-1 with G G^T = M, M_ij = int_0^1 phi_i phi_j ds (the L2 Gram matrix of the free
    nodal values): the eigenvalues of G^-1 H G^-T solve H v = lambda M v, the second
    variation per unit int dtheta^2 ds, independent of N (pi^2 / 4 for the unloaded
    clamped-free rod of unit stiffness)."""
    return np.linalg.inv(np.linalg.cholesky(np.asarray(disc.mass_matrix())))


def l2_smallest(hessian, metric):
    """The smallest eigenvalue of the Hessian in the L2 norm (``l2_metric``)."""
    return jnp.linalg.eigvalsh(metric @ hessian @ metric.T)[0]


def lowest(r, lam):
    """The least of lam(r) sampled at increasing r: the smallest sample, or below it the
    vertex of the parabola through it and its two neighbours (an interior dip between
    samples)."""
    if lam.shape[0] < 3:
        return jnp.min(lam)
    i = jnp.clip(jnp.argmin(lam), 1, lam.shape[0] - 2)
    (x0, x1, x2), (y0, y1, y2) = (r[i - 1], r[i], r[i + 1]), \
        (lam[i - 1], lam[i], lam[i + 1])
    d1, d2 = (y1 - y0) / (x1 - x0), (y2 - y1) / (x2 - x1)
    a = (d2 - d1) / (x2 - x0)
    b = d1 - a * (x0 + x1)
    safe = jnp.where(a > 0.0, a, 1.0)
    vertex = y0 - a * x0**2 - b * x0 - b**2 / (4.0 * safe)
    inside = (a > 0.0) & (-b / (2.0 * safe) > x0) & (-b / (2.0 * safe) < x2)
    return jnp.minimum(jnp.min(lam), jnp.where(inside, vertex, jnp.inf))


@jit
def _smallest_along(path, disc, metric, states, scales, inputs):
    """``l2_smallest`` at each state and load scale of the path's inputs."""
    return jax.vmap(lambda x, r: l2_smallest(
        MODEL.hessian(x, 0.0, (path, disc, r, 1.0, inputs)), metric))(states, scales)


def _ramped(scene, n: int, at=None):
    """(load scales, states, stable all the way) of the ramp of ``scene``'s loads from zero
    to full (the branch in ``load_scale``, its points up to 1); ``at``: only the states
    first met at or past those load scales."""
    up = branch(scene, "load_scale", 0.0, 1.0, n=n, throw=False)
    on = up.value <= 1.0  # the branch's last step may pass the full load
    if at is not None:
        idx = [int(np.argmax(up.value >= r)) for r in at]
        return up.value[idx], up.theta[idx], bool(np.all(up.stable[on]))
    return up.value[on], up.theta[on], bool(np.all(up.stable[on]))


def _program(path, disc, x0, p0, free, cases, ramp, metric, readout, target, sigma, smoothing,
             rough, limits, magnets, margin, max_iter):
    """The least squares over p (the path's inputs after the load scale, scaled by |p0|)
    from the equilibria x0 (K, R, m) of the K load cases at the R load scales ``ramp``
    (the last 1: the design's) at p0: case k sets the path's last inputs to ``cases[k]``;
    target (K, shape size) and sigma (shape size) in the units of ``shape_of``; limits =
    (A, lo, hi): lo <= A p <= hi (the bounds of inputs and of profiles' values); ``rough``
    p: the profiles' roughness residuals;
    ``magnets``: term name -> (its radius in rod lengths at the start, its exponents in the
    path's inputs)."""
    unit = jnp.where(p0 == 0.0, 1.0, jnp.abs(p0))
    start = jnp.concatenate([p0, cases[0]])

    def clear(q):
        """Every magnet beyond the rod's reach at the inputs q (free, then the case's)."""
        scene = path.at(jnp.concatenate([jnp.ones(1), q]))
        safe = jnp.where(start == 0.0, 1.0, start)
        gaps = [jnp.linalg.norm(scene.terms[t].centre()) - 1.0
                - radius * jnp.prod(jnp.where(k == 0, 1.0, (q / safe) ** k))
                for t, (radius, k) in magnets.items()]
        return jnp.all(jnp.stack(gaps) > 0.0) if gaps else jnp.asarray(True)

    def solve(p, x, case, scale):
        args = lambda q: (path, disc, scale, 1.0, jnp.concatenate([q, case]))
        ok = clear(jnp.concatenate([p, case]))
        x_new, stats = implicit_newton(
            lambda y, q: MODEL.gradient(y, 0.0, args(q)), x, p, tol=1e-12,
            jacobian=lambda y, q: MODEL.hessian(y, 0.0, args(q)))
        smallest = l2_smallest(MODEL.hessian(x_new, 0.0, args(p)), metric)
        # stable only, and continued: a step that moves the rod by more than MAX_JUMP
        # would leave the branch the design follows (the line search shortens it)
        near = jnp.max(jnp.abs(x_new - x)) <= MAX_JUMP
        return x_new, ok & (stats[0] == 1.0) & (smallest > 0.0) & near, smallest

    along_ramp = jax.vmap(solve, (None, 0, None, 0))
    every = jax.vmap(along_ramp, (None, 0, 0, None))

    def residuals(u, x):
        p = u * unit
        x_new, ok, smallest = every(p, x, cases, ramp)
        A, lo, hi = limits
        ok = jnp.all(ok) & jnp.all((A @ p >= lo) & (A @ p <= hi))
        shapes = jax.vmap(lambda y: shape_of(readout, y))(x_new[:, -1])
        r = ((shapes - target) / sigma).reshape(-1)
        least = jnp.concatenate([smallest, jax.vmap(lambda lam: lowest(ramp, lam))(
            smallest)[:, None]], axis=1) if ramp.shape[0] >= 3 else smallest
        short = (MARGIN_WEIGHT * jnp.maximum(margin - least, 0.0) * (margin > 0.0))
        return jnp.concatenate([r, short.reshape(-1), smoothing * (u - p0 / unit) * free,
                                rough @ p]), x_new, ok

    res = least_squares_run(forward_mode(residuals), p0 / unit, x0, free,
                            target.size + x0.shape[0] * (x0.shape[1] + (
                                x0.shape[1] >= 3)) + p0.shape[0] + rough.shape[0], True,
                            max_iter)
    return res._replace(p=res.p * unit, J=res.J / unit)


_design_program = jit(_program, static_argnames=("max_iter",))


def design_shape(scene: Scene | FileScene, free, s, target_deg=None, n: int = DEFAULT_N,
                 bounds: dict | None = None, sigma_deg: float = 1.0, smoothing: float = 0.0,
                 max_iter: int = 80, cases: dict | None = None, margin: float = 0.0, *,
                 target_xz=None, sigma_length: float = 0.01,
                 roughness: float = 0.0) -> ShapeDesign:
    """The inputs ``free`` (keys) of a planar scene or rig whose equilibrium's tangent angle
    at ``s`` is ``target_deg`` and (or) whose centreline passes through ``target_xz``
    ((len(s), 2): x and z in rod lengths from the clamp; a tip pose is s = [1] with both)
    (module docstring). The scene's values of the free inputs are the start; ``bounds``:
    key -> (lo, hi), an input's, or a profile's values along s by its list's key
    (``magnetisation.strength_profile``: mu(s), at 101 points; every coefficient free);
    ``smoothing`` > 0 pulls the inputs towards the start (relative); ``roughness`` > 0
    penalises each profile of free coefficients by roughness^2 int_0^1 f''(s)^2 ds (its
    values' units, beside residuals in sigmas); ``sigma_deg`` and
    ``sigma_length`` scale the residuals. ``cases``: several load cases at once, key -> its
    K values (e.g. two field directions, {"field.0.angle_deg": [90, 45]}), with one target
    row per case (``target_deg`` (K, len(s)), ``target_xz`` (K, len(s), 2)). ``margin`` >
    0: a stability margin, ``l2_smallest`` at least ``margin`` along the whole ramp of the
    loads from zero to the design in every case (a penalty
    ``MARGIN_WEIGHT`` (margin - lambda_min) at ``RAMP_POINTS`` load scales where it falls
    short; ``margin_met`` says whether it holds to ``MARGIN_TOLERANCE`` of it at every
    point of the continued ramp, ``path_smallest_eigenvalue``). A target no design reaches
    returns ``converged`` True with its shape error (the least-squares answer), never an
    error."""
    inner = scene.scene if isinstance(scene, FileScene) else scene
    if inner.geometry != "planar":
        raise ParameterError("scene: shape targets are shapes of a planar rod "
                             f"(geometry = \"planar\"), got {inner.geometry!r}")
    free = tuple(free)
    if not free or len(set(free)) != len(free):
        raise ParameterError(f"free: one or more distinct inputs, got {free}")
    case_keys, case_values = _cases(cases, free)
    K = len(case_values)
    s = np.asarray(s, float).reshape(-1)
    angles, points = _targets(s, target_deg, target_xz, K)
    check_value("sigma_deg", sigma_deg, lambda v: v > 0, "a number > 0")
    check_value("sigma_length", sigma_length, lambda v: v > 0, "a number > 0 (rod lengths)")
    check_value("smoothing", smoothing, lambda v: v >= 0, "a number >= 0")
    check_value("roughness", roughness, lambda v: v >= 0, "a number >= 0")
    check_value("margin", margin, lambda v: v >= 0, "a number >= 0 (the smallest eigenvalue "
                "of the second variation per unit int dtheta^2 ds to keep)")
    path = along(scene, ("load_scale", *free, *case_keys))
    p0 = np.asarray(path.start[1:1 + len(free)], float)
    limits = bound_rows(dict(bounds or {}), free, p0)
    rough = roughness * roughness_rows(free) if roughness > 0 else np.zeros((0, len(free)))
    at_case = lambda sc, k: with_values(sc, dict(zip(case_keys, case_values[k])))
    ramp = np.linspace(1.0, 0.0, RAMP_POINTS, endpoint=False)[::-1] if margin > 0 else \
        np.ones(1)
    starts = []
    for k in range(K):
        full = equilibrium(at_case(scene, k), n=n, throw=False)
        if not full.converged:
            raise ParameterError(f"scene: its equilibrium at the start (load case {k}) did "
                                 f"not converge ({full.status.message})")
        on_way = list(_ramped(at_case(scene, k), n, ramp[:-1])[1]) if ramp.size > 1 else []
        starts.append([*on_way, full.state])
    disc = discretise(path.template, n)
    metric = l2_metric(disc)
    readout = _readout(disc, s, angles is not None, points is not None)
    n_a, n_p = (0 if angles is None else s.size), (0 if points is None else s.size)
    target = np.concatenate([np.radians(angles) if n_a else np.zeros((K, 0)),
                             points[..., 0] if n_p else np.zeros((K, 0)),
                             points[..., 1] if n_p else np.zeros((K, 0))], axis=1)
    sigma = np.r_[np.full(n_a, math.radians(sigma_deg)), np.full(2 * n_p, sigma_length)]
    res = jax.device_get(_design_program(
        path, disc, jnp.asarray(np.array(starts)), jnp.asarray(p0), jnp.ones(p0.size, bool),
        jnp.asarray(case_values), jnp.asarray(ramp), jnp.asarray(metric),
        tuple(map(jnp.asarray, readout)),
        jnp.asarray(target), jnp.asarray(sigma), float(smoothing), jnp.asarray(rough),
        tuple(jnp.asarray(v) for v in limits),
        magnet_margins(scene, free + case_keys, np.r_[p0, case_values[0]]), float(margin),
        max_iter))
    # a direction's angle is periodic: the design's, within half a turn of the start's
    values = {k: float(v - 360.0 * round((v - v0) / 360.0)) if k.endswith("angle_deg")
              else float(v) for k, v, v0 in zip(free, res.p, p0)}
    designed = with_values(scene, values)
    x = np.asarray(res.aux)[:, -1]
    shapes = np.array([np.asarray(shape_of(readout, jnp.asarray(xk))) for xk in x])
    tangent = np.degrees(shapes[:, :n_a])
    xz = np.stack([shapes[:, n_a:n_a + n_p], shapes[:, n_a + n_p:]], axis=-1)
    eig, path_eig, reachable = math.inf, math.inf, True
    for k in range(K):
        inputs = jnp.concatenate([res.p, case_values[k]])
        eig = min(eig, float(_smallest_along(path, disc, metric, x[k:k + 1], np.ones(1),
                                             inputs)[0]))
        ramped = equilibrium(at_case(designed, k), n=n, throw=False)
        scales, states, stable = _ramped(at_case(designed, k), n)
        path_eig = min(path_eig, float(lowest(jnp.asarray(scales), _smallest_along(
            path, disc, metric, jnp.asarray(states), jnp.asarray(scales), inputs))))
        reachable &= bool(ramped.converged) and stable and float(
            np.max(np.abs(ramped.state - x[k]))) <= 1e-8
    path_eig = min(path_eig, eig)
    converged = bool(res.converged) and bool(res.ok)
    error_estimate = tail_estimate(disc, x)
    status = Status.NOT_CONVERGED if not converged else (
        Status.UNDER_RESOLVED if error_estimate > TOLERANCE else Status.SUCCESS)
    one = (lambda a: a[0]) if cases is None else (lambda a: a)
    error = float(np.max(np.abs(tangent - angles))) if n_a else None
    miss = float(np.max(np.hypot(*np.moveaxis(xz - points, -1, 0)))) if n_p else None
    reached = (error is None or error <= REACHED * sigma_deg) and \
        (miss is None or miss <= REACHED * sigma_length)
    A, lo, hi = limits
    held = A @ np.asarray(res.p)
    # the line search rejects points beyond a bound: it stops short of it by its last step
    at_bound = bool(np.any(np.minimum(held - lo, hi - held)
                           <= 1e-3 * np.maximum(1.0, np.abs(held))))
    said = ([f"the largest shape error is {error:.3g} deg"] if n_a else []) + \
        ([f"the centreline misses its points by up to {miss:.3g} rod lengths"] if n_p else [])
    reason = "" if reached else (
        f"the target is not reached: {' and '.join(said)} ("
        + ("the design stops at its bounds" if at_bound else
           "the margin or the profiles' degree keep the design from it") + ")")
    return ShapeDesign(values=values, s=s, target_deg=None if not n_a else one(angles),
                       tangent_deg=None if not n_a else one(tangent),
                       shape_error_deg=error, target_xz=None if not n_p else one(points),
                       xz=None if not n_p else one(xz), position_error=miss,
                       reached=reached, reason=reason,
                       stable=eig > 0.0, smallest_eigenvalue=eig, reachable=bool(reachable),
                       path_smallest_eigenvalue=path_eig,
                       margin_met=path_eig >= margin * (1.0 - MARGIN_TOLERANCE),
                       converged=converged, iterations=int(res.iterations),
                       error_estimate=error_estimate, status=status,
                       scene=designed, state=one(x), n=int(n))


def _targets(s, target_deg, target_xz, K: int):
    """(angles (K, len(s)) or None, points (K, len(s), 2) or None), checked."""
    if target_deg is None and target_xz is None:
        raise ParameterError("target: give the tangent angles (target_deg) or the "
                             "centreline's points (target_xz), or both")
    angles = None if target_deg is None else np.atleast_2d(np.asarray(target_deg, float))
    points = None if target_xz is None else np.asarray(target_xz, float)
    if points is not None and points.ndim == 2:
        points = points[None]
    fewest = MIN_POINTS if points is None else 1
    if (angles is not None and angles.shape != (K, s.size)) or \
            (points is not None and points.shape != (K, s.size, 2)) or s.size < fewest:
        raise ParameterError(
            f"target: at least {MIN_POINTS} points (s, tangent_deg), or one with the "
            f"centreline's (x, z) (a tip: s = [1]), one row per load case ({K}) of len(s) = "
            f"{s.size}, got angles {np.shape(target_deg)}, points {np.shape(target_xz)}")
    if not (np.all(np.isfinite(s)) and all(np.all(np.isfinite(a)) for a in (angles, points)
                                             if a is not None)):
        raise ParameterError("target: s, the angles and the points must be finite (no NaN)")
    if np.any((s < 0.0) | (s > 1.0)):
        raise ParameterError(f"target: s must lie in [0, 1], got {s.min():g} to {s.max():g}")
    return angles, points


def _readout(disc, s, angles: bool, points: bool) -> tuple:
    """``shape_of``'s matrices at the points s: the tangent's interpolation, the fine
    nodes' interpolation, the centreline's integration there (empty rows where not asked)."""
    to_quad = np.asarray(disc.to_quad)
    fine = to_quad.shape[0] - 1
    rows = spectral.interpolation_matrix(disc.n, s) @ np.asarray(disc.to_full)
    cumulative = spectral.interpolation_matrix(fine, s) @ \
        spectral.cumulative_integration_matrix(fine)
    return (rows if angles else rows[:0], to_quad, cumulative if points else cumulative[:0])


#: The load scales (of RAMP_POINTS, evenly spaced up to 1) where a margin is kept.
RAMP_POINTS = 8


#: A shape within this many sigma of the target everywhere is reached.
REACHED = 1e-6


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


def centreline(design: ShapeDesign, s) -> tuple[np.ndarray, np.ndarray]:
    """(x, z) of the designed equilibrium's centreline at s (rod lengths from the clamp; the
    first load case's), r(s) = int_0^s (sin theta, cos theta) ds."""
    x = np.asarray(design.state)
    x = x[0] if x.ndim == 2 else x
    inner = design.scene.scene if isinstance(design.scene, FileScene) else design.scene
    disc = discretise(inner, design.n)
    shape = np.asarray(shape_of(_readout(disc, np.asarray(s, float), False, True),
                                jnp.asarray(x)))
    return shape[:len(shape) // 2], shape[len(shape) // 2:]
