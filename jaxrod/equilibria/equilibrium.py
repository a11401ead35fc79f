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
from jaxrod.scenes.checks import check_scene
from jaxrod.scenes.files import FileScene
from jaxrod.scenes.path import ALONG, scene_path
from jaxrod.scenes.scene import Scene
from jaxrod.solvers.continuation import (
    FOLDS_FOUND,
    REACHED_BOUND,
    ContinuationOptions,
    continuation_run,
)
from jaxrod.solvers.descent import descend
from jaxrod.solvers.newton import newton
from jaxrod.status import Status, check
from jaxrod.stored import StoredProgram

#: Default Chebyshev degree of the generic analyses (the paper's scenes converge to round-off
#: from N = 12; 16 keeps a margin).
DEFAULT_N = 16

#: Steps of at most 0.05 in the load scale's arclength: near an imperfect pitchfork (a field
#: almost opposite a hard-magnetic rod's magnetisation, with gravity) steps of 0.2 cut the
#: branch's sharp turn and land on the unstable near-straight branch.
RAMP_OPTIONS = ContinuationOptions(ds=0.05, ds_min=1e-8, ds_max=0.05, lam_max=1.0, tol=1e-12,
                                   max_folds=1, max_points=0)
#: Points of a run (the ramp's and the branch's) in ``path_program``.
CAPACITY = 400
#: The equilibrium's run along the load scale past full load ends at its first step: the
#: program's second run (``run_from_rest``) reports the equilibrium at its origin.
STAY = ContinuationOptions(ds=0.01, ds_min=1e-9, ds_max=0.05, lam_min=0.0, lam_max=0.0,
                           tol=1e-12, max_points=0)


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


def _linearise(x, args):
    lam, model, margs = args
    return model.gradient_and_hessian(x, lam, margs)


def solve_at(model, x0, lam, args, tol=1e-12):
    """Newton for grad E(x, lam) = 0 from x0 (traceable): the gradient and the Hessian from
    one assembly, in one place of the program."""
    return newton(None, x0, (lam, model, args), tol=tol, linearise=_linearise)


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


#: The equilibria's model along a path (``jaxrod.scenes.path``): one for every key.
MODEL = Structured(ALONG)
NO_REST = np.zeros(0)


def observe(path, disc, x, lam, origin, span, rest=NO_REST):
    """(q, tip angle, energy, tip position) at a point (x, lam) of a branch (traceable)."""
    args = (path, disc, origin, span, rest)
    at, _ = ALONG(lam, args)
    angle, X = tip(at, x, disc)
    return mean_functional(disc)(x), angle, MODEL.energy(x, lam, args), X


def run_from_rest(path, disc, origin, span, opts, capacity, rest=NO_REST, x0=None,
                  given=False, spectrum=True):
    """The continuation run along the path from the equilibrium at its ``origin`` (lam = 0),
    Newton's answer there and the ramp's status code (``SUCCESS``; ``SNAPPED_WHILE_LOADING``
    where it folded; else ``NOT_CONVERGED``; traceable): that equilibrium is Newton's from
    ``x0`` where ``given``, else from the state reached by ramping the loads from zero
    (``RAMP_OPTIONS``; where the ramp folds, the energy descended at full load:
    ``loaded``). The ramp is the same continuation on the path along the load scale
    (``Path.loading``), the two runs one ``lax.scan``: the program compiles it once."""
    ramp_path = path.loading(jnp.concatenate([jnp.reshape(origin, (1,)), rest]))
    stack = lambda *v: jnp.stack([jnp.asarray(u, jnp.float64) for u in v])
    phases = (jax.tree_util.tree_map(stack, ramp_path, path), stack(0.0, origin),
              stack(1.0, span), jax.tree_util.tree_map(stack, RAMP_OPTIONS, opts),
              jnp.array([False, True]))
    x0 = jnp.zeros(disc.size) if x0 is None else x0

    def phase(x, data):
        p, o, sp, op, main = data
        args = (p, disc, o, sp, rest)
        start = solve_at(MODEL, x, 0.0, args)
        run = continuation_run(MODEL, start.x, 0.0, args, op, capacity, 1.0, spectrum)
        ramped = loaded(MODEL, run, args, (run.status == FOLDS_FOUND) & ~main)
        return jnp.where(given, x0, ramped), (run, start)

    _, (runs, starts) = jax.lax.scan(phase, jnp.zeros(disc.size), phases)
    ramp_status = runs.status[0]
    code = jnp.where(given | (ramp_status == REACHED_BOUND), int(Status.SUCCESS),
                     jnp.where(ramp_status == FOLDS_FOUND, int(Status.SNAPPED_WHILE_LOADING),
                               int(Status.NOT_CONVERGED)))
    run, start = jax.tree_util.tree_map(lambda v: v[1], (runs, starts))
    return run, start, code


def given_state(state, disc) -> tuple[jax.Array, bool]:
    """(x0, given): a state given to start from, checked against the discretisation, or
    zeros (the ramp starts from the straight rod) and False."""
    given = state is not None
    x0 = jnp.asarray(state if given else np.zeros(disc.size), jnp.float64)
    if x0.shape != (disc.size,):
        raise ValueError(f"state has shape {x0.shape}; this discretisation needs "
                         f"({disc.size},)")
    return x0, given


def _path_program(path, disc, origin, span, x0, given, opts, capacity):
    """The run along the path from the equilibrium at its origin (``run_from_rest``), its
    points observed (q, tip angle, energy; tip position), and at the origin: Newton's
    report, the ramp's status code and the tip's tangent angle."""
    run, start, ramp_code = run_from_rest(path, disc, origin, span, opts, capacity, x0=x0,
                                          given=given)
    q, angle, energy, X = jax.vmap(
        lambda x, lam: observe(path, disc, x, lam, origin, span))(run.x, run.lam)
    tangent = tip_tangent(ALONG(0.0, (path, disc, origin, span, NO_REST))[0], start.x, disc)
    return run, (q, angle, energy), X, (start.converged, start.residual_norm,
                                         start.iterations, ramp_code, tangent)


#: The one program of a scene's structure and N along any path: the equilibrium
#: (``equilibrium``), the branch (``jaxrod.equilibria.trace``) and the fold guesses.
path_program = StoredProgram("path", _path_program, static_argnames=("capacity",))


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
    x0, given = given_state(state, disc)
    run, (_, angle, energy), X, (conv, res, it, ramp_code, tangent) = jax.device_get(
        path_program(scene_path(scene, ("load_scale",)), disc, 1.0, 1.0, x0, given, STAY,
                     CAPACITY))
    status = int(ramp_code) if bool(conv) else int(Status.NOT_CONVERGED)
    code = check(status, throw, "equilibrium")
    eig = float(run.min_eig[0])
    return Equilibrium(state=np.asarray(run.x[0]), tip_angle_deg=math.degrees(float(angle[0])),
                       tip_position=np.asarray(X[0]),
                       tip_tangent_deg=math.degrees(float(tangent)), energy=float(energy[0]),
                       smallest_eigenvalue=eig, stable=eig > 0,
                       converged=bool(conv) and code.ok, residual_norm=float(res),
                       iterations=int(it), status=code)
