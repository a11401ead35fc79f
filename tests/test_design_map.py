"""Bistability maps: values against locate_folds, the on-disk store, resume after a kill,
8 virtual devices and 2 processes identical to one."""

import json
import math
import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from jaxrod.bistability.design_map import (
    FOLD_BEYOND_90,
    INVALID_INPUT,
    NOT_BISTABLE,
    NOT_CONVERGED,
    OK,
    REASONS,
    MapAxis,
    MapSpec,
    fold_crossings,
    read_store,
    run_map,
    solve_points,
)
from jaxrod.design_point import DesignPoint
from jaxrod.magnet.folds import locate_folds
from jaxrod.params import NDFEB_MAGNET, ParameterError, preset
from jaxrod.scenes.dipole import DipoleMagnet


def _same(a, b):
    """Identical maps: the same reasons and NaN pattern, angles equal to round-off (XLA may
    vectorise a different batch shape differently: the fold angles' round-off floor is
    ~1e-11 degrees)."""
    np.testing.assert_array_equal(a["status"], b["status"])
    for name in ("capture_deg", "release_deg", "width_deg"):
        np.testing.assert_array_equal(np.isnan(a[name]), np.isnan(b[name]))
        np.testing.assert_allclose(a[name], b[name], rtol=0, atol=1e-11, equal_nan=True)


def _point():
    rod, _ = preset("permanent-magnet")
    return DesignPoint.from_physical(rod, NDFEB_MAGNET)


#: A grid inside the bistable region (every point OK: the subprocess tests then compile the
#: batched path only).
BISTABLE_X, BISTABLE_Y = "track-radius:0.105:0.112:9", "E:150e9:250e9:7"
CLI = [sys.executable, "-m", "jaxrod.cli", "map", "--preset", "permanent-magnet",
       "--x", BISTABLE_X, "--y", BISTABLE_Y, "--chunk", "4", "--quiet", "--no-plot"]


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    out = tmp_path_factory.mktemp("map") / "ref"
    spec = MapSpec(_point(), MapAxis.parse(BISTABLE_X), MapAxis.parse(BISTABLE_Y), chunk=4)
    run_map(spec, out, progress=False)
    return read_store(out)


def test_every_tier_and_reason_against_locate_folds():
    point = _point()
    # rows: bistable; beyond the cusp (not bistable); magnet touching; small clearance with
    # the upper fold beyond 90 degrees
    names = point.names
    rows = []
    for R, E in ((0.11, 200e9), (0.135, 200e9), (0.099, 200e9), (0.1005, 80e9)):
        v = list(point.values)
        v[names.index("track-radius")], v[names.index("E")] = R, E
        rows.append(v)
    res = solve_points(point, np.array(rows))
    assert list(res["status"]) == [OK, NOT_BISTABLE, INVALID_INPUT, FOLD_BEYOND_90]
    for i, v in enumerate(rows[:2]):
        G, M, D = DesignPoint("physical", tuple(v)).groups()
        rep = locate_folds(DipoleMagnet(G, M, D, 0.0))
        if res["status"][i] == OK:
            low, up = rep.folds
            assert abs(res["capture_deg"][i] - low.alpha_deg) < 1e-9
            assert abs(res["release_deg"][i] - up.alpha_deg) < 1e-9
        else:
            assert rep.folds == [] and math.isnan(res["width_deg"][i])
    assert np.isnan(res["capture_deg"][2:]).all()


def test_store_opens_and_matches_solve_points(reference):
    point = _point()
    assert (reference["status"] == OK).all()
    iy, ix = 3, 5
    v = list(point.values)
    v[point.index("track-radius")] = reference["x"][ix]
    v[point.index("E")] = reference["y"][iy]
    one = solve_points(point, np.array([v]))
    # another batch shape: the same solve to round-off
    assert abs(one["capture_deg"][0] - reference["capture_deg"][iy, ix]) < 1e-12
    assert reference["width_deg"].shape == (7, 9)


def test_store_is_zarr_that_xarray_opens_without_warnings(reference, tmp_path, capsys):
    """The command line's store, opened as the docs say: no warning (consolidated metadata;
    map.png and map.json beside the store, not in it), coordinates named by the inputs, a
    chunk not written yet is missing (NaN to xarray, -1 "not computed" to ``read_store``), and
    the code 4 ("not converged") stays 4 (it was the fill value, which xarray turned into
    NaN)."""
    import warnings

    xr = pytest.importorskip("xarray")
    pytest.importorskip("zarr")
    from jaxrod.cli import main

    out = tmp_path / "z"
    assert main([*CLI[3:], "--out", str(out)]) == 0
    capsys.readouterr()
    assert (out / "map.json").exists() and not (out / "map.zarr" / "map.json").exists()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        ds = xr.open_zarr(out / "map.zarr")
    assert set(ds.coords) == {"track-radius", "E"} and ds["width_deg"].dims == (
        "E", "track-radius")
    np.testing.assert_array_equal(ds["width_deg"].values, reference["width_deg"])
    assert ds["capture_deg"].attrs["units"] == "degree" and "source" in ds.attrs
    assert ds["E"].attrs["units"] == "Pa"
    # a point that no solver converged, and a chunk not written
    (out / "map.zarr" / "status" / "0.0").write_bytes(
        np.full((4, 4), NOT_CONVERGED, np.int8).tobytes())
    (out / "map.zarr" / "status" / "1.1").unlink()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        reason = xr.open_zarr(out / "map.zarr")["status"].values
    assert (reason[:4, :4] == NOT_CONVERGED).all() and np.isnan(reason[4:, 4:8]).all()
    mine = read_store(out)["status"]
    assert (mine[4:, 4:8] == -1).all() and (mine[:4, :4] == NOT_CONVERGED).all()
    assert np.count_nonzero(np.isnan(reason)) == np.count_nonzero(mine == -1)


