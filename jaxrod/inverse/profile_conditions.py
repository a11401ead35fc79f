"""Conditions on a design's profiles and inputs: a profile's basis by its list's key, bounds
on inputs and on a profile's values along s (lo <= A p <= hi), and the roughness of a
profile, int_0^1 f''(s)^2 ds = |R p|^2 (``jaxrod.inverse.shape_design``)."""

from __future__ import annotations

import numpy as np

from jaxrod.params import ParameterError

#: A profile's basis by its list's key: Chebyshev in 2 s - 1, or powers of s (degrees).
PROFILES = {"magnetisation.strength_profile": "chebyshev", "rod.stiffness_profile":
            "chebyshev", "magnetisation.profile_deg": "powers"}


def profile_columns(key: str, free, what: str) -> tuple[list[int], list[int]] | None:
    """(the positions in ``free`` of a profile's coefficients, their orders), None where none
    is free; ParameterError where some are held."""
    idx = [i for i, k in enumerate(free) if k.startswith(key + ".")]
    if not idx:
        return None
    order = [int(free[i].rsplit(".", 1)[1]) for i in idx]
    if sorted(order) != list(range(len(order))):
        raise ParameterError(f"{what} {key}: a condition on the profile's values needs all "
                             f"its coefficients free ({key}.0 to .{len(order) - 1})")
    return idx, order


def basis(key: str, s, degree: int, derivative: int = 0) -> np.ndarray:
    """The profile's basis functions' ``derivative``-th derivative in s at s, (len(s),
    degree + 1)."""
    eye = np.eye(degree + 1)
    if PROFILES[key] == "chebyshev":
        return np.stack([np.polynomial.chebyshev.chebval(2 * s - 1, np.polynomial.chebyshev
                                                         .chebder(e, derivative) * 2.0 **
                                                         derivative) for e in eye], axis=1)
    return np.stack([np.polynomial.polynomial.polyval(
        s, np.polynomial.polynomial.polyder(e, derivative)) for e in eye], axis=1)


def roughness_rows(free) -> np.ndarray:
    """R with |R p|^2 = sum over the profiles of free coefficients of int_0^1 f''(s)^2 ds
    (Gauss-Legendre, 32 nodes: exact for the degrees a file takes)."""
    x, w = np.polynomial.legendre.leggauss(32)
    s, w = (x + 1.0) / 2.0, w / 2.0
    rows = []
    for key in PROFILES:
        found = profile_columns(key, free, "roughness")
        if found is None:
            continue
        idx, order = found
        block = np.zeros((s.size, len(free)))
        block[:, idx] = np.sqrt(w)[:, None] * basis(key, s, len(idx) - 1, 2)[:, order]
        rows.append(block)
    if not rows:
        raise ParameterError(f"roughness: it acts on a profile of free coefficients "
                             f"({', '.join(PROFILES)}); none is free")
    return np.concatenate(rows)


def bound_rows(bounds: dict, free, p0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(A, lo, hi) with lo <= A p <= hi: a free input's bounds a row of the identity, a
    profile's bounds its basis at 101 points of s times its free coefficients."""
    rows, lo, hi = [], [], []
    for key, pair in bounds.items():
        try:
            a, b = (float(v) for v in pair)
        except (TypeError, ValueError):
            raise ParameterError(f"bounds {key}: a pair (lo, hi), got {pair!r:.60}") from None
        if not a < b:
            raise ParameterError(f"bounds {key}: lo < hi, got ({a:g}, {b:g})")
        if key in free:
            rows.append(np.eye(len(free))[free.index(key)][None])
        elif key in PROFILES:
            found = profile_columns(key, free, "bounds")
            if found is None:
                raise ParameterError(f"bounds {key}: free its coefficients ({key}.0, ...)")
            idx, order = found
            s = np.linspace(0.0, 1.0, 101)
            block = np.zeros((s.size, len(free)))
            block[:, idx] = basis(key, s, len(idx) - 1)[:, order]
            rows.append(block)
        else:
            raise ParameterError(f"bounds: {key!r} is not free ({', '.join(free)}) nor a "
                                 f"profile of free coefficients ({', '.join(PROFILES)})")
        lo += [a] * len(rows[-1])
        hi += [b] * len(rows[-1])
    A = np.concatenate(rows) if rows else np.zeros((0, len(free)))
    lo, hi = np.array(lo, float), np.array(hi, float)
    if np.any(A @ p0 < lo) or np.any(A @ p0 > hi):
        raise ParameterError("bounds: the start (the scene's values) lies outside them")
    return A, lo, hi
