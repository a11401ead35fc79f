"""A map's on-disk store: variables on a grid over two named inputs, written chunk by chunk,
resumable, each process of a ``jax.distributed`` run writing its own chunks.

The store is a Zarr (version 2) group written with numpy alone (raw little-endian chunks, no
compressor), which xarray opens with ``xarray.open_zarr`` (``pip install 'jaxrod[maps]'``):
one 2-D array per variable on dimensions named by the two inputs (y first), square chunks,
the axes as 1-D coordinate arrays with units, and consolidated metadata (``.zmetadata``). An
integer variable holds ``NOT_COMPUTED`` (-1) and a float variable NaN where a chunk was not
written yet. The variables are written in their given order, each file atomically, the last
one marking the chunk complete: a killed run started again with the same arguments
(``description``; another one is refused) skips the complete chunks and loses nothing.

With ``jax.distributed`` initialised, process p of P computes and writes the chunks whose
row-major index is p modulo P; the metadata is written by every process, identically.

Users: ``jaxrod.bistability.design_map`` (the paper's capture and release angles) and
``jaxrod.bistability.fold_map`` (the folds of any scene).
"""

from __future__ import annotations

import dataclasses
import datetime
import json
import os
import tempfile
from collections.abc import Callable
from pathlib import Path

import jax
import numpy as np

from jaxrod.params import ParameterError
from jaxrod.progress import ctrl_c_guard, interrupt_requested, progress_bar

#: An integer variable's value where its chunk was not written yet.
NOT_COMPUTED = -1


@dataclasses.dataclass(frozen=True)
class Variable:
    """One gridded variable: numpy ``dtype`` string ("<f8", "|i1", "<i2"), ``units`` (UDUNITS;
    "1" for a count or a code) and a ``long_name``."""

    dtype: str
    units: str
    long_name: str

    @property
    def fill(self):
        """NaN for a float, ``NOT_COMPUTED`` for an integer (as numpy and as Zarr writes it)."""
        return np.nan if np.dtype(self.dtype).kind == "f" else NOT_COMPUTED

    def zarr_fill(self):
        return "NaN" if np.dtype(self.dtype).kind == "f" else NOT_COMPUTED


@dataclasses.dataclass(frozen=True)
class GridAxis:
    """One axis: the input ``name``, its ``values`` and their ``units``."""

    name: str
    values: tuple[float, ...]
    units: str


