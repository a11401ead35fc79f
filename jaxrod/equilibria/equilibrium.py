"""The equilibrium of a scene under its loads, reached by ramping them from zero.

The ramp is pseudo-arclength continuation in the load scale t (``Scene.load_scale``) of

    grad E_t(x) = 0,   E_t = E_elastic + t (E - E_elastic),   t: 0 -> 1,

from the straight unloaded rod x = 0 (an equilibrium of the bending energy alone), stopped at
the first fold; the state at t = 1 is then polished by Newton (or, if the ramp folded first,
reached by energy descent at t = 1 from the fold: the snap). Stability is the sign of the
Hessian's smallest eigenvalue (the discrete second variation).
"""

from __future__ import annotations

import dataclasses
import math

import jax
import jax.numpy as jnp
import numpy as np

from jaxrod.derivatives import Structured
from jaxrod.discretise.director import director_discretisation
from jaxrod.discretise.planar import planar_discretisation
from jaxrod.params import check_degree
from jaxrod.programs import jit
from jaxrod.scenes.checks import check_scene
from jaxrod.scenes.files import FileScene
from jaxrod.scenes.scene import Input, Scene
from jaxrod.solvers.continuation import (
    FOLDS_FOUND,
    REACHED_BOUND,
    ContinuationOptions,
    continuation_run,
)
from jaxrod.solvers.descent import descend
from jaxrod.solvers.newton import newton
from jaxrod.status import Status, check

#: Default Chebyshev degree of the generic analyses (the paper's scenes converge to round-off
#: from N = 12; 16 keeps a margin).
DEFAULT_N = 16

#: The load scale as continuation parameter.
LOAD = Structured(Input("load_scale"))

#: Steps of at most 0.05 in the load scale's arclength: near an imperfect pitchfork (a field
#: almost opposite a hard-magnetic rod's magnetisation, with gravity) steps of 0.2 cut the
#: branch's sharp turn and land on the unstable near-straight branch.
RAMP_OPTIONS = ContinuationOptions(ds=0.05, ds_min=1e-8, ds_max=0.05, lam_max=1.0, tol=1e-12,
                                   max_folds=1, max_points=0)
RAMP_CAPACITY = 200


def discretise(scene: Scene, n: int):
    """The discretisation of degree n for the scene's geometry and support (a ``Scene`` or a
    rig read from a file)."""
    n = check_degree(n)
    scene = getattr(scene, "scene", scene)
    if scene.geometry == "planar":
        return planar_discretisation(n, scene.support)
    return director_discretisation(n, scene.support)


def mean_functional(disc):
    """q = int of the (first) angle: the reduced coordinate of the normal forms."""
    if hasattr(disc, "mean"):
        return disc.mean
    return lambda x: disc.planar.mean(disc.split(x)[0])


def tip(scene: Scene, x, disc):
    """(tip angle from +z toward +x in radians, tip position X = int d3 (3-vector))."""
    X = scene.directors(x, disc).T @ disc.quad_weights
    return jnp.arctan2(X[0], X[2]), X


def tip_tangent(scene: Scene, x, disc):
    """The angle of the tangent d3(1) at the tip from +z toward +x (radians): the rotation of
    the tip (the hard-magnetic elastica's tip angle); ``tip`` gives the direction of the tip
    position, the paper's tip angle."""
    d3 = scene._jet(disc.jet_matrix[-1] @ x)[0]  # the last quadrature node is s = 1
    return jnp.arctan2(d3[0], d3[2])


def _residual(x, args):
    lam, model, margs = args
    return model.gradient(x, lam, margs)


def _jacobian(x, args):
    lam, model, margs = args
    return model.hessian(x, lam, margs)


def solve_at(model, x0, lam, args, tol=1e-12):
    """Newton for grad E(x, lam) = 0 from x0 (traceable)."""
    return newton(_residual, x0, (lam, model, args), tol=tol, jacobian=_jacobian)


def loaded(model, run, args, snapped):
    """The state at full load (lam = 1) from a run of the loads' ramp: where it folded
    (``snapped``) the energy descended from the fold (the snap), else the run's last two
    points interpolated to lam = 1 (Newton's start there; traceable)."""
    k = run.num_points - 1
    j = jnp.maximum(k - 1, 0)
    w = jnp.clip((1.0 - run.lam[j]) / (run.lam[k] - run.lam[j]), 0.0, 1.0)
    x_mid = run.x[j] + w * (run.x[k] - run.x[j])
    return jax.lax.cond(snapped, lambda x: descend(model, x, args, lam=1.0).x, lambda x: x,
                        jnp.where(snapped, run.x[k], x_mid))


