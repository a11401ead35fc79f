"""Maps of any scene's folds (``jaxrod.fold_map``): the on-disk store read back equal to the
map in memory, a killed map resumed to the same answer, a store of other arguments refused,
and the points laid out over several devices giving the same map as one device."""

import json
import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import jaxrod as jr
from jaxrod.bistability.fold_map import FoldMap, read_fold_map
from jaxrod.scenes.terms import Bending, Dipole, Gravity, Zeeman

N = 10
ALPHA = (0.0, math.pi / 2)
AXES = (("magnet.D", np.array([1.15, 1.2, 1.25])), ("magnet.M", np.array([0.022, 0.026, 0.03])))


def _scene():
    return jr.Scene({"bending": Bending(), "gravity": Gravity(2.2),
                     "magnet": Dipole(0.0236, 1.2, 0.0)})


def _same(a, b):
    np.testing.assert_array_equal(a.count, b.count)
    np.testing.assert_array_equal(a.status, b.status)
    for name in ("first", "second"):
        np.testing.assert_allclose(getattr(a, name), getattr(b, name), rtol=0, atol=1e-11,
                                   equal_nan=True)


@pytest.fixture(scope="module")
def in_memory():
    return jr.fold_map(_scene(), "magnet.alpha", ALPHA, *AXES, n=N, progress=False, chunk=2)


def test_the_map_is_what_scene_folds_gives_at_its_points(in_memory):
    assert np.all(in_memory.status == int(jr.Status.SUCCESS))
    assert np.all(in_memory.count == 2)  # the paper's rig is bistable over this grid
    for iy, ix in ((0, 0), (2, 1)):
        scene = _scene().replace("magnet.D", AXES[0][1][ix]).replace("magnet.M",
                                                                      AXES[1][1][iy])
        folds = jr.folds(scene, "magnet.alpha", *ALPHA, n=N)
        assert abs(in_memory.first[iy, ix] - folds[0].value) <= 1e-10
        assert abs(in_memory.second[iy, ix] - folds[1].value) <= 1e-10


def test_a_point_whose_folds_converged_is_not_marked_failed():
    """A hard-magnetic cantilever under gravity turned by its field (the folds in the
    field's angle over load and G): the branches are long (the tip turns by up to 270
    degrees), and points whose two folds converged were marked NOT_CONVERGED because the
    branch ran out of points after them. Every point succeeds, its first fold that of
    ``scene_folds`` there."""
    scene = jr.Scene({"bending": Bending(), "gravity": Gravity(1.0),
                      "field": Zeeman(5.0, math.pi / 2)})
    loads, gs = np.array([6.3, 10.0]), np.array([1.0, 3.0])
    angles = (math.pi / 2, math.radians(359.0))
    m = jr.fold_map(scene, "field.angle", angles, ("field.load", loads), ("gravity.G", gs),
                    n=N, progress=False, chunk=2)
    assert np.all(m.status == int(jr.Status.SUCCESS)) and np.all(m.count >= 1)
    for iy, ix in ((0, 0), (1, 1)):
        at = scene.replace("field.load", loads[ix]).replace("gravity.G", gs[iy])
        first = jr.folds(at, "field.angle", *angles, n=N)[0]
        assert abs(m.first[iy, ix] - first.value) <= 1e-10


def test_the_store_is_the_map_and_a_killed_map_resumes(in_memory, tmp_path):
    out = tmp_path / "map.zarr"
    stored = jr.fold_map(_scene(), "magnet.alpha", ALPHA, *AXES, n=N, progress=False,
                         chunk=2, out=out)
    _same(stored, in_memory)
    _same(read_fold_map(out), in_memory)
    assert json.loads((out / ".zmetadata").read_text())["metadata"]["count/.zarray"][
        "chunks"] == [2, 2]
    # a chunk lost (as if the run had been killed before its last variable was written)
    (out / "status" / "1.0").unlink()
    partial = read_fold_map(out)
    assert np.all(partial.status[2:, :2] == -1) and np.all(partial.status[:2] == 0)
    again = jr.fold_map(_scene(), "magnet.alpha", ALPHA, *AXES, n=N, progress=False,
                        chunk=2, out=out)
    assert np.all(again.count[:2] == -1)  # the chunks already on disk were not recomputed
    _same(read_fold_map(out), in_memory)
    with pytest.raises(jr.ParameterError, match="other arguments"):
        jr.fold_map(_scene(), "magnet.alpha", (0.0, 1.0), *AXES, n=N, progress=False,
                    chunk=2, out=out)


DEVICES = """
import json, math, sys
import numpy as np
import jax
import jaxrod as jr
sys.path.insert(0, {tests!r})
from test_fold_map import ALPHA, AXES, N, _scene
assert len(jax.local_devices()) == 4
m = jr.fold_map(_scene(), "magnet.alpha", ALPHA, *AXES, n=N, progress=False, chunk=2)
print(json.dumps({{"count": m.count.tolist(), "status": m.status.tolist(),
                  "first": m.first.tolist(), "second": m.second.tolist()}}))
"""


def test_four_devices_give_the_map_of_one(in_memory):
    env = os.environ | {"XLA_FLAGS": os.environ.get("XLA_FLAGS", "")
                        + " --xla_force_host_platform_device_count=4",
                        "JAX_PLATFORMS": "cpu"}
    code = DEVICES.format(tests=str(Path(__file__).parent))
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          env=env, timeout=1800)
    assert proc.returncode == 0, proc.stderr[-2000:]
    got = json.loads(proc.stdout.strip().splitlines()[-1])
    np.testing.assert_array_equal(got["count"], in_memory.count)
    np.testing.assert_array_equal(got["status"], in_memory.status)
    for name in ("first", "second"):
        np.testing.assert_allclose(got[name], getattr(in_memory, name), rtol=0, atol=1e-11)


def test_the_maps_figure_shows_the_first_fold_and_names_the_failed_points():
    """FoldMap.plot: the colour is the first fold's value (the count was shown before), a
    failed point is marked and named in the legend with how many failed."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    first = np.array([[0.5, 0.6], [0.7, np.nan]])
    status = np.array([[0, 0], [0, int(jr.Status.NOT_CONVERGED)]], dtype=np.int16)
    m = FoldMap("magnet.alpha", (0.0, 1.0), "magnet.D", np.array([1.1, 1.2]), "magnet.M",
                   np.array([0.02, 0.03]), np.array([[2, 2], [1, -1]]), first,
                   np.full((2, 2), np.nan), status)
    fig, ax = plt.subplots()
    m.plot(ax, factor=math.pi / 180.0, label="first fold (deg)")
    mesh = ax.collections[0]
    np.testing.assert_allclose(mesh.get_array().compressed(), np.degrees(first.ravel()[:3]))
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert any(t.startswith("failed (1 of 4") for t in labels)
    assert fig.axes[-1].get_ylabel() == "first fold (deg)"
    plt.close(fig)