@dataclasses.dataclass(frozen=True)
class GridStore:
    """The store at ``path``: ``variables`` by name (written in this order, the last marking
    a chunk complete), axes ``x`` (columns) and ``y`` (rows), square chunks of ``chunk``
    points a side; ``description`` (JSON text) names what the map computes, and a store made
    with another one is refused; ``attrs`` go into the group's attributes."""

    path: Path
    variables: dict[str, Variable]
    x: GridAxis
    y: GridAxis
    chunk: int
    description: str
    attrs: dict

    @property
    def shape(self) -> tuple[int, int]:
        return len(self.y.values), len(self.x.values)

    def chunks(self) -> list[tuple[int, int]]:
        """(iy, ix) chunk indices, row-major."""
        ny, nx = (-(-n // self.chunk) for n in self.shape)
        return [(i, j) for i in range(ny) for j in range(nx)]

    def rows_and_columns(self, iy: int, ix: int) -> tuple[slice, slice]:
        c = self.chunk
        return slice(iy * c, min((iy + 1) * c, self.shape[0])), \
            slice(ix * c, min((ix + 1) * c, self.shape[1]))

    def create(self) -> None:
        """Write the metadata (identical from every process); refuse a store made for other
        arguments (resuming needs the same map)."""
        out = Path(self.path)
        out.mkdir(parents=True, exist_ok=True)
        root = out / ".zattrs"
        if root.exists():
            try:
                made = json.loads(root.read_text()).get("jaxrod_map")
            except ValueError:
                made = None
            if made != self.description:
                raise ParameterError(f"out: {out} holds a map made with other arguments; give "
                                     "a new directory (or the same arguments to resume it)")
        else:
            created = datetime.datetime.now(datetime.timezone.utc).isoformat(
                timespec="seconds")
            _json(out / ".zgroup", {"zarr_format": 2})
            _json(root, self.attrs | {"history": "created " + created,
                                      "jaxrod_map": self.description})
        dims = [self.y.name, self.x.name]
        meta = {".zgroup": {"zarr_format": 2}, ".zattrs": json.loads(root.read_text())}
        for name, v in self.variables.items():
            meta[f"{name}/.zarray"] = _array_meta(self.shape, (self.chunk, self.chunk),
                                                  v.dtype, v.zarr_fill())
            meta[f"{name}/.zattrs"] = {"_ARRAY_DIMENSIONS": dims, "units": v.units,
                                       "long_name": v.long_name}
        for axis in (self.x, self.y):
            n = len(axis.values)
            meta[f"{axis.name}/.zarray"] = _array_meta((n,), (n,), "<f8", "NaN")
            meta[f"{axis.name}/.zattrs"] = {"_ARRAY_DIMENSIONS": [axis.name],
                                            "units": axis.units, "long_name": axis.name}
        for key, value in meta.items():
            if "/" in key:
                (out / key).parent.mkdir(exist_ok=True)
                _json(out / key, value)
        for axis in (self.x, self.y):
            _write_atomic(out / axis.name / "0", np.asarray(axis.values, "<f8").tobytes())
        # consolidated metadata (``.zmetadata``): readers open the store with one read
        _json(out / ".zmetadata", {"zarr_consolidated_format": 1, "metadata": meta})

    def done(self, iy: int, ix: int) -> bool:
        """The chunk is complete (its last variable written)."""
        return (Path(self.path) / list(self.variables)[-1] / f"{iy}.{ix}").exists()

    def write(self, iy: int, ix: int, blocks: dict[str, np.ndarray]) -> None:
        """Write one chunk's blocks (each its rows and columns of the grid), the last variable
        last."""
        c, key = self.chunk, f"{iy}.{ix}"
        for name, v in self.variables.items():
            block = np.full((c, c), v.fill, np.dtype(v.dtype))
            part = np.asarray(blocks[name])
            block[:part.shape[0], :part.shape[1]] = part
            _write_atomic(Path(self.path) / name / key, block.tobytes())

    def fill(self, solve: Callable[[int, int], dict[str, np.ndarray]], progress: bool = True,
             label: str = "map") -> dict:
        """Create the store (or reopen it) and compute this process's chunks not yet
        complete, ``solve(iy, ix)`` giving each chunk's blocks; Ctrl-C stops after the
        chunk being computed (raised as KeyboardInterrupt), keeping the finished ones.
        Returns the counts of chunks: all, this process's, computed now, resumed."""
        self.create()
        p, count = jax.process_index(), jax.process_count()
        mine = [ij for k, ij in enumerate(self.chunks()) if k % count == p]
        todo = [ij for ij in mine if not self.done(*ij)]
        bar = progress_bar(len(mine), label, "chunk", progress, len(mine) - len(todo))
        try:
            with ctrl_c_guard():
                for iy, ix in todo:
                    self.write(iy, ix, solve(iy, ix))
                    bar.update(1)
                    if interrupt_requested():  # a Ctrl-C that something swallowed
                        raise KeyboardInterrupt
        finally:
            bar.close()
        return {"chunks": len(self.chunks()), "this_process": len(mine),
                "computed": len(todo), "resumed": len(mine) - len(todo)}


def read(path: Path) -> dict[str, np.ndarray]:
    """Every array of a store written here (numpy only), by name: the 2-D variables (their
    fill where a chunk was not written) and the 1-D axes, the axes also as ``x`` and
    ``y``."""
    out = Path(path)
    meta = json.loads((out / ".zmetadata").read_text())["metadata"]
    data, dims = {}, None
    for key in meta:
        if not key.endswith("/.zarray"):
            continue
        name = key[:-len("/.zarray")]
        shape, chunks = meta[key]["shape"], meta[key]["chunks"]
        dtype, fill = np.dtype(meta[key]["dtype"]), meta[key]["fill_value"]
        arr = np.full(shape, np.nan if fill == "NaN" else fill, dtype)
        if len(shape) == 1:
            arr[:] = np.frombuffer((out / name / "0").read_bytes(), dtype)[:shape[0]]
        else:
            dims = meta[f"{name}/.zattrs"]["_ARRAY_DIMENSIONS"]
            for iy in range(-(-shape[0] // chunks[0])):
                for ix in range(-(-shape[1] // chunks[1])):
                    f = out / name / f"{iy}.{ix}"
                    if not f.exists():
                        continue
                    block = np.frombuffer(f.read_bytes(), dtype).reshape(chunks)
                    ys, xs = iy * chunks[0], ix * chunks[1]
                    h, w = min(chunks[0], shape[0] - ys), min(chunks[1], shape[1] - xs)
                    arr[ys:ys + h, xs:xs + w] = block[:h, :w]
        data[name] = arr
    if dims is not None:
        data["y"], data["x"] = data[dims[0]], data[dims[1]]
    return data


def _write_atomic(path: Path, data: bytes) -> None:
    with tempfile.NamedTemporaryFile(dir=path.parent, delete=False, prefix=".tmp-") as f:
        f.write(data)
    os.replace(f.name, path)


def _json(path: Path, obj) -> None:
    _write_atomic(path, json.dumps(obj, indent=1, sort_keys=True).encode())


def _array_meta(shape, chunks, dtype, fill):
    return {"zarr_format": 2, "shape": list(shape), "chunks": list(chunks), "dtype": dtype,
            "compressor": None, "fill_value": fill, "filters": None, "order": "C"}
