import os
import subprocess
import sys

import numpy as np

from jaxrod.analysis import magnet
from jaxrod.analysis.batch import fold_pairs
from jaxrod.programs import jit

D = 11.25 / 9.2


def test_fold_pairs_agree_with_the_continuation_route_and_flag_missing_folds():
    E = np.array([80.0, 100.0, 150.0, 200.0, 250.0])
    G, M = 2.2 * 200 / E, 0.0236 * 200 / E
    # add a magnet too weak for bistability (beyond the cusp) and a clearance where the rod
    # stays engaged up to 90 degrees: no fold pair, reported as not converged
    G = np.append(G, [2.2, 2.2])
    M = np.append(M, [0.002, 0.0236])
    Ds = np.append(np.full(E.size, D), [D, 1.02])
    alphas, converged, iterations = fold_pairs(G, M, Ds)
    converged = np.asarray(converged)
    assert converged[:E.size].all() and not converged[E.size:].any()
    for i in range(E.size):
        ref = magnet.locate_folds(magnet.make_scene(G[i], M[i], D), n=16).folds
        got = np.degrees(np.asarray(alphas[i]))
        assert np.max(np.abs(got - [f.alpha_deg for f in ref])) < 1e-10
    assert int(np.max(np.asarray(iterations)[:E.size])) <= 8


def test_fold_pairs_at_strongly_bent_folds_match_locate_folds():
    # small clearances: the upper fold's tip at 60-80 degrees (benchmarks/extreme.py)
    Ds = np.array([1.1, 1.05, 1.03])
    alphas, converged, _ = fold_pairs(np.full(3, 2.2), np.full(3, 0.0236), Ds)
    assert np.asarray(converged).all()
    for i, Di in enumerate(Ds):
        ref = magnet.locate_folds(magnet.make_scene(2.2, 0.0236, Di), n=16).folds
        got = np.degrees(np.asarray(alphas[i]))
        assert np.max(np.abs(got - [f.alpha_deg for f in ref])) < 1e-9


def test_fold_pairs_float32_loses_about_four_digits():
    G, M = np.array([2.2, 4.4]), np.array([0.0236, 0.0472])
    a64, c64, _ = fold_pairs(G, M, np.full(2, D))
    a32, c32, _ = fold_pairs(G, M, np.full(2, D), dtype="float32")
    assert np.asarray(a32).dtype == np.float32
    assert np.asarray(c32).all() and np.asarray(c64).all()
    err = np.degrees(np.abs(np.asarray(a32, float) - np.asarray(a64)))
    assert 1e-7 < err.max() < 1e-2


def test_a_set_without_folds_is_nan_not_a_number():
    """M = 0.001 is far past the cusp (no hysteresis; ``locate_folds`` finds no fold): the
    row is NaN and not converged, never a plausible angle; its neighbour is unaffected."""
    assert magnet.locate_folds(magnet.make_scene(2.2, 0.001, 1.2228)).folds == []
    alphas, converged, _ = fold_pairs([2.2, 2.2, 2.2], [0.001, 0.0236, 0.0236],
                                      [1.2228, 1.2228, 1.2228])
    alphas, converged = np.asarray(alphas), np.asarray(converged)
    assert not converged[0] and np.all(np.isnan(alphas[0]))
    assert converged[1] and np.all(np.isfinite(alphas[1]))


def test_more_bracketing_cells_rescue_small_clearances():
    """At these small clearances the first bracketing cells lie near q = 0 (the straight rod
    nearly critical at alpha = 0) and lead both one-mode solves to the upper fold: with one
    cell per end the pair is reported not converged; with four it is the pair of
    locate_folds, and a map (design_map.solve_points) reports them bistable with those angles."""
    import jax

    from jaxrod.analysis import design_map
    from jaxrod.analysis.batch import fold_pair_states
    from jaxrod.analysis.fold_curves import DesignPoint
    from jaxrod.discretise.planar import planar_discretisation

    disc = planar_discretisation(12, "clamped")
    rows = [(2.263, 2.263 * 0.0236 / 2.2, 1.1908), (1.760, 1.760 * 0.0236 / 2.2, 1.1872)]
    for cells in (1, 4):
        program = jit(jax.vmap(lambda g, m, d: fold_pair_states(g, m, d, disc, cells)))
        z, converged, _ = program(*(np.array(c) for c in zip(*rows)))
        converged = np.asarray(converged)
        assert not converged.any() if cells == 1 else converged.all()
    res = design_map.solve_points(DesignPoint.from_groups(*rows[0]), np.array(rows))
    assert (res["reason"] == design_map.OK).all()
    for i, (G, M, Di) in enumerate(rows):
        ref = [f.alpha_deg for f in magnet.locate_folds(magnet.make_scene(G, M, Di), n=16).folds]
        assert np.max(np.abs(np.degrees(np.asarray(z[i, :, -1])) - ref)) < 1e-8
        assert abs(res["capture_deg"][i] - ref[0]) < 1e-8
        assert abs(res["release_deg"][i] - ref[1]) < 1e-8


