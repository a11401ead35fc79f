"""Exported entry points (jaxrod.stored): a program read back from the store gives the same
results as the traced one, and a damaged file falls back to tracing (the generic branch and
fold programs, whose inputs are a scene's path)."""

import math

import numpy as np

from jaxrod import stored
from jaxrod.equilibria import equilibrium, folds
from jaxrod.magnet import diagram as magnet

PROGRAMS = (equilibrium.path_program, folds._refine)

D_EXP = 11.25 / 9.2


def _folds(G, M):
    scene = magnet.make_scene(G, M, D_EXP)
    return [f.value for f in folds.folds(scene.scene, "magnet.alpha", 0.0, math.pi / 2, n=12)]


def test_programs_read_back_from_the_store_match_the_traced_ones(tmp_path):
    traced = _folds(2.2, 0.0236)
    stored.enable_store(tmp_path)
    for program in PROGRAMS:
        program._loaded.clear()  # programs an earlier store (a CLI run in this process) loaded
    try:
        written = _folds(2.2, 0.0236)
        files = sorted(tmp_path.glob("*.jaxexport"))
        assert {f.name.rsplit("-", 1)[0] for f in files} == {"path", "fold-refine"}
        for program in PROGRAMS:
            program._loaded.clear()  # as in a new process: read the files
        read = _folds(2.0, 0.0236)
        assert all(p._loaded for p in PROGRAMS)
        stored.enable_store(None)
        reference = _folds(2.0, 0.0236)
        np.testing.assert_allclose(written, traced, rtol=0, atol=1e-12)
        np.testing.assert_allclose(read, reference, rtol=0, atol=1e-12)
        # a truncated file is traced again and rewritten
        stored.enable_store(tmp_path)
        for f in files:
            f.write_bytes(f.read_bytes()[:100])
        for program in PROGRAMS:
            program._loaded.clear()
        np.testing.assert_allclose(_folds(2.0, 0.0236), reference, rtol=0, atol=1e-12)
        assert all(f.stat().st_size > 100 for f in files)
    finally:
        stored.enable_store(None)
