"""A few thousand mixed calls of the compiled entry points in one process, each with new
parameter values: once every program is compiled, neither the process's memory mappings
(compiled machine code is mapped into the process) nor its resident memory may grow."""

import os
from pathlib import Path

import jax
import numpy as np
import pytest

from jaxrod.inverse import youngs as fit_youngs
from jaxrod.magnet import diagram as magnet
from jaxrod.magnet import folds as magnet_folds
from jaxrod.magnet.batch import fold_pairs
from jaxrod.uniform import greenhill

D_EXP = 11.25 / 9.2
MAPS = Path("/proc/self/maps")


def _mappings() -> int:
    return len(MAPS.read_text().splitlines())


def _resident_bytes() -> int:
    return int(Path("/proc/self/statm").read_text().split()[1]) * os.sysconf("SC_PAGE_SIZE")


def _calls():
    """(name, call(E in GPa)) with the paper's wire scaled to E."""
    G = lambda E: 2.2 * 200.0 / E
    M = lambda E: 0.0236 * 200.0 / E
    return [
        ("fold_angles", lambda E: magnet_folds.fold_angles(G(E), M(E), D_EXP)),
        ("grad fold_angles", lambda E: jax.grad(
            lambda g: magnet_folds.fold_angles(g, M(E), D_EXP)[0][1])(G(E))),
        ("fold_pair", lambda E: magnet_folds.fold_pair(magnet.make_scene(G(E), M(E), D_EXP))),
        ("fold_pairs", lambda E: fold_pairs(np.array([G(E), 1.1 * G(E)]),
                                            np.array([M(E), M(E)]), np.full(2, D_EXP))),
        ("greenhill", lambda E: greenhill.greenhill(4.0 * G(E), "clamped", A=300.0 * M(E))),
        ("fit", lambda E: fit_youngs.fit_youngs_modulus([-25.0, 38.0, 24.0, -42.0], 1.0, True,
                                                 E0=E * 1e9)),
    ]


@pytest.mark.skipif(not MAPS.exists(), reason="needs /proc (Linux)")
def test_thousands_of_mixed_calls_keep_mappings_and_memory_flat():
    calls = _calls()
    rng = np.random.default_rng(0)
    for _ in range(3):  # compile every program, let the allocators settle
        for _, call in calls:
            jax.block_until_ready(call(rng.uniform(140.0, 220.0)))
    maps0, rss0 = _mappings(), _resident_bytes()
    for i in range(2400):
        name, call = calls[i % len(calls)]
        jax.block_until_ready(call(rng.uniform(140.0, 220.0)))
    grown_maps, grown_rss = _mappings() - maps0, _resident_bytes() - rss0
    assert grown_maps <= 16, f"{grown_maps} new memory mappings over 2400 calls"
    assert grown_rss < 64 * 2**20, f"resident memory grew by {grown_rss / 2**20:.1f} MiB"
