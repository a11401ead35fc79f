"""Magnet tracks that leave the plane: 3D equilibria of the permanent-magnet scene.

The magnet centre moves on the sphere of radius D along a great circle

    p(t) = cos(t) p0 + sin(t) e,     p0 = (sin a0, 0, cos a0),
    e = cos(tilt) (cos a0, 0, -sin a0) + sin(tilt) e2,

which starts in the experiment's plane at polar angle a0 and leaves it at the angle ``tilt``
(tilt = 0: the planar track alpha = a0 + t; tilt = 90 degrees: towards e2). Along it the rod
is a 3D state d3(s) on the director discretisation (``jaxrod.discretise.director``), and the
branch of equilibria of

    E(v; t) = 1/2 int |d3'|^2 + G int (1 - s) d3 . e3 + M Phi_p(t)(int d3)

in the track parameter t is traced by the package's pseudo-arclength continuation
(``jaxrod.solvers.continuation``) and its folds refined by the package's Moore-Spence solver
(``jaxrod.solvers.folds``): the planar solvers, unchanged, on the 3D discretisation.

Check against the planar theory: gravity and the clamp are symmetric about e3, so the
equilibrium for a magnet at polar angle a(t) and azimuth b(t) is the planar one at a(t)
rotated by b(t) about e3 (the rod leans towards the magnet's azimuth). The rod therefore
snaps off where a(t) reaches the planar upper fold angle, whatever the track.
"""

from __future__ import annotations

import dataclasses
import math

import jax
import jax.numpy as jnp
import numpy as np

from jaxrod.discretise.director import DirectorDiscretisation, director_discretisation
from jaxrod.equilibria.equilibrium import mean_functional
from jaxrod.equilibria.record import Branch, SpecialPoint, branch_from_runs
from jaxrod.params import check, check_degree
from jaxrod.programs import jit
from jaxrod.scenes.dipole import DipoleMagnet
from jaxrod.scenes.three_d import DipoleMagnet3D, magnet_position
from jaxrod.solvers.continuation import ContinuationOptions, continuation_run
from jaxrod.solvers.descent import descend
from jaxrod.solvers.folds import moore_spence_solve
from jaxrod.status import Status


@jax.tree_util.register_dataclass
@dataclasses.dataclass(frozen=True)
class GreatCircleTrack:
    """p(t) = cos(t) start + sin(t) towards (orthonormal unit 3-vectors)."""

    start: jax.Array
    towards: jax.Array

    def position(self, t):
        return jnp.cos(t) * self.start + jnp.sin(t) * self.towards


def tilted_track(alpha0_deg: float, tilt_deg: float) -> GreatCircleTrack:
    """The great circle through the in-plane position at polar angle alpha0, leaving the
    plane at angle ``tilt`` to the meridian (0: the planar track; 90: heading along e2).

    Paper: beyond its planar setting; the magnet stays on the sphere of radius D of eq.
    ``permanent_magnet_energy``.
    """
    a = math.radians(check("alpha0", alpha0_deg))
    b = math.radians(check("tilt", tilt_deg))
    meridian = jnp.array([math.cos(a), 0.0, -math.sin(a)])
    return GreatCircleTrack(magnet_position(a), math.cos(b) * meridian
                            + math.sin(b) * jnp.array([0.0, 1.0, 0.0]))


def track_energy(x, t, args):
    """E(v; t) of the module docstring; args = (scene, track, disc)."""
    scene, track, disc = args
    return DipoleMagnet3D(scene.G, scene.M, scene.D, track.position(t)).energy(x, disc)


def _polar_azimuth(vec):
    """(polar angle from e3, azimuth from e1) of 3-vectors (last axis), radians (host)."""
    vec = np.asarray(vec)
    return (np.arctan2(np.hypot(vec[..., 0], vec[..., 1]), vec[..., 2]),
            np.arctan2(vec[..., 1], vec[..., 0]))


def _tip(x, disc: DirectorDiscretisation):
    d3, _ = disc.at_quadrature(x)
    return disc.integrate(d3.T)


@jit(static_argnames="capacity")
def _trace(scene: DipoleMagnet, track: GreatCircleTrack, disc: DirectorDiscretisation,
           options: ContinuationOptions, capacity: int):
    args = (scene, track, disc)
    # the rod settles from straight to the local minimum (Newton from straight can fail: the
    # straight rod is far from the engaged state when the magnet pulls hard)
    start = descend(lambda x, a: track_energy(x, 0.0, a), jnp.zeros(disc.size), args)
    raw = continuation_run(track_energy, start.x, 0.0, args, options, capacity, 1.0)
    q = mean_functional(disc)

    def observed(x, t):  # the Branch record's columns, and the tip position
        X = _tip(x, disc)
        return q(x), jnp.arctan2(X[0], X[2]), track_energy(x, t, args), X

    return start, raw, jax.vmap(observed)(jnp.nan_to_num(raw.x), raw.lam)


@jit
def _refine(x0, t0, scene: DipoleMagnet, track: GreatCircleTrack, disc: DirectorDiscretisation):
    args = (scene, track, disc)
    H = jax.hessian(track_energy)(x0, t0, args)
    _, V = jnp.linalg.eigh(H)
    fold = moore_spence_solve(track_energy, x0, t0, V[:, 0], args)
    m = x0.shape[0]  # the Hessian at the fold: the first block of its Moore-Spence Jacobian
    return fold, _tip(fold.x, disc), jnp.linalg.eigvalsh(fold.newton.jacobian[:m, :m])[:2]


