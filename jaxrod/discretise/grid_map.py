"""A map of the Chebyshev grid that gathers its nodes about the rod's middle.

A state localised at s = 1/2 (the localised helix of a rod held at both ends: its fields
decay like sech(k (s - 1/2))) has poles at distance pi / (2 k) from the real line; the
Chebyshev points of [0, 1] are spaced about pi / (2 n) there, so the plain grid needs
n of order k times the digits wanted. The fields are instead polynomials in xi in [0, 1],
with (Tee and Trefethen's sinh map, centred)

    s(xi) = 1/2 + w sinh(a (2 xi - 1)),    a = asinh(1 / (2 w)),

which takes [0, 1] onto itself and spaces the nodes about pi w a / n at the middle: about
1 / (2 w a) times closer than the plain grid, for a layer of width w there. As w grows the
map tends to the identity; ``layer_width`` = None is the plain grid.
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

from jaxrod import spectral
from jaxrod.params import ParameterError


def check_layer_width(layer_width) -> float | None:
    """None (the plain grid) or a finite width in (0, 1]."""
    if layer_width is None:
        return None
    if isinstance(layer_width, bool) or not isinstance(layer_width, (int, float)) or \
            not (math.isfinite(layer_width) and 0.0 < layer_width <= 1.0):
        raise ParameterError(f"layer_width: None (the plain grid) or a number in (0, 1], got "
                             f"{layer_width!r}")
    return float(layer_width)


def _rate(width: float) -> float:
    return math.asinh(0.5 / width)


def arclength(xi, layer_width: float | None) -> np.ndarray:
    """s(xi) (module docstring)."""
    xi = np.asarray(xi, float)
    if layer_width is None:
        return xi
    a = _rate(layer_width)
    return np.clip(0.5 + layer_width * np.sinh(a * (2.0 * xi - 1.0)), 0.0, 1.0)


def stretch(xi, layer_width: float | None) -> np.ndarray:
    """ds / dxi."""
    xi = np.asarray(xi, float)
    if layer_width is None:
        return np.ones_like(xi)
    a = _rate(layer_width)
    return 2.0 * a * layer_width * np.cosh(a * (2.0 * xi - 1.0))


def grid_coordinate(s, layer_width: float | None) -> np.ndarray:
    """xi(s), the inverse of ``arclength``."""
    s = np.asarray(s, float)
    if layer_width is None:
        return s
    a = _rate(layer_width)
    return np.clip(0.5 * (1.0 + np.arcsinh((s - 0.5) / layer_width) / a), 0.0, 1.0)


@lru_cache(maxsize=32)
def cumulative_integration(degree: int, layer_width: float | None) -> np.ndarray:
    """(C f)_j = int_0^{s_j} f ds at the nodes of the degree-``degree`` Chebyshev grid
    mapped by ``layer_width``: the plain grid's matrix in xi, each column times ds / dxi
    (cached: not to be written to)."""
    xi = spectral.chebyshev_nodes(degree)
    return spectral.cumulative_integration_matrix(degree) * stretch(xi, layer_width)
