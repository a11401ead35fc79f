"""Permanent magnet on a circle: bifurcation diagram, folds and hysteresis (paper, section
"Permanent Magnet on Sphere").

Pipeline: ``trace_diagram`` follows the planar equilibria from the straight rod at alpha = 0
in both directions by pseudo-arclength continuation (engaged branch, upper fold, unstable
middle branch, lower fold, disengaged branch); ``locate_folds`` refines each detected fold by
the Moore-Spence system and reports the normal form (``jaxrod.magnet.folds``);
``hysteresis_sweep`` runs the experiment's quasi-static protocol and ``square_root_law``
fits the exponent of |tip - tip*| ~ |alpha - alpha*|^(1/2) next to a fold
(``jaxrod.magnet.sweep``). This module: the scene, the diagram's options and program, and
the equilibria at one magnet angle.

Everything is in radians internally; results carry degrees where the name says ``_deg``.
"""

from __future__ import annotations

import math

import jax
import jax.numpy as jnp
import numpy as np

from jaxrod.discretise.planar import PlanarDiscretisation, planar_discretisation
from jaxrod.equilibria.record import Branch, branch_from_runs
from jaxrod.params import check, check_degree, check_track_clearance
from jaxrod.programs import jit
from jaxrod.scenes.dipole import ALPHA_MODEL, DipoleMagnet, tip_angle
from jaxrod.solvers.continuation import ContinuationOptions, continuation_run
from jaxrod.solvers.newton import newton
from jaxrod.stored import StoredProgram

#: Default Chebyshev degree. At the paper's parameters the fold angles reach their round-off
#: floor (~1e-11 degrees) from N = 12 (docs/accuracy.md); 16 keeps a margin.
#: Small clearances D - 1 need more (benchmarks/extreme.py).
DEFAULT_N = 16


def alpha_energy(theta, alpha, args):
    """E_perm(theta) at magnet angle alpha; args = (scene, disc). The continuation energy."""
    scene, disc = args
    return scene.with_alpha(alpha).energy(theta, disc)


def make_scene(G: float, M: float, D: float, magnet_radius: float | None = None) -> DipoleMagnet:
    """Validated scene. ``magnet_radius`` (a/L) refuses magnets the rod could touch.

    The scene is ``DipoleMagnet(G, M, D, alpha=0)``, energy E_perm of eq.
    ``permanent_magnet_energy_reduced`` (paper); D > 1 + a/L keeps the magnet off the rod.
    """
    check("G-magnet", G)
    check("M", M)
    check_track_clearance(D, 0.0 if magnet_radius is None else magnet_radius)
    return DipoleMagnet(float(G), float(M), float(D), 0.0)


def _observables_of(theta, alpha, scene: DipoleMagnet, disc: PlanarDiscretisation):
    """(q, tip angle, energy) at rows of theta and alpha (NaN rows stay NaN)."""
    one = lambda th, a: (disc.mean(th), tip_angle(th, disc),
                         ALPHA_MODEL.energy(th, a, (scene, disc)))
    return jax.vmap(one)(theta, alpha)


def default_options(max_points: int = 400) -> ContinuationOptions:
    """Step control of the diagram: steps of at most 0.1 in arclength, alpha in [-90, 90]."""
    return ContinuationOptions(ds=0.05, ds_min=1e-8, ds_max=0.1, lam_min=-math.pi / 2,
                               lam_max=math.pi / 2, tol=1e-12, max_points=max_points)


#: The largest step of a diagram drawn for a figure: about five times denser than the
#: default, so that the curves are smooth through the folds. ``ds_max`` is traced, so the
#: dense diagram reuses the compiled program.
FIGURE_DS_MAX = 0.02


def figure_options() -> ContinuationOptions:
    """``default_options`` with steps of at most ``FIGURE_DS_MAX`` (for plotting)."""
    return default_options()._replace(ds_max=FIGURE_DS_MAX)


def _diagram_program(scene: DipoleMagnet, disc: PlanarDiscretisation,
                     options: ContinuationOptions, capacity: int):
    # the straight rod is an equilibrium at alpha = 0 (mirror symmetry; see fold_guesses)
    trace = lambda d: continuation_run(ALPHA_MODEL, jnp.zeros(disc.size), 0.0, (scene, disc),
                                       options, capacity, d)
    runs = jax.vmap(trace)(jnp.array([-1.0, 1.0]))
    observed = jax.vmap(lambda th, a: _observables_of(th, a, scene, disc))(runs.x, runs.lam)
    return runs, observed


_diagram = StoredProgram("magnet-diagram", _diagram_program, static_argnames=("capacity",))


def _alpha_residual(theta, args):
    alpha, scene, disc = args
    return ALPHA_MODEL.gradient(theta, alpha, (scene, disc))


def _alpha_jacobian(theta, args):
    alpha, scene, disc = args
    return ALPHA_MODEL.hessian(theta, alpha, (scene, disc))


@jit
def _equilibrium(theta0, alpha, scene: DipoleMagnet, disc: PlanarDiscretisation):
    """Newton for the equilibrium at magnet angle alpha from theta0 (compiled once)."""
    return newton(_alpha_residual, theta0, (alpha, scene, disc), tol=1e-13,
                  jacobian=_alpha_jacobian)


def trace_diagram(scene: DipoleMagnet, n: int = DEFAULT_N,
                  options: ContinuationOptions | None = None) -> Branch:
    """The whole planar diagram for alpha in [-90, 90] degrees through the straight rod.

    One compiled program runs both directions from (theta, alpha) = (0, 0) (vmapped).

    Equilibria solve grad E_perm(theta; alpha) = 0, the discrete planar Euler-Lagrange
    equation. Paper: Lemma ``thm:planar_equilibria`` (eq. ``planar_EL``), Corollary
    ``cor:planar_branch``.
    """
    disc = planar_discretisation(check_degree(n, "N-magnet"), "clamped")
    options = options or default_options()
    runs, observed = jax.device_get(  # index on the host
        _diagram(scene, disc, options._replace(max_points=0), options.max_points))
    if not np.all(runs.residual_norm[:, 0] <= options.tol):
        raise RuntimeError("the straight rod is not an equilibrium at alpha = 0 (residual "
                           f"{np.max(runs.residual_norm[:, 0]):.3g}): the scene is not "
                           "mirror-symmetric there")
    left, right = (jax.tree_util.tree_map(lambda v, i=i: v[i], (runs, observed))
                   for i in (0, 1))
    return branch_from_runs([(left[0], True, left[1]), (right[0], False, right[1])])


def equilibria_at(scene: DipoleMagnet, branch: Branch, alpha: float,
                  n: int = DEFAULT_N) -> tuple[np.ndarray, np.ndarray]:
    """(states, stable) of every equilibrium of the diagram ``branch`` at the magnet angle
    ``alpha`` (radians): Newton at alpha from the branch point before each crossing (the
    equilibria of grad E_perm(theta; alpha) = 0 on the traced branch)."""
    disc = planar_discretisation(check_degree(n, "N-magnet"), "clamped")
    a = branch.alpha
    crossing = np.nonzero((a[:-1] - alpha) * (a[1:] - alpha) <= 0.0)[0]
    states, stable = [], []
    for i in crossing:
        res = _equilibrium(branch.theta[i], alpha, scene, disc)
        if bool(res.converged):
            states.append(np.asarray(res.x))
            stable.append(bool(branch.stable[i] and branch.stable[i + 1]))
    return np.array(states).reshape(-1, disc.size), np.array(stable, bool)