def ramp(scene: Scene, disc) -> tuple:
    """(x, converged, residual, iterations, status code) at full load (traceable)."""
    args = (scene, disc, 0.0, 1.0)
    x0 = jnp.zeros(disc.size, disc.quad_weights.dtype)
    run = continuation_run(LOAD, x0, 0.0, args, RAMP_OPTIONS, RAMP_CAPACITY, 1.0,
                           spectrum=False)
    snapped = run.status == FOLDS_FOUND
    reached = run.status == REACHED_BOUND
    res = solve_at(LOAD, loaded(LOAD, run, args, snapped), 1.0, args)
    status = jnp.where(~res.converged, int(Status.NOT_CONVERGED),
                       jnp.where(snapped, int(Status.SNAPPED_WHILE_LOADING),
                                 jnp.where(reached, int(Status.SUCCESS),
                                           int(Status.NOT_CONVERGED))))
    return res.x, res.converged, res.residual_norm, res.iterations, status


@dataclasses.dataclass(frozen=True)
class Equilibrium:
    """An equilibrium of a scene: the state and what it means.

    ``tip_angle_deg``: the direction of the tip position X = int_0^1 d3 ds (rod lengths,
    ``tip_position``) from +z toward +x (the paper's tip angle); ``tip_tangent_deg``: the
    tangent's angle at the tip from +z toward +x (the tip's rotation); ``stable``: the
    Hessian's smallest eigenvalue is positive; ``converged``: the final Newton solve
    converged and ``status`` is a success (a ramp that stopped short of full load is not
    converged, whatever Newton did from where it stopped).
    """

    state: np.ndarray
    tip_angle_deg: float
    tip_position: np.ndarray
    tip_tangent_deg: float
    energy: float
    smallest_eigenvalue: float
    stable: bool
    converged: bool
    residual_norm: float
    iterations: int
    status: Status

    @property
    def message(self) -> str:
        return self.status.message

    def as_dict(self) -> dict:
        return {"tip_angle_deg": self.tip_angle_deg,
                "tip_position": [float(v) for v in self.tip_position],
                "tip_tangent_deg": self.tip_tangent_deg, "energy": self.energy,
                "smallest_eigenvalue": self.smallest_eigenvalue, "stable": self.stable,
                "converged": self.converged, "residual_norm": self.residual_norm,
                "iterations": self.iterations, "status": self.status.name.lower(),
                "message": self.message}


def _given(lam, args):
    return args


#: The scene's energy as it is (lam unused).
FIXED = Structured(_given)


def _report(scene, disc, x):
    model = FIXED
    H = model.hessian(x, 0.0, (scene, disc))
    angle, X = tip(scene, x, disc)
    return (angle, X, tip_tangent(scene, x, disc), model.energy(x, 0.0, (scene, disc)),
            jnp.linalg.eigvalsh(H)[0])


@jit
def _ramped(scene, disc):
    x, conv, res, it, status = ramp(scene, disc)
    return (x, conv, res, it, status), _report(scene, disc, x)


@jit
def _continued(scene, disc, x0):
    res = solve_at(FIXED, x0, 0.0, (scene, disc))
    status = jnp.where(res.converged, int(Status.SUCCESS), int(Status.NOT_CONVERGED))
    return (res.x, res.converged, res.residual_norm, res.iterations, status), \
        _report(scene, disc, res.x)


def equilibrium(scene: Scene | FileScene, n: int = DEFAULT_N, state=None,
                throw: bool = True) -> Equilibrium:
    """The equilibrium of ``scene`` (a ``Scene`` or a rig from ``jaxrod.load_scene``) reached
    by ramping its loads from zero, or continued from ``state`` (a state of the same
    discretisation) when given.

    Solves grad E(x) = 0 (the discrete Euler-Lagrange equations of the scene's energy,
    ``jaxrod.scenes.scene``). The inputs are checked first (``jaxrod.scenes.checks``: a
    non-finite input or a magnet within the rod's reach is a ``ParameterError`` naming
    it). ``throw``: raise ``SolverError`` if it does not converge (else the status says so).
    """
    margins = None
    if isinstance(scene, FileScene):
        scene, margins = scene.scene, scene.margins
    check_scene(scene, margins)
    disc = discretise(scene, n)
    if state is None:
        (x, conv, res, it, status), rep = jax.device_get(_ramped(scene, disc))
    else:
        x0 = jnp.asarray(state, jnp.float64)
        if x0.shape != (disc.size,):
            raise ValueError(f"state has shape {x0.shape}; this discretisation needs "
                             f"({disc.size},)")
        (x, conv, res, it, status), rep = jax.device_get(_continued(scene, disc, x0))
    code = check(status, throw, "equilibrium")
    angle, X, tangent, energy, eig = rep
    return Equilibrium(state=np.asarray(x), tip_angle_deg=math.degrees(float(angle)),
                       tip_position=np.asarray(X), tip_tangent_deg=math.degrees(float(tangent)),
                       energy=float(energy),
                       smallest_eigenvalue=float(eig), stable=bool(eig > 0),
                       converged=bool(conv) and code.ok, residual_norm=float(res),
                       iterations=int(it),
                       status=code)
