"""A path through a scene's inputs: the scene as a function of a few named parameters p.

Every scalar input of a scene (its leaves, flattened: the terms' fields and ``load_scale``)
is a product of powers of the parameters,

    leaf_i(p) = b_i + c_i * prod_j p_j ** k_ij,        k_ij integers in [-3, 3],

where an input that no parameter moves keeps b_i (c_i = 0) and a moved one has b_i = 0.
A scene input named by its key (``"gravity.G"``) moves as leaf = p (c = 1, k = 1 there).
A rig file's key enters the scene's inputs (nondimensional groups) as a product of powers,
by dimensional analysis: Young's modulus as 1/E in the gravity group, the load and the
dipole group; the rod's length as L^3 in G, L^2 in the load, 1/L in M and in the magnet's
distance. The exponents are read off the rig built at two nearby values of the key (a ratio
of 1.01 and 1/1.01), rounded to integers and checked to round-off against both builds;
a key that does not enter as a product of powers is refused, naming it.

b, c and k are traced leaves: the scene a program sees is ``Path.at(p)``, so one compiled
program serves every key of a scene (a program is keyed by the scene's structure, the
number of parameters and N, never by the key).
"""

from __future__ import annotations

import dataclasses
import math

import jax
import jax.numpy as jnp
import numpy as np

from jaxrod.params import ParameterError
from jaxrod.scenes.scene import Scene

#: The exponents a parameter may carry (beyond them a key is not a physical input).
POWERS = range(-3, 4)
#: The relative step of the builds that read off a rig key's exponents.
PROBE = 1.01


def _flat(scene: Scene) -> np.ndarray:
    return np.concatenate([np.ravel(np.asarray(v, np.float64))
                           for v in jax.tree_util.tree_leaves(scene)])


def _entry(scene: Scene, key: str) -> int:
    """The position of the input ``key`` in the scene's flattened leaves."""
    scene.check_key(key)
    marker = jax.tree_util.tree_map(lambda v: np.zeros(np.shape(v)), scene)
    marker = marker.replace(key, 1.0)
    return int(np.flatnonzero(_flat(marker))[0])


@dataclasses.dataclass(frozen=True)
class Path:
    """The scene as a function of parameters p (module docstring): ``template`` gives the
    structure (its leaves are not read), ``base``, ``coef`` (S,) and ``powers`` (S, P) the
    map. ``keys`` names the parameters and ``start`` holds their values at the template
    (host side only: they are not part of the pytree, so programs are keyed by the
    structure, never by the key)."""

    template: Scene
    base: jax.Array
    coef: jax.Array
    powers: jax.Array
    keys: tuple = ()
    start: tuple = ()

    def value(self, key: str) -> float:
        """The parameter ``key``'s value at the template."""
        return self.start[self.keys.index(key)]

    def at(self, p) -> Scene:
        """The scene at the parameter values p, shape (P,) (traceable)."""
        p = jnp.asarray(p, jnp.float64).reshape(-1)
        safe = jnp.where(p == 0.0, 1.0, p)  # negative powers are never chosen at p = 0
        table = jnp.stack([(safe if k < 0 else p) ** k for k in POWERS], axis=-1)  # (P, 7)
        # the power of each entry picked by a one-hot product (exact: ones and zeros)
        pick = (self.powers[..., None] == jnp.arange(POWERS.start, POWERS.stop)).astype(p.dtype)
        factors = jnp.einsum("spk,pk->sp", pick, table)                 # (S, P)
        flat = self.base + self.coef * jnp.prod(factors, axis=1)
        leaves, treedef = jax.tree_util.tree_flatten(self.template)
        out, start = [], 0
        for leaf in leaves:
            size = int(np.size(leaf))
            out.append(flat[start:start + size].reshape(np.shape(leaf)))
            start += size
        return jax.tree_util.tree_unflatten(treedef, out)

    def at_host(self, *p) -> Scene:
        """The scene at concrete parameter values, with numpy leaves (host side)."""
        p = np.asarray(p, np.float64).reshape(-1)
        k = np.asarray(self.powers)
        with np.errstate(divide="ignore"):
            factors = np.where(k == 0, 1.0, p[None, :] ** k)
        flat = np.asarray(self.base) + np.asarray(self.coef) * np.prod(factors, axis=1)
        leaves, treedef = jax.tree_util.tree_flatten(self.template)
        cuts = np.cumsum([np.size(v) for v in leaves])[:-1]
        return jax.tree_util.tree_unflatten(treedef, [
            part.reshape(np.shape(v)) for part, v in zip(np.split(flat, cuts), leaves)])

    def loading(self, p) -> Path:
        """The path of this one's structure along the load scale (its first parameter; the
        others move nothing) of the scene at the parameter values p: the loads' ramp there
        (traceable; ``Scene.load_scale`` is one of the flattened leaves)."""
        flat = still_path(self.at(p)).base
        i = _entry(self.template, "load_scale")
        return Path(self.template, flat.at[i].set(0.0), jnp.zeros_like(flat).at[i].set(1.0),
                    jnp.zeros_like(self.powers).at[i, 0].set(1.0))

    def moved_terms(self) -> set[str]:
        """The names of the terms whose inputs the path moves (host side)."""
        moved = np.asarray(self.coef) != 0.0
        names, start = set(), 0
        for key_path, leaf in jax.tree_util.tree_flatten_with_path(self.template)[0]:
            size = int(np.size(leaf))
            if moved[start:start + size].any() and len(key_path) > 1:
                names.add(key_path[1].key)
            start += size
        return names


