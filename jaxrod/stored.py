"""Compiled entry points kept between processes: ``jax.export`` next to the persistent
compilation cache.

JAX's persistent compilation cache skips XLA's compilation in a later process, but not the
tracing of the Python function into a program, which for the continuation and fold programs
takes seconds. A ``StoredProgram`` behaves as ``jaxrod.programs.jit(fn)``; when a store is enabled
(the command line enables one next to its compilation cache) it also serialises the traced
program (``jax.export``) on its first call for each input structure, and a later process
deserialises it instead of tracing. Files are keyed by the program's name, the jaxrod and jax
versions (and the package's source files, so that an edited installation never runs an old
program), the backend, the static arguments and the input tree with its shapes and dtypes;
a missing, unreadable or stale file falls back to tracing (and is rewritten). Inside another
trace (jit, vmap, grad of the caller) the plain jitted function is used. Stored programs are
compiled with the same XLA options as the others (``jaxrod.programs``).
"""

from __future__ import annotations

import functools
import hashlib
import importlib.metadata
import inspect
import os
import pickle
import tempfile
from collections.abc import Callable
from pathlib import Path

import jax
import numpy as np

from jaxrod.programs import jit

_store: list[Path | None] = [None]


def enable_store(directory: str | os.PathLike | None) -> None:
    """Keep exported programs in ``directory`` (None switches the store off; so does a
    missing ``flatbuffers``, which jax.export's serialisation needs)."""
    try:
        import flatbuffers  # noqa: F401
    except ImportError:
        directory = None
    _store[0] = None if directory is None else Path(directory)
    if _store[0] is not None:
        _store[0].mkdir(parents=True, exist_ok=True)


def default_cache_dir() -> Path:
    """The folder of the caches: $JAXROD_CACHE_DIR, else ~/.cache/jaxrod/xla."""
    return Path(os.environ.get("JAXROD_CACHE_DIR",
                               os.path.join(os.path.expanduser("~"), ".cache", "jaxrod", "xla")))


def enable_caches(directory: str | os.PathLike | None = None) -> Path | None:
    """Keep compiled programs on disk for later processes, as the command line does: JAX's
    persistent compilation cache (programs that took over 0.2 s to compile) and, beside it,
    jaxrod's traced entry points (``enable_store``). A fresh Python process then loads what
    an earlier one compiled instead of compiling it again (the README's tour: about 18 s of
    compilation the first time, a few seconds after). ``directory``: default
    ``default_cache_dir()``. Returns the folder, or None if it cannot be written (the caches
    stay off; nothing else changes)."""
    cache = Path(directory) if directory is not None else default_cache_dir()
    try:
        cache.mkdir(parents=True, exist_ok=True)
    except OSError:
        return None
    jax.config.update("jax_compilation_cache_dir", str(cache))
    jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.2)
    enable_store(cache / "exported")
    return cache


@functools.cache
def _source_fingerprint() -> str:
    """jaxrod's version and the size and modification time of each of its source files."""
    try:
        version = importlib.metadata.version("jaxrod")
    except importlib.metadata.PackageNotFoundError:
        version = "unknown"
    package = Path(__file__).resolve().parent
    files = sorted((str(p.relative_to(package)), p.stat().st_size, p.stat().st_mtime_ns)
                   for p in package.rglob("*.py"))
    return hashlib.sha256(repr((version, files)).encode()).hexdigest()


class StoredProgram:
    """``jaxrod.programs.jit(fn, static_argnames)`` whose traced programs persist in the store."""

    def __init__(self, name: str, fn: Callable, static_argnames: tuple[str, ...] = ()):
        self.name = name
        self.jitted = jit(fn, static_argnames=static_argnames)
        self._fn = fn
        self._signature = inspect.signature(fn)
        self._static = static_argnames
        self._loaded: dict[str, tuple] = {}

    def __call__(self, *args, **kwargs):
        if _store[0] is None:
            return self.jitted(*args, **kwargs)
        bound = self._signature.bind(*args, **kwargs)
        bound.apply_defaults()
        dynamic = dict(bound.arguments)
        static = {k: dynamic.pop(k) for k in self._static}
        leaves, tree = jax.tree_util.tree_flatten(dynamic)
        if any(isinstance(x, jax.core.Tracer) for x in leaves):
            return self.jitted(*args, **kwargs)
        leaves = [np.asarray(x) for x in leaves]
        key = self._key(tree, leaves, static)
        entry = self._loaded.get(key) or self._read(key) or self._export(key, tree, leaves,
                                                                           static)
        call, out_tree = entry
        return jax.tree_util.tree_unflatten(out_tree, call(*leaves))

    def _key(self, tree, leaves, static) -> str:
        description = repr((self.name, _source_fingerprint(), jax.__version__,
                            jax.default_backend(),
                            sorted(static.items()), str(tree),
                            [(x.shape, str(x.dtype)) for x in leaves]))
        return hashlib.sha256(description.encode()).hexdigest()[:32]

    def _path(self, key: str) -> Path:
        return _store[0] / f"{self.name}-{key}.jaxexport"

    def _read(self, key: str):
        try:
            blob = self._path(key).read_bytes()
            serialised, out_tree = pickle.loads(blob)
            entry = (jit(jax.export.deserialize(bytearray(serialised)).call), out_tree)
        except Exception:  # missing, truncated or written by another version: trace again
            return None
        self._loaded[key] = entry
        return entry

    def _export(self, key: str, tree, leaves, static):
        out_trees = []

        def flat(*xs):
            out, out_tree = jax.tree_util.tree_flatten(
                self._fn(**jax.tree_util.tree_unflatten(tree, xs), **static))
            out_trees.append(out_tree)
            return out

        exported = jax.export.export(jax.jit(flat))(*leaves)
        entry = (jit(exported.call), out_trees[0])
        self._loaded[key] = entry
        blob = pickle.dumps((bytes(exported.serialize()), entry[1]))
        # write to a temporary file and rename it: a concurrent reader never sees half a file
        with tempfile.NamedTemporaryFile(dir=_store[0], delete=False) as f:
            f.write(blob)
        os.replace(f.name, self._path(key))
        return entry