def test_two_programs_at_once_do_not_hang():
    """The batched path on two CPU devices at once, with two dispatches in flight, and from
    two threads on one device, in a fresh process: with LAPACK's batched LU the programs
    blocked XLA's thread pool and the process hung for ever (two threads on one device: hung
    every time tried); the jnp LU has no such call. Also: the answers equal the one-device
    ones."""
    code = """
import jax, numpy as np
from jaxrod.analysis.batch import fold_pairs_program
from jaxrod.analysis.design_map import _per_device, _sharded
assert len(jax.local_devices()) == 2
E = np.random.default_rng(0).uniform(80, 250, 2048)
G, M, D = 2.2 * 200 / E, 0.0236 * 200 / E, np.full(2048, 11.25 / 9.2)
program, mesh = _per_device(tuple(jax.local_devices()), 12)
inputs, _ = _sharded([G, M, D], mesh)
a2, ok2 = jax.device_get(program(*inputs))
halves = [fold_pairs_program(G[i::2], M[i::2], D[i::2]) for i in (0, 1)]  # both in flight
a1 = np.empty((2048, 2)); a1[0::2], a1[1::2] = (np.asarray(h[0]) for h in halves)
assert ok2.all() and np.max(np.abs(a2 - a1)) < 1e-12, np.max(np.abs(a2 - a1))
from concurrent.futures import ThreadPoolExecutor  # two threads, one device
with ThreadPoolExecutor(2) as pool:
    a3 = list(pool.map(lambda i: np.asarray(fold_pairs_program(G[i::2], M[i::2], D[i::2])[0]),
                       (0, 1, 0, 1)))
assert np.max(np.abs(a3[0] - a1[0::2])) < 1e-12
print("ok")
"""
    env = os.environ | {"XLA_FLAGS": "--xla_force_host_platform_device_count=2"}
    proc = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                          text=True, timeout=600)
    assert proc.returncode == 0 and "ok" in proc.stdout, proc.stderr[-2000:]


def test_near_the_cusp_a_converged_pair_is_the_pair_of_locate_folds():
    """Random sets around the cusp in D (D = 1.3064 at the paper's G, M), E 80-250 GPa,
    M +-10 %: every pair the batched path reports converged is the pair of the continuation
    route (``locate_folds``), and it reports none where that route finds no pair in
    (0, 90] degrees; the sets it misses are left to the map's retry tiers."""
    rng = np.random.default_rng(1)
    K = 40
    E = rng.uniform(80, 250, K)
    G, M = 2.2 * 200 / E, 0.0236 * 200 / E * rng.uniform(0.9, 1.1, K)
    Ds = rng.uniform(1.27, 1.34, K)
    alphas, converged, _ = fold_pairs(G, M, Ds)
    alphas, converged = np.degrees(np.asarray(alphas)), np.asarray(converged)
    assert 0.4 * K < converged.sum() < K  # both sides of the cusp are sampled
    for i in range(K):
        rep = magnet.locate_folds(magnet.make_scene(G[i], M[i], Ds[i]), n=16)
        kinds = {f.kind: f.alpha_deg for f in rep.folds}
        pair = rep.converged and {"lower", "upper"} <= kinds.keys() and kinds["upper"] <= 90
        if converged[i]:
            assert pair, (G[i], M[i], Ds[i])
            assert np.max(np.abs(alphas[i] - [kinds["lower"], kinds["upper"]])) < 1e-8
