"""Out-of-plane stability of a planar equilibrium of any scene.

A planar equilibrium theta(s) of a scene is also an equilibrium of the same scene on the 3D
rod (its terms are written in the director, ``jaxrod.scenes.terms``). The 3D Hessian there
(the director discretisation's exponential chart, ``jaxrod.discretise.director``; assembled
from the terms, ``jaxrod.derivatives``) splits into blocks [H11 H12; H21 H22] for the
in-plane and out-of-plane unknowns (the paper's Lemma "Planar splitting of the full second
variation": H12 = 0 when the scene is symmetric under e2 -> -e2). Its smallest eigenvalues,
in the metrics of ``jaxrod.three_d.outofplane`` (int a^2 in-plane; int b^2 out of plane,
b = sinc(theta) v2), say whether the rod leaves the plane.
"""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp

from jaxrod.discretise.director import director_discretisation
from jaxrod.equilibria.equilibrium import DEFAULT_N, FIXED, discretise
from jaxrod.params import ParameterError
from jaxrod.programs import jit
from jaxrod.scenes.scene import Scene
from jaxrod.solvers.eigen import smallest_generalised_eigenvalue
from jaxrod.three_d.outofplane import _sinc


@dataclasses.dataclass(frozen=True)
class OutOfPlane:
    """``min_eig_plane`` and ``min_eig_perp``: the smallest eigenvalues of the in-plane and
    out-of-plane blocks; ``coupling``: max |H12|; ``stable_out_of_plane``: min_eig_perp > 0;
    ``smallest_is_in_plane``: the in-plane eigenvalue is the smaller one (in magnitude)."""

    min_eig_plane: float
    min_eig_perp: float
    coupling: float

    @property
    def stable_out_of_plane(self) -> bool:
        return self.min_eig_perp > 0.0

    @property
    def smallest_is_in_plane(self) -> bool:
        return abs(self.min_eig_plane) < abs(self.min_eig_perp)

    def as_dict(self) -> dict:
        return {"min_eig_plane": self.min_eig_plane, "min_eig_perp": self.min_eig_perp,
                "coupling": self.coupling, "stable_out_of_plane": self.stable_out_of_plane}


@jit
def _blocks(scene3, ddisc, theta):
    disc = ddisc.planar
    x = ddisc.from_planar(theta)
    H = FIXED.hessian(x, 0.0, (scene3, ddisc))
    m = disc.size
    P, w = disc.to_quad, disc.quad_weights
    th, _ = disc.at_quadrature(theta)
    W_b = P.T @ ((w * _sinc(th) ** 2)[:, None] * P)
    return (smallest_generalised_eigenvalue(H[:m, :m], disc.mass_matrix()),
            smallest_generalised_eigenvalue(H[m:, m:], W_b), jnp.max(jnp.abs(H[:m, m:])))


def out_of_plane_stability(scene: Scene, state, n: int = DEFAULT_N) -> OutOfPlane:
    """The out-of-plane check at the planar equilibrium ``state`` (free nodal values of the
    planar discretisation of degree ``n``, e.g. ``jr.equilibrium(scene, n).state``) of the
    planar ``scene`` (module docstring)."""
    if scene.geometry != "planar":
        raise ParameterError("scene: give the planar scene whose equilibrium this is")
    planar_only = [name for name, t in scene.terms.items() if getattr(t, "planar_only", False)]
    if planar_only:
        raise ParameterError(f"scene: the term {planar_only[0]!r} has no 3D form")
    disc = discretise(scene, n)
    theta = jnp.asarray(state, jnp.float64)
    if theta.shape != (disc.size,):
        raise ParameterError(f"state has shape {theta.shape}; degree {n} needs ({disc.size},)")
    scene3 = dataclasses.replace(scene, geometry="3d")
    ddisc = director_discretisation(n, scene.support)
    plane, perp, coupling = (float(v) for v in jax.device_get(_blocks(scene3, ddisc, theta)))
    return OutOfPlane(plane, perp, coupling)


