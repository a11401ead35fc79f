"""A scene: the energy terms a set-up needs, composed into one energy.

    E[d3] = sum over density terms   int_0^1 rho_t(d3, d3', s) ds
          + sum over endpoint terms  Psi_t(X),                 X = int_0^1 d3 ds
          + sum over distributed terms  Q_t(r, d3),            r(s) = int_0^s d3

(``jaxrod.scenes.terms``), on the planar rod (d3 = sin(theta) e1 + cos(theta) e3, unknowns
theta) or the 3D rod (d3 on the sphere, ``jaxrod.discretise.director``). The scene provides
what ``jaxrod.derivatives.Structured`` assembles the exact derivatives from: ``density(a, s)``
of the discretisation's jet a, ``tip_map(a)`` (d3) and ``endpoint(X)``; distributed terms
are added as a whole (``distributed_energy``).

Inputs are named by dotted keys: ``"gravity.G"``, ``"magnet.alpha"``, ``"field.direction.0"``
(a term's name in the scene, then its field, then an index into a vector field). Every input
is a traced leaf: a new value never recompiles, and any input can be the continuation
parameter (``Input``). ``load_scale`` multiplies every term except the rod's own (elastic)
energy: the ramp from the unloaded straight rod (``jaxrod.equilibria``) continues in it.
"""

from __future__ import annotations

import dataclasses
import math
from functools import lru_cache
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from jaxrod import spectral
from jaxrod.discretise.director import director_jet

GEOMETRIES = ("planar", "3d")


class SceneError(ValueError):
    """A scene or an input key that does not exist (the message names it)."""


def planar_jet(a):
    """(d3, d3') at one node from the planar jet a = (theta, theta')."""
    s, c = jnp.sin(a[0]), jnp.cos(a[0])
    zero = jnp.zeros_like(s)
    return jnp.stack([s, zero, c]), a[1] * jnp.stack([c, zero, -s])