jax.tree_util.register_pytree_node(
    Path, lambda p: ((p.template, p.base, p.coef, p.powers), None),
    lambda _, children: Path(*children))


@dataclasses.dataclass(frozen=True)
class Along:
    """``scene_at`` for ``jaxrod.derivatives.Structured``: the continuation parameter lam is
    the path's first parameter on the affine scale p_0 = origin + span * lam (so that every
    input's range is [0, 1] for the step control), the others held at ``rest``: args =
    (path, disc, origin, span, rest)."""

    def __call__(self, lam, args):
        path, disc, origin, span, rest = args
        return path.at(jnp.concatenate([jnp.reshape(origin + span * lam, (1,)), rest])), disc


#: The one scene_at of every path (hashable: equal programs are shared).
ALONG = Along()


def scene_path(scene: Scene, keys) -> Path:
    """The path along the scene inputs ``keys`` (each moves as leaf = p_j); with no keys, a
    path of one parameter that moves nothing (the scene as it is)."""
    keys = tuple(keys)
    base = _flat(scene)
    coef = np.zeros_like(base)
    powers = np.zeros((base.size, max(len(keys), 1)))
    for j, key in enumerate(keys):
        i = _entry(scene, key)
        if coef[i] != 0.0:
            raise ParameterError(f"{key}: named twice")
        base[i], coef[i], powers[i, j] = 0.0, 1.0, 1.0
    start = tuple(float(np.asarray(scene.value(k))) for k in keys)
    return Path(scene, jnp.asarray(base), jnp.asarray(coef), jnp.asarray(powers), keys, start)


def still_path(scene: Scene) -> Path:
    """The path of one parameter that moves nothing: the scene as it is (traceable, its
    inputs may be traced)."""
    flat = jnp.concatenate([jnp.ravel(jnp.asarray(v, jnp.float64))
                            for v in jax.tree_util.tree_leaves(scene)])
    return Path(scene, flat, jnp.zeros_like(flat), jnp.zeros((flat.size, 1)))


def exponents(build, value: float, key: str) -> np.ndarray:
    """The integer exponents k_i with which the key enters each input of the scene that
    ``build(v)`` makes (module docstring): read off the builds at value * 1.01 and
    value / 1.01 and checked to round-off; ParameterError naming ``key`` otherwise."""
    if value == 0.0 or not math.isfinite(value):
        raise ParameterError(f"{key}: {value:g} cannot be varied as a physical input (it "
                             "enters as a power, and is zero here)")
    at = _flat(build(value))
    up, down = _flat(build(value * PROBE)), _flat(build(value / PROBE))
    if not (at.shape == up.shape == down.shape):
        raise ParameterError(f"{key}: changes the scene's structure; it cannot be varied")
    k = np.zeros(at.shape)
    moved = (up != at) | (down != at)
    with np.errstate(divide="ignore", invalid="ignore"):
        k[moved] = np.round(np.log(np.abs(up[moved] / at[moved])) / math.log(PROBE))
    ok = np.isfinite(k) & np.isin(k, list(POWERS))
    ok &= np.isclose(up, at * PROBE**k, rtol=1e-11, atol=0.0)
    ok &= np.isclose(down, at * PROBE**-k, rtol=1e-11, atol=0.0)
    if not ok.all():
        raise ParameterError(f"{key}: does not enter the scene's inputs as a product of "
                             "powers; it cannot be varied")
    return k


