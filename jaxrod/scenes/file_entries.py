"""A scene file's entries read and checked, each error naming its dotted key: numbers,
SI magnitudes (``SI_LIMITS``: a unit slip), vectors in the plane, a hard magnetisation's
profiles along s (its angle to the tangent, its strength)."""

from __future__ import annotations

import difflib
import math

import numpy as np

from jaxrod.params import ParameterError

#: Plausible SI magnitudes: (lowest, highest, unit).
SI_LIMITS = {"length": (1e-6, 100.0, "m"), "radius": (1e-8, 1.0, "m"),
             "youngs_modulus": (1.0, 1e13, "Pa"), "density": (0.0, 1e5, "kg/m^3"),
             "remanence": (0.0, 1e7, "A/m"), "saturation": (0.0, 1e7, "A/m"),
             "B": (0.0, 5.0, "T"), "g": (0.0, 1e4, "m/s^2"), "moment": (0.0, 1e6, "A m^2"),
             "diameter": (0.0, 10.0, "m")}


def fail(key: str, message: str):
    raise ParameterError(f"{key}: {message}")


def unknown_key(where: str, key: str, allowed) -> None:
    near = difflib.get_close_matches(key, list(allowed), n=1)
    hint = f" (did you mean {near[0]!r}?)" if near else ""
    fail(f"{where}{key}", f"unknown key{hint}; valid here: {', '.join(allowed)}")


def number(data: dict, key: str, where: str, required: bool = True, default=None):
    if key not in data:
        if required:
            fail(f"{where}{key}", "missing")
        return default
    v = data[key]
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
        fail(f"{where}{key}", f"must be a finite number, got {v!r}")
    return float(v)


#: SI entries that are sizes or magnitudes: a negative value is a sign slip, never a mirror
#: image (a negative E, radius or magnet diameter would give the answer of its opposite).
#: A sign is meaningful for B (a reversed field), g (a hanging rod: negative g) and the rod's
#: remanence (a magnetisation against the tangent); a magnet's moment takes its direction
#: from ``moment_direction``.
POSITIVE = ("length", "radius", "youngs_modulus", "density", "diameter", "saturation",
            "moment")


def check_plausible(table: dict, where: str) -> None:
    """An SI file's numbers within ``SI_LIMITS`` (a 30 T field, a 3 km rod: a unit slip),
    sizes and magnitudes (``POSITIVE``, and a magnet's remanence) not negative; entries
    that are not finite numbers are left to ``number``."""
    for key, v in table.items():
        lo_hi = SI_LIMITS.get(key)
        if lo_hi is None or isinstance(v, bool) or not isinstance(v, (int, float)) \
                or not math.isfinite(v):
            continue
        sized = key in POSITIVE or (key == "remanence" and where.startswith("field"))
        if sized and v <= 0.0 and not (v == 0.0 and key in ("saturation", "moment")):
            fail(f"{where}{key}", f"must be > 0 {lo_hi[2]} (a size or magnitude), got {v:g}")
        if lo_hi[0] <= abs(v) <= lo_hi[1]:
            continue
        fail(f"{where}{key}", f"{v:g} {lo_hi[2]} is outside the plausible {lo_hi[0]:g} to "
                               f"{lo_hi[1]:g} {lo_hi[2]}: a unit slip? (SI units; or set "
                               "units = \"nondimensional\")")


def vector(data: dict, key: str, where: str, default):
    if key not in data:
        return default
    v = data[key]
    if not isinstance(v, list) or len(v) != 2 or not all(
            isinstance(c, (int, float)) and not isinstance(c, bool) and math.isfinite(c)
            for c in v):
        fail(f"{where}{key}", f"must be two finite numbers [x, z], got {v!r}")
    return [float(c) for c in v]


def angle_profile(mag: dict, kind, geometry: str):
    """The magnetisation's angle to the tangent, polynomial coefficients in s (radians), or
    None along the tangent: ``angle_deg`` (constant) or ``profile_deg`` ([c0, c1, ...])."""
    if "angle_deg" in mag and "profile_deg" in mag:
        fail("magnetisation.profile_deg", "give angle_deg (a constant angle) or profile_deg "
                                           "(coefficients in s), not both")
    if "angle_deg" not in mag and "profile_deg" not in mag:
        return None
    key = "angle_deg" if "angle_deg" in mag else "profile_deg"
    if kind != "hard":
        fail(f"magnetisation.{key}", "only a hard magnetisation is programmed at an angle "
                                      "to the tangent")
    if geometry == "3d":
        fail(f"magnetisation.{key}", "a programmed magnetisation needs geometry = "
                                      "\"planar\", or a rod that carries its frame (support "
                                      "= \"clamped-clamped\"; the 3D cantilever's chart "
                                      "carries no d1)")
    if key == "angle_deg":
        return np.radians([number(mag, "angle_deg", "magnetisation.")])
    return np.radians(coefficients(mag, "profile_deg", "magnetisation.",
                                   "degrees: c0 + c1 s + c2 s^2 ..."))


def coefficients(table: dict, key: str, where: str, form: str):
    """A profile's coefficients, a list of finite numbers (``form`` says what they are, for
    the error), or None where the key is absent."""
    if key not in table:
        return None
    d = table[key]
    if not isinstance(d, list) or not d or not all(
            isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
            for v in d):
        fail(f"{where}{key}", f"must be a list of finite numbers ({form}), got {d!r}")
    return np.asarray(d, float)


def chebyshev_form(what: str) -> str:
    """The error's words for Chebyshev coefficients of ``what`` along the rod."""
    return f"Chebyshev coefficients of {what} in 2 s - 1: d0 T0 + d1 T1 + ...; [1.0] is uniform"


def strength_profile(mag: dict, kind, geometry: str, fields):
    """The remanence's strength along s relative to the load (``coefficients``), or None."""
    if "strength_profile" not in mag:
        return None
    key = "magnetisation.strength_profile"
    if kind != "hard":
        fail(key, "only a hard magnetisation has a remanence profile")
    if geometry == "3d":
        fail(key, "a remanence profile needs geometry = \"planar\", or support = "
                  "\"clamped-clamped\"")
    if any(f.get("kind") != "uniform" for f in fields):
        fail(key, "a remanence profile acts in uniform fields")
    return coefficients(mag, "strength_profile", "magnetisation.",
                        chebyshev_form("the remanence"))


def direction(angle: float):
    return np.array([math.sin(angle), 0.0, math.cos(angle)])


#: The rigs that ship as scene files (``presets()``), by name.