def test_a_map_for_other_arguments_is_refused(tmp_path):
    spec = MapSpec(_point(), MapAxis.parse("E:150e9:250e9:3"), MapAxis.parse("length:0.09:0.095:3"))
    run_map(spec, tmp_path, progress=False)
    other = MapSpec(_point(), MapAxis.parse("E:150e9:250e9:4"),
                    MapAxis.parse("length:0.09:0.095:3"))
    with pytest.raises(ParameterError, match="other arguments"):
        run_map(other, tmp_path, progress=False)


@pytest.mark.parametrize("text", ["E:1:2", "E:a:2:3", "E:1:1:3", "E:1:2:0", "E:inf:2:3"])
def test_bad_axes(text):
    with pytest.raises(ParameterError):
        MapAxis.parse(text)


def test_resume_after_kill_loses_nothing(reference, tmp_path):
    out = tmp_path / "killed"
    proc = subprocess.Popen([*CLI, "--out", str(out)], stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE)
    chunks = lambda: [f for f in (out / "map.zarr" / "status").glob("*") if f.name[0].isdigit()]
    deadline = time.monotonic() + 600
    while time.monotonic() < deadline and proc.poll() is None:
        if len(chunks()) >= 2:  # two of six chunks written
            break
        time.sleep(0.02)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    done = len(chunks())
    assert 2 <= done < 6, f"{done} chunks before the kill"
    again = subprocess.run([*CLI, "--out", str(out), "--json"], capture_output=True, text=True,
                           timeout=900)
    assert again.returncode == 0, again.stderr
    assert json.loads(again.stdout)["resumed"] == done
    resumed = read_store(out)
    for name in ("capture_deg", "release_deg", "width_deg", "status"):  # same chunk shapes
        np.testing.assert_array_equal(resumed[name], reference[name])


def test_eight_devices_identical_to_one(reference, tmp_path):
    out = tmp_path / "eight"
    env = os.environ | {"XLA_FLAGS": os.environ.get("XLA_FLAGS", "")
                        + " --xla_force_host_platform_device_count=8"}
    code = ("import jax, json; from jaxrod.cli import main; import sys; "
            "assert len(jax.local_devices()) == 8; "
            f"sys.exit(main({[*CLI[3:], '--out', str(out)]!r}))")
    proc = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                          text=True, timeout=900)
    assert proc.returncode == 0, proc.stderr[-2000:]
    _same(read_store(out), reference)