def monomial_path(template: Scene, keys, values, linear: dict, builds: dict) -> Path:
    """The path along rig keys: ``values`` their values at ``template``; ``linear``: key ->
    (scene key, factor) for the keys that enter one input in proportion (factor: that
    input's value per unit of the key); ``builds``: key -> ``build(v)`` of the scene for
    the other keys (their exponents are read off, ``exponents``)."""
    keys = tuple(keys)
    leaf = _flat(template)
    base, coef = leaf.copy(), leaf.copy()
    powers = np.zeros((leaf.size, len(keys)))
    targets = {}
    for j, key in enumerate(keys):
        if key in linear:
            i = _entry(template, linear[key][0])
            targets[i] = linear[key][1]
            powers[i, j] = 1.0
        else:
            powers[:, j] = exponents(builds[key], values[j], key)
    for i, factor in targets.items():
        coef[i] = factor
    for j, key in enumerate(keys):
        if key not in linear:
            coef /= np.asarray(values[j], float) ** powers[:, j]
    moved = powers.any(axis=1)
    base[moved], coef[~moved] = 0.0, 0.0
    return Path(template, jnp.asarray(base), jnp.asarray(coef), jnp.asarray(powers), keys,
                tuple(float(v) for v in values))


def _entry_of(data, key: str):
    """The number at the dotted ``key`` of a parsed rig file, or None."""
    node = data
    for part in key.split("."):
        if isinstance(node, list) and part.isdigit() and int(part) < len(node):
            node = node[int(part)]
        elif isinstance(node, dict) and part in node:
            node = node[part]
        else:
            return None
    if isinstance(node, bool) or not isinstance(node, (int, float)):
        return None
    return float(node)


def numeric_keys(data, prefix: str = "") -> list[str]:
    """Every number's dotted key in a parsed rig file (``rod.youngs_modulus``,
    ``field.0.position.1``...)."""
    items = data.items() if isinstance(data, dict) else enumerate(data) \
        if isinstance(data, list) else ()
    keys = []
    for k, v in items:
        if isinstance(v, (dict, list)):
            keys += numeric_keys(v, f"{prefix}{k}.")
        elif isinstance(v, (int, float)) and not isinstance(v, bool):
            keys.append(f"{prefix}{k}")
    return keys


def rig_path(rig, keys) -> Path:
    """The path of a rig read from a file (``jaxrod.scenes.files.FileScene``) along ``keys``:
    any number of the file (in its units: ``rod.youngs_modulus``, ``rod.length``,
    ``field.0.diameter``, ``field.0.B``...) or an input of its scene (``gravity.G``)."""
    from jaxrod.scenes.files import apply_settings, scene_from

    linear, builds, values = {}, {}, []
    scene_keys = set(rig.scene.inputs()) | {"load_scale"}
    for key in keys:
        if key in rig.inputs:
            linear[key] = rig.inputs[key]
            values.append(rig.value(key))
        elif key in scene_keys:
            linear[key] = (key, 1.0)
            values.append(float(np.asarray(rig.scene.value(key))))
        elif (value := _entry_of(rig.data, key)) is not None:
            builds[key] = lambda v, key=key: scene_from(
                apply_settings(rig.data, [f"{key}={float(v)!r}"])).scene
            values.append(value)
        else:
            import difflib

            valid = list(rig.inputs) + [k for k in numeric_keys(rig.data)
                                        if k not in rig.inputs]
            near = difflib.get_close_matches(key, valid + sorted(scene_keys), n=1)
            hint = f" (did you mean {near[0]!r}?)" if near else ""
            raise ParameterError(f"{key!r} is not a number of this rig{hint}; its numbers: "
                                 f"{', '.join(valid)}")
    return monomial_path(rig.scene, keys, values, linear, builds)


def along(scene, keys) -> Path:
    """The path of a ``Scene`` or a rig read from a file along ``keys``."""
    return scene_path(scene, keys) if isinstance(scene, Scene) else rig_path(scene, keys)
