"""Checks of a scene's concrete inputs, once, before any work: one clear error naming the input.

Every input must be finite (a NaN or an infinity names its key), and every magnet's centre
must lie beyond the rod's reach (|c| > 1 + the magnet's radius, in rod lengths: at or
inside it the energy is singular and a solver would return NaN or a wrong answer as
converged). A rig read from a file is checked by building it (``jaxrod.scenes.files``:
signs, units and ranges of every number, with the file's key named).
"""

from __future__ import annotations

import jax
import numpy as np

from jaxrod.params import ParameterError


def _key(key_path) -> str:
    parts = []
    for k in key_path:
        parts.append(str(getattr(k, "key", getattr(k, "name", getattr(k, "idx", k)))))
    return ".".join(p for p in parts if p != "terms")


def check_scene(scene, margins: dict | None = None, where: str = "") -> None:
    """ParameterError naming the input if ``scene`` (concrete inputs) has a non-finite input
    or a magnet within the rod's reach (``margins``: the magnets' radii by term name, rod
    lengths). ``where``: what the message says of the values (a point of a range)."""
    at = f" at {where}" if where else ""
    for key_path, leaf in jax.tree_util.tree_flatten_with_path(scene)[0]:
        if isinstance(leaf, jax.core.Tracer):
            return  # traced: checked where it was concrete
        if not np.all(np.isfinite(np.asarray(leaf, float))):
            raise ParameterError(f"{_key(key_path)}: must be finite{at}, got {leaf}")
    margins = margins or {}
    for name, c in scene.magnet_distances().items():
        if c - 1.0 - margins.get(name, 0.0) <= 0.0:
            raise ParameterError(
                f"{name}: the magnet's centre is {c:.6g} rod lengths from the clamp{at}, "
                f"within the rod's reach (it must lie farther than "
                f"{1.0 + margins.get(name, 0.0):.6g}: the rod's length plus the magnet's "
                "radius)")


def rebuild(rig, key: str, value: float):
    """The rig read from a file built anew with its number ``key`` set to ``value`` (the
    file's checks: ParameterError naming the key); the rig itself for an input of its
    scene."""
    from jaxrod.scenes.files import apply_settings, scene_from

    if key in rig.scene.inputs() or key == "load_scale":
        return rig
    return scene_from(apply_settings(rig.data, [f"{key}={float(value)!r}"]))