def _free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_two_processes_identical_to_one(reference, tmp_path):
    out = tmp_path / "two"
    port = _free_port()
    procs = [subprocess.Popen([*CLI, "--out", str(out), "--coordinator", f"127.0.0.1:{port}",
                               "--num-processes", "2", "--process-id", str(i), "--json"],
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
             for i in (0, 1)]
    outs = [p.communicate(timeout=900) for p in procs]
    for p, (stdout, stderr) in zip(procs, outs, strict=True):
        assert p.returncode == 0, stderr[-2000:]
    summaries = [json.loads(stdout) for stdout, _ in outs]
    assert sorted(s["process"] for s in summaries) == [0, 1]
    assert sum(s["computed"] for s in summaries) == 6  # each its own chunks
    _same(read_store(out), reference)


def test_fold_crossings_bound_the_region_beyond_90_degrees():
    """Two independent routes to one boundary: on a grid row at small clearance, the fold
    curve's "alpha = 90 deg" event lies between the last grid point whose upper fold is
    beyond 90 degrees and the first bistable one."""
    point = _point()
    x, y = MapAxis.parse("track-radius:0.1002:0.106:8"), MapAxis("E", 80e9, 90e9, 1)
    spec = MapSpec(point, x, y, chunk=8)
    rows = []
    for R in x.values():
        v = list(point.values)
        v[point.index("track-radius")], v[point.index("E")] = R, 80e9
        rows.append(v)
    res = solve_points(point, np.array(rows))
    data = {"x": x.values(), "y": y.values()} | {k: v[None, :] for k, v in res.items()}
    reason = res["status"]
    assert reason[0] == FOLD_BEYOND_90 and reason[-1] == OK
    last_beyond = np.nonzero(reason == FOLD_BEYOND_90)[0].max()
    assert (reason[last_beyond + 1:] == OK).all()
    crossings = fold_crossings(spec, data)
    assert len(crossings) == 1
    assert x.values()[last_beyond] < crossings[0]["track-radius"] < x.values()[last_beyond + 1]


#: A longer map for the Ctrl-C test: 100 chunks of 16 points (about 0.2 s a chunk, warm).
LONG_MAP = [sys.executable, "-m", "jaxrod.cli", "map", "--G", "2.2", "--M", "0.0236",
            "--D", "1.2", "--x", "D:1.1:1.3:40", "--y", "M:0.02:0.03:40", "--chunk", "4",
            "--quiet", "--no-plot"]


def _wait_for_jax_import(proc, deadline: float) -> None:
    """Until the process has begun to import JAX (its compiled library is mapped): jaxrod's
    start-up. Before that the interpreter is starting, and a Ctrl-C ends it as Python
    does (a loaded machine can take a second to get there)."""
    maps = Path(f"/proc/{proc.pid}/maps")
    while time.monotonic() < deadline and proc.poll() is None:
        if "jaxlib" in maps.read_text(errors="replace"):
            return
        time.sleep(0.005)


@pytest.mark.xdist_group("sigint")
@pytest.mark.skipif(not Path("/proc/self/maps").exists(), reason="needs /proc (Linux)")
def test_ctrl_c_at_ten_moments_exits_130_and_keeps_the_finished_chunks(tmp_path):
    """SIGINT to ``jaxrod map`` at ten moments (as JAX is being imported, during the first
    chunk's compilation, and after 1 to 60 finished chunks): exit 130 every time, with one
    line on stderr, soon (no run goes on to the end: a Ctrl-C swallowed in a
    garbage-collection callback did that), and every chunk marked complete readable with its
    four variables."""
    chunk_files = lambda out: [f for f in (out / "map.zarr" / "status").glob("*")
                               if f.name[0].isdigit()]
    for i, (delay, after) in enumerate([(0.0, 0), (3.0, 0), (0, 1), (0, 2), (0, 3), (0, 6),
                                        (0, 10), (0, 20), (0, 35), (0, 60)]):
        out = tmp_path / f"map{i}"
        proc = subprocess.Popen([*LONG_MAP, "--out", str(out)], stdout=subprocess.DEVNULL,
                                stderr=subprocess.PIPE, text=True)
        deadline = time.monotonic() + 300
        _wait_for_jax_import(proc, deadline)
        time.sleep(delay)
        while after and time.monotonic() < deadline and proc.poll() is None:
            if (out / "map.zarr" / "status").exists() and len(chunk_files(out)) >= after:
                break
            time.sleep(0.01)
        assert proc.poll() is None, f"moment {i}: the map ended before the signal"
        seen = len(chunk_files(out)) if (out / "map.zarr" / "status").exists() else 0
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=120)
        assert proc.returncode == 130, (i, err[-2000:])
        assert len(err.strip().splitlines()) == 1, (i, err[-2000:])
        if not (out / "map.zarr" / "status").exists():
            continue
        done = chunk_files(out)
        assert seen <= len(done) <= seen + 2, (i, seen, len(done))
        for f in done:
            for name in ("capture_deg", "release_deg", "width_deg"):
                assert (out / "map.zarr" / name / f.name).stat().st_size == 16 * 8
        if done:
            data = read_store(out)
            assert np.isin(data["status"], [-1, *REASONS]).all()


@pytest.mark.parametrize("x, y, name", [
    ("D:1.1:1.2:1", "M:0.02:0.03:1", "axis D: count"),
    ("D:1.1:1.2:100000", "M:0.02:0.03:100000", "x, y: the grid has 100000 x 100000"),
    ("D:1.1:1.2:4000", "M:0.02:0.03:4000", "x, y: the grid has 4000 x 4000"),
])
def test_map_refuses_grids_before_any_work(tmp_path, x, y, name):
    """A 1 x 1 grid (which computed and then crashed in the figure) and grids whose counts
    are each in range but whose product is not (100000 x 100000 ran numpy out of memory):
    one line, exit 2, and no output folder."""
    out = tmp_path / "never"
    proc = subprocess.run([sys.executable, "-m", "jaxrod.cli", "map", "--G", "2.2", "--x", x,
                           "--y", y, "--out", str(out), "--quiet"], capture_output=True,
                          text=True, timeout=120)
    assert proc.returncode == 2 and name in proc.stderr, proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1 and not out.exists()


def test_map_axes_need_not_be_given_as_inputs(tmp_path, capsys):
    """--M and --D are the map's axes: the grid sets them (they were demanded)."""
    from jaxrod.cli import main

    out = tmp_path / "axes"
    assert main(["map", "--G", "2.2", "--x", "D:1.15:1.25:2", "--y", "M:0.022:0.026:2",
                 "--out", str(out), "--quiet", "--no-plot", "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["inputs"]["D"]["source"] == "the map's axis"
    assert summary["status_counts"]["bistable"] == 4