@dataclasses.dataclass(frozen=True)
class TrackFold(SpecialPoint):
    """A fold of the 3D branch along the track, refined by Moore-Spence: a special point
    (``jaxrod.equilibria.record.SpecialPoint``, ``vary`` = "t", the track's parameter, and
    ``value`` in radians; ``tip_angle_deg`` the tip position's angle from +z toward +x, as
    for every special point and the branch's ``tip``) with the tip's polar angle from +z
    (``tip_polar_deg``: the lean of the tip whatever its azimuth; equal to ``tip_angle_deg``
    only in the xz-plane), the magnet's direction there, the rod's azimuth and the Hessian's
    two smallest eigenvalues."""

    tip_polar_deg: float
    magnet_polar_deg: float
    magnet_azimuth_deg: float
    rod_azimuth_deg: float
    hessian_smallest: tuple[float, float]

    @property
    def t_deg(self) -> float:
        return math.degrees(self.value)


@dataclasses.dataclass(frozen=True)
class TrackBranch(Branch):
    """3D equilibria along a magnet track: the ``Branch`` record (``jaxrod.equilibria.record``)
    in the track parameter (``vary`` = "t", ``value`` in radians; ``theta`` the chart unknowns
    [v1; v2]; ``q`` = int v1; ``tip`` the tip position's angle from +z toward +x, as for any
    3D scene, and ``tip_position`` X = int d3; ``stable``: Morse index 0), with the magnet's
    direction p(t) per point (``magnet``), the refined ``folds`` and the degree ``n``."""

    magnet: np.ndarray | None = None
    folds: tuple[TrackFold, ...] = ()
    n: int = 16

    @property
    def t_deg(self) -> np.ndarray:
        return np.degrees(self.value)

    @property
    def states(self) -> np.ndarray:
        """The chart unknowns [v1; v2] per point (``theta``)."""
        return self.theta

    @property
    def magnet_polar_deg(self) -> np.ndarray:
        return np.degrees(_polar_azimuth(self.magnet)[0])

    @property
    def magnet_azimuth_deg(self) -> np.ndarray:
        return np.degrees(_polar_azimuth(self.magnet)[1])

    @property
    def rod_azimuth_deg(self) -> np.ndarray:
        return np.degrees(_polar_azimuth(self.tip_position)[1])

    @property
    def out_of_plane(self) -> np.ndarray:
        """Largest |v2| per point: how far each state is from the experiment's plane."""
        m = self.states.shape[1] // 2
        return np.max(np.abs(self.states[:, m:]), axis=1)

    def centreline(self, i: int, points: int = 81) -> np.ndarray:
        """r(s) = int_0^s d3 of the i-th state at ``points`` even arclengths, (points, 3)."""
        disc = director_discretisation(self.n)
        return np.asarray(disc.centreline(jnp.asarray(self.states[i]),
                                          np.linspace(0.0, 1.0, points)))


def trace_track(scene: DipoleMagnet, alpha0_deg: float = 20.0, tilt_deg: float = 90.0,
                n: int = 16, t_max_deg: float = 60.0, max_points: int = 300) -> TrackBranch:
    """Follow the rod in 3D as the magnet moves along ``tilted_track(alpha0, tilt)`` from
    t = 0 (the local minimum reached from the straight rod) to t_max, through folds; each
    fold is refined.

    Energy: eq. ``permanent_magnet_energy`` of the paper with the magnet at D p(t) on the
    track; out-of-plane stability as in Proposition
    ``thm:conditional_out_of_plane_stability``.
    """
    check("t-max", t_max_deg)
    track = tilted_track(alpha0_deg, tilt_deg)
    disc = director_discretisation(check_degree(n, "N-magnet"))
    options = ContinuationOptions(ds=0.02, ds_min=1e-8, ds_max=0.05, lam_min=-1e-9,
                                  lam_max=math.radians(t_max_deg), tol=1e-12, max_points=0)
    start, raw, (q, tip, energy, X) = _trace(scene, track, disc, options, max_points)
    if not bool(start.converged):
        raise RuntimeError("no equilibrium reached at the track's start (energy descent: "
                           f"|grad| = {float(start.gradient_norm):.3g} after "
                           f"{int(start.iterations)} steps)")
    branch = branch_from_runs([(raw, False, (q, tip, energy))])
    k = len(branch)
    t, x, tangent = branch.value, branch.theta, branch.tangent_value
    folds = []
    for i in branch.fold_indices:
        j = i if abs(tangent[i]) < abs(tangent[i + 1]) else i + 1
        fold, tip, eigs = _refine(jnp.asarray(x[j]), t[j], scene, track, disc)
        p = track.position(fold.lam)
        a, b = _polar_azimuth(p)
        tip_polar, tip_azimuth = _polar_azimuth(tip)
        conv = bool(fold.newton.converged)
        folds.append(TrackFold(
            vary="t", value=float(fold.lam),
            tip_angle_deg=math.degrees(math.atan2(float(tip[0]), float(tip[2]))),
            tip_polar_deg=math.degrees(float(tip_polar)),
            tip_position=np.asarray(tip), state=np.asarray(fold.x),
            null_vector=np.asarray(fold.null_vector), converged=conv,
            residual_norm=float(fold.newton.residual_norm),
            iterations=int(fold.newton.iterations), status=Status.of(conv),
            magnet_polar_deg=math.degrees(float(a)), magnet_azimuth_deg=math.degrees(float(b)),
            rod_azimuth_deg=math.degrees(float(tip_azimuth)),
            hessian_smallest=tuple(float(e) for e in eigs)))
    fields = {f.name: getattr(branch, f.name) for f in dataclasses.fields(Branch)}
    return TrackBranch(**fields | {"vary": "t", "tip_position": np.asarray(X)[:k]},
                       magnet=np.asarray(jax.vmap(track.position)(jnp.asarray(t))),
                       folds=tuple(folds), n=n)