@jax.tree_util.register_dataclass
@dataclasses.dataclass(frozen=True)
class Scene:
    """Named energy terms on a rod of one geometry and support.

    ``terms``: name -> term (``jaxrod.scenes.terms``); the names make the input keys.
    ``load_scale`` multiplies every non-elastic term (1: the loads as given). ``geometry``:
    "planar" (unknowns theta) or "3d" (the director chart); ``support``: "clamped" or
    "pinned"; both static.
    """

    terms: dict[str, Any]
    load_scale: jax.Array | float = 1.0
    geometry: str = dataclasses.field(default="planar", metadata=dict(static=True))
    support: str = dataclasses.field(default="clamped", metadata=dict(static=True))

    def __post_init__(self):
        if not isinstance(self.terms, dict):
            return  # rebuilt by a JAX transformation with placeholder leaves
        if self.geometry not in GEOMETRIES:
            raise SceneError(f"geometry must be one of {GEOMETRIES}, got {self.geometry!r}")
        for name, t in self.terms.items():
            if not isinstance(name, str) or not name.isidentifier():
                raise SceneError(f"a term's name must be an identifier, got {name!r}")
            if self.geometry == "3d" and getattr(t, "planar_only", False):
                raise SceneError(f"the term {name!r} has no 3D form (planar rods only)")

    # -- the structure that jaxrod.derivatives.Structured assembles --------------------------

    def _jet(self, a):
        return planar_jet(a) if self.geometry == "planar" else director_jet(a)

    def _scale(self, t):
        return 1.0 if t.elastic else self.load_scale

    def _of_kind(self, kind):
        return [t for t in self.terms.values() if getattr(t, kind) is not None]

    def density(self, a, s):
        """Sum of the density terms at one node, from the jet a (on the planar rod, a term's
        ``planar`` form where it has one)."""
        terms = self._of_kind("density")
        planar = self.geometry == "planar"
        if planar and all(t.planar is not None for t in terms):
            return sum(self._scale(t) * t.planar(a[0], a[1], s) for t in terms)
        d3, dd3 = self._jet(a)
        return sum(self._scale(t) * (t.planar(a[0], a[1], s) if planar and t.planar is not None
                                     else t.density(d3, dd3, s)) for t in terms)

    @property
    def _planar_tip(self) -> bool:
        """The tip as (X1, X3): a planar rod whose endpoint terms all have a planar form."""
        return self.geometry == "planar" and all(
            t.planar_endpoint is not None for t in self._of_kind("endpoint"))

    @property
    def tip_map(self):
        """The integrand of the tip position, d3(a) (or its in-plane components (sin theta,
        cos theta) on the planar rod when every endpoint term has a planar form), or None
        without endpoint terms."""
        if not self._of_kind("endpoint"):
            return None
        if self._planar_tip:
            return lambda a: jnp.stack([jnp.sin(a[0]), jnp.cos(a[0])])
        return lambda a: self._jet(a)[0]

    def endpoint(self, X):
        """Sum of the endpoint potentials at the tip X (``tip_map``'s components)."""
        if self._planar_tip:
            return sum(self._scale(t) * t.planar_endpoint(X) for t in self._of_kind("endpoint"))
        return sum(self._scale(t) * t.endpoint(X) for t in self._of_kind("endpoint"))

    @property
    def has_distributed(self) -> bool:
        return bool(self._of_kind("distributed"))

    def directors(self, x, disc):
        """d3 at the quadrature nodes of the state x, (n_q, 3)."""
        a = jnp.einsum("jrm,m->jr", disc.jet_matrix, x)
        return jax.vmap(lambda aj: self._jet(aj)[0])(a)

    def curvatures(self, x, disc):
        """The curvature vectors kappa = d3 x d3' at the quadrature nodes, (n_q, 3) (on the
        planar rod (0, theta', 0)): what the Kelvin-Voigt damping acts on."""
        a = jnp.einsum("jrm,m->jr", disc.jet_matrix, x)
        return jax.vmap(lambda aj: jnp.cross(*self._jet(aj)))(a)

    def positions(self, x, disc, d3=None):
        """r(s_j) = int_0^{s_j} d3 at the quadrature nodes (rod lengths), (n_q, 3)."""
        d3 = self.directors(x, disc) if d3 is None else d3
        return jnp.asarray(_cumulative(d3.shape[0] - 1)) @ d3

    def distributed_energy(self, x, disc):
        """Sum of the distributed terms at the state x (0 without them)."""
        terms = self._of_kind("distributed")
        if not terms:
            return jnp.zeros((), x.dtype)
        d3 = self.directors(x, disc)
        r = self.positions(x, disc, d3)
        s, w = disc.quad_nodes, disc.quad_weights
        return sum(self._scale(t) * t.distributed(r, d3, s, w) for t in terms)

    def energy(self, x, disc):
        """The whole discrete energy at x, term by term (the reference for the assembled
        derivatives)."""
        a = jnp.einsum("jrm,m->jr", disc.jet_matrix, x)
        s, w = disc.quad_nodes, disc.quad_weights
        e = jnp.dot(w, jax.vmap(self.density)(a, s)) if self._of_kind("density") else 0.0
        if self.tip_map is not None:
            e = e + self.endpoint(jnp.einsum("j,jk->k", w, jax.vmap(self.tip_map)(a)))
        return e + self.distributed_energy(x, disc)

    # -- inputs by name ------------------------------------------------------------------

    def inputs(self) -> list[str]:
        """Every scalar input's key, in the terms' order ("gravity.G", "field.direction.0"...)."""
        keys = []
        for name, t in self.terms.items():
            for f in dataclasses.fields(t):
                v = np.shape(getattr(t, f.name))
                if v == ():
                    keys.append(f"{name}.{f.name}")
                elif len(v) == 1:
                    keys += [f"{name}.{f.name}.{i}" for i in range(v[0])]
        return keys

    def _locate(self, key: str):
        parts = key.split(".")
        if key == "load_scale":
            return None, None, None
        if len(parts) not in (2, 3) or parts[0] not in self.terms:
            raise SceneError(_unknown(key, self))
        t = self.terms[parts[0]]
        names = [f.name for f in dataclasses.fields(t)]
        if parts[1] not in names:
            raise SceneError(_unknown(key, self))
        index = None
        if len(parts) == 3:
            size = np.shape(getattr(t, parts[1]))
            if not parts[2].isdigit() or len(size) != 1 or int(parts[2]) >= size[0]:
                raise SceneError(_unknown(key, self))
            index = int(parts[2])
        elif np.ndim(getattr(t, parts[1])) != 0:
            raise SceneError(f"{key} is not a scalar input: name one component "
                             f"({key}.0, {key}.1, ...)")
        return parts[0], parts[1], index

    def value(self, key: str):
        """The input named ``key``."""
        name, field, index = self._locate(key)
        if name is None:
            return self.load_scale
        v = getattr(self.terms[name], field)
        return v if index is None else v[index]

    def replace(self, key: str, value) -> Scene:
        """A copy with the input ``key`` set to ``value`` (traceable)."""
        name, field, index = self._locate(key)
        if name is None:
            return dataclasses.replace(self, load_scale=value)
        t = self.terms[name]
        if index is not None:
            value = jnp.asarray(getattr(t, field)).at[index].set(value)
        terms = dict(self.terms)
        terms[name] = dataclasses.replace(t, **{field: value})
        return dataclasses.replace(self, terms=terms)

    def clearance(self, margins: dict | None = None) -> float:
        """How far the nearest magnet's centre lies beyond the rod's reach, in rod lengths:
        min over the terms with a ``centre()`` of |c| - 1 - margin (``margins``: term name ->
        the magnet's radius, 0 by default); +inf without magnets. Negative: a magnet the
        rod can touch, where the energy is singular. Host side (concrete inputs)."""
        margins = margins or {}
        gaps = [d - 1.0 - margins.get(name, 0.0) for name, d in self.magnet_distances().items()]
        return min(gaps, default=math.inf)

    def magnet_distances(self) -> dict:
        """|centre| of every term with a ``centre()`` (a magnet), by name, in rod lengths:
        one small program per scene structure (host side, concrete inputs)."""
        magnets = {name: t for name, t in self.terms.items() if hasattr(t, "centre")}
        if not magnets:
            return {}
        # float64 leaves: Python floats (weak types) would compile a second program
        magnets = jax.tree_util.tree_map(lambda v: np.asarray(v, np.float64), magnets)
        return {name: float(d) for name, d in _centre_norms(magnets).items()}

    def check_key(self, key: str) -> str:
        """``key`` if it names a scalar input, else a ``SceneError`` naming it."""
        self._locate(key)
        return key


def _unknown(key: str, scene: Scene) -> str:
    import difflib

    keys = scene.inputs() + ["load_scale"]
    near = difflib.get_close_matches(key, keys, n=1)
    hint = f" (did you mean {near[0]}?)" if near else ""
    return f"{key!r} is not an input of this scene{hint}; its inputs: {', '.join(keys)}"


@jax.jit
def _centre_norms(magnets: dict) -> dict:
    return {name: jnp.linalg.norm(t.centre()) for name, t in magnets.items()}


@lru_cache(maxsize=16)
def _cumulative(degree: int) -> np.ndarray:
    """int_0^{s_j} on the Chebyshev quadrature grid of this degree."""
    return spectral.cumulative_integration_matrix(degree)


@dataclasses.dataclass(frozen=True)
class Input:
    """``scene_at`` for ``jaxrod.derivatives.Structured``: the continuation parameter lam is
    the input ``key`` on the affine scale value = origin + span * lam, with args = (scene,
    disc, origin, span). The scale makes every input's range [0, 1] for the step control
    (a field in tesla and an angle in radians are then stepped alike)."""

    key: str

    def __call__(self, lam, args):
        scene, disc, origin, span = args
        return scene.replace(self.key, origin + span * lam), disc
