"""How jaxrod's programs are compiled: ``jit``, which is ``jax.jit`` with XLA options, and the
batch sizes batched programs are compiled for (``bucket``, ``padded``).

jaxrod's solvers are small dense linear algebra inside nested ``lax.while_loop``s, and on a
CPU most of a first call is XLA's code generation for a few hundred small fused kernels.
XLA's CPU backend has two code generators for fused kernels; the older one (chosen by
``xla_cpu_use_fusion_emitters = False``) compiles these programs about twice as fast and
runs them as fast or faster. Measured on a 2-core x86_64 CPU with jax 0.10.2, the
one-program fold pair (``fold_angles``, N = 12): first call 4.1 s -> 2.1 s, warm call
2.0 ms -> 1.9 ms; 1000 batched fold pairs 268 ms -> 235 ms (benchmarks/compile_time.py and
benchmarks/throughput.py measure it for every entry point). XLA's CPU runtime can also
deadlock when a kernel inside a program's loops hands work to its multi-threaded Eigen pool
(jax 0.10.2, 2 cores: the vmapped condition numbers of ``conditioning_near_fold`` hung on
their second call, idle, every time); ``xla_cpu_multi_thread_eigen = False`` runs those
kernels on the calling thread. jaxrod's matrices are small (N + 1 <= a few hundred): 1000
fold pairs run at 3410-3430 per second against 3420-3470 without it and one fold pair in
3.0-3.1 ms either way; the paper's ``folds`` (N = 16, the diagram and both folds) takes
20 ms warm against 17 ms. On other backends the options are ignored.

An analysis that runs programs one after another, each waiting for the last one's answer,
can start compiling the later ones (whose inputs' shapes it knows) on a background thread
while the first runs (``Program.compile_ahead``): XLA's compilation releases Python, so on
two cores the compilations overlap. The fit of the paper's Young's modulus (the fold
guesses' branch, then the fit) takes 5.8-6.2 s from a fresh process against 6.5-6.7 s one
after the other, the cusp (the fold pair, then the fold curves and the cusp's refinement)
12.0-12.8 s against 13.3-14.3 s, measured in one run on 2 cores. Only a program sure to
run is compiled ahead: XLA's compiler itself uses both cores, so a compilation that
overlaps another slows it. The folds of a scene compiling their refinement while the
branch is traced took 3.8-3.9 s against 4.2-4.4 s, but 3.6-3.8 s against 2.6 s where the
branch had no fold to refine; they do not. A program already compiled for those shapes is
found in JAX's own cache (nothing is compiled twice).

The options are passed to each program's compilation (``jax.jit``'s ``compiler_options``),
not set process-wide, so a user's own programs are compiled as they would be without
jaxrod. They are checked once, on the first compilation, against the installed XLA (a
version that does not know an option compiles without it); until then nothing touches a
backend, so ``jax.distributed.initialize`` and device-count settings still work after
``import jaxrod``.
"""

from __future__ import annotations

import concurrent.futures
import functools
import inspect
from collections.abc import Callable

import jax
import numpy as np

#: XLA options for jaxrod's programs (module docstring).
COMPILER_OPTIONS = {"xla_cpu_use_fusion_emitters": False, "xla_cpu_multi_thread_eigen": False}


@functools.cache
def compiler_options() -> dict:
    """``COMPILER_OPTIONS`` if the installed jax and XLA accept them, else {} (checked once by
    compiling a one-line program)."""
    try:
        jax.jit(lambda x: x + 1, compiler_options=COMPILER_OPTIONS).lower(1.0).compile()
    except Exception:  # an older jax without compiler_options, or an XLA without the option
        return {}
    return dict(COMPILER_OPTIONS)


def _inside_a_trace() -> bool:
    """Whether a call made now is traced (into an enclosing jit, or under grad or vmap)
    rather than run at the top level; True where jax does not say (a plain nested jit is
    always valid). jax takes compiler options only from a top-level program (under grad it
    stages the call into a new one)."""
    try:
        from jax._src import core
        return not core.trace_state_clean()
    except (ImportError, AttributeError):
        return True


_EMPTY = inspect.Parameter.empty


def _strong(leaf):
    """A Python float or int as a float64 or int64 numpy scalar (a strongly typed input);
    other leaves unchanged."""
    if type(leaf) is float:
        return np.float64(leaf)
    if type(leaf) is int:
        return np.int64(leaf)
    return leaf


class Program:
    """``jax.jit(fn, **kwargs)`` compiled with ``compiler_options()``, built on first use.

    Called at the top level it compiles with the options; inside another trace (jit, grad,
    vmap) it is a plain nested ``jax.jit``. ``lower`` and every other attribute go to the
    top-level function.

    At the top level, Python floats and ints among the dynamic inputs (a scene's inputs, say)
    are passed as float64 and int64 scalars: JAX gives Python numbers a weak type and compiles
    a program for them apart from the one for numpy numbers of the same shape, so that a
    scene made of Python floats and one made of numpy floats compiled twice (jaxrod's programs
    compute in float64; the float32 path casts its inputs itself). For the same reason every
    call is put in one form, its arguments by position and its static arguments' defaults
    filled in: ``f(x)``, ``f(x, n=12)`` and ``f(x, 12)`` are one call to JAX, not three
    programs.
    """

    def __init__(self, fn: Callable, **kwargs):
        # name and docstring only: fn's __dict__ may hold another Program's attributes
        functools.update_wrapper(self, fn, updated=())
        self._fn = fn
        self._kwargs = kwargs
        self._jitted = None
        self._ahead = {}  # compile_ahead's compilations under way, by the call's abstract key
        self.nested = jax.jit(fn, **kwargs)
        names = set(kwargs.get("static_argnames", ()) if not isinstance(
            kwargs.get("static_argnames"), str) else (kwargs["static_argnames"],))
        numbers = kwargs.get("static_argnums", ())
        numbers = {numbers} if isinstance(numbers, int) else set(numbers)
        try:
            self._signature = inspect.signature(fn)
            params = list(self._signature.parameters)
        except (TypeError, ValueError):  # no signature: leave the inputs as they are
            params = None
        self._static_names = names | {params[i] for i in numbers if params and i < len(params)}
        self._static_positions = numbers | {i for i, p in enumerate(params or ()) if p in names}
        self._canonical = params is not None
        # a signature of plain parameters is put in its one form without inspect's binding
        # (a few microseconds instead of some 30 per call); others are bound by inspect
        plain = params is not None and all(
            p.kind is inspect.Parameter.POSITIONAL_OR_KEYWORD
            for p in self._signature.parameters.values())
        self._plain = tuple(params) if plain else None
        self._plain_names = frozenset(params) if plain else frozenset()
        defaults = {p.name: p.default for p in self._signature.parameters.values()} \
            if params is not None else {}
        self._defaults = defaults
        self._static_defaults = {k: v for k, v in defaults.items()
                                 if k in self._static_names and v is not _EMPTY}

    def _strong_inputs(self, args, kwargs):
        """The call's dynamic inputs with Python numbers made strongly typed (class docstring)."""
        if not self._canonical:
            return args, kwargs
        args, kwargs = self._one_form(args, kwargs)
        args = tuple(a if i in self._static_positions else jax.tree_util.tree_map(_strong, a)
                     for i, a in enumerate(args))
        kwargs = {k: v if k in self._static_names else jax.tree_util.tree_map(_strong, v)
                  for k, v in kwargs.items()}
        return args, kwargs

    def _one_form(self, args, kwargs):
        """The call in one form, whichever way it was written (class docstring): every
        argument by position (programs of ``vmap``ped functions take no keywords), every
        static argument present (its default filled in); a dynamic argument left out stays
        left out (a constant of the program) unless a later one is given. inspect binds the
        signatures that are not plain, and reports a wrong call."""
        plain = self._plain
        if not kwargs and plain is not None and len(args) == len(plain):
            return args, kwargs
        if plain is not None and len(args) <= len(plain) and kwargs.keys() <= self._plain_names \
                and not any(name in kwargs for name in plain[:len(args)]):
            out, missing = list(args), []
            for name in plain[len(args):]:
                if name in kwargs:
                    out += missing + [kwargs[name]]
                    missing = []
                elif name in self._static_defaults:
                    out += missing + [self._static_defaults[name]]
                    missing = []
                elif self._defaults.get(name, _EMPTY) is not _EMPTY:
                    missing.append(self._defaults[name])
                else:
                    break  # a required argument left out: inspect says so
            else:
                return tuple(out), {}
        bound = self._signature.bind(*args, **kwargs)
        for name, default in self._static_defaults.items():
            bound.arguments.setdefault(name, default)
        return bound.args, bound.kwargs

    @property
    def jitted(self):
        if self._jitted is None:
            options = compiler_options()
            self._jitted = jax.jit(self._fn, compiler_options=options, **self._kwargs) \
                if options else self.nested
        return self._jitted

    def compile_ahead(self, *args, **kwargs) -> None:
        """Start compiling the top-level program for a later call with arguments of these
        shapes and dtypes (arrays, or ``jax.ShapeDtypeStruct`` where the values are not
        known yet) on a background thread, while the caller computes those values: that
        call then waits for it instead of compiling (module docstring). Does nothing inside
        a trace or where the call is already prepared."""
        if _inside_a_trace():
            return
        args, kwargs = self._strong_inputs(args, kwargs)
        key = self._abstract_key(args, kwargs)
        if key is None or key in self._ahead:
            return
        self._ahead[key] = _background().submit(
            lambda: self.jitted.lower(*args, **kwargs).compile())

    def _abstract_key(self, args, kwargs):
        """The call's structure, shapes, dtypes and static values (None if a static value
        cannot be hashed)."""
        dynamic = [a for i, a in enumerate(args) if i not in self._static_positions]
        static = tuple((i, a) for i, a in enumerate(args) if i in self._static_positions)
        static += tuple(sorted((k, v) for k, v in kwargs.items() if k in self._static_names))
        dynamic_kw = {k: v for k, v in kwargs.items() if k not in self._static_names}
        leaves, tree = jax.tree_util.tree_flatten((dynamic, dynamic_kw))
        try:
            return hash(static), static, tree, tuple(
                (np.shape(x), np.dtype(getattr(x, "dtype", None) or np.asarray(x).dtype),
                 bool(getattr(x, "weak_type", False))) for x in leaves)
        except TypeError:
            return None

    def __call__(self, *args, **kwargs):
        if _inside_a_trace():
            return self.nested(*args, **kwargs)
        args, kwargs = self._strong_inputs(args, kwargs)
        if self._ahead:
            future = self._ahead.pop(self._abstract_key(args, kwargs), None)
            if future is not None:
                # wait for it: the call below then finds the executable in JAX's cache (a
                # failure ahead is the call's own to report)
                concurrent.futures.wait([future])
            # a compilation whose call never came is dropped once done (the plain path again)
            self._ahead = {k: f for k, f in self._ahead.items() if not f.done()}
        return self.jitted(*args, **kwargs)

    def __getattr__(self, name):
        if name.startswith("__"):
            raise AttributeError(name)
        return getattr(self.jitted, name)


@functools.cache
def _background():
    """The one thread ``compile_ahead`` compiles on (joined before the interpreter exits)."""
    return concurrent.futures.ThreadPoolExecutor(max_workers=1,
                                                 thread_name_prefix="jaxrod-compile")


def jit(fn: Callable | None = None, /, **kwargs):
    """``jax.jit`` for jaxrod's programs (module docstring); also a decorator with keyword
    arguments, ``@jit(static_argnames=...)``."""
    if fn is None:
        return functools.partial(jit, **kwargs)
    return Program(fn, **kwargs)


# --- batch sizes: one program per bucket, not per batch size ---------------------------

#: The smallest padded batch of several sets: on a CPU a batch of 8 runs in 2-4x the time of
#: a batch of 1 (``jaxrod.magnet.batch``: its tier 1 2.9 ms against 1.4 ms, its batched
#: continuation 42 ms against 11 ms),
#: while each distinct batch size compiles its own program (10-15 s): batches of 2 to 8
#: share one. One set keeps its own (the single fold pair's time); the retry tiers, whose
#: batches are the failures of a batch, always take at least 8 (``retry_size``).
MIN_BATCH = 8


def bucket(k: int) -> int:
    """The padded size of a batch of k: 1 for one set, ``MIN_BATCH`` (8) for 2 to 8, then
    m 2^j with m in 8..15 (at most 1/8 of padding): programs compile once per bucket, not
    per batch size."""
    if k <= 1:
        return 1
    if k <= MIN_BATCH:
        return MIN_BATCH
    j = (k - 1).bit_length() - 4
    return -(-k // (1 << j)) * (1 << j)


def retry_size(k: int) -> int:
    """The padded size of a retry tier's batch of k failures: ``bucket``, at least 8."""
    return max(MIN_BATCH, bucket(k))


def padded(arrays, size: int | None = None, multiple: int = 1):
    """The arrays padded along their first axis to ``size`` (default ``bucket``) rounded up
    to a multiple of ``multiple`` (the devices a batch is split over) by repeating their
    first entry (a valid parameter set; the padding's answers are dropped)."""
    k = arrays[0].shape[0]
    size = bucket(k) if size is None else size
    size = -(-size // multiple) * multiple
    if size == k:
        return list(arrays)
    return [np.concatenate([a, np.repeat(a[:1], size - k, axis=0)]) for a in arrays]


def steps_loop(step: Callable, carry, steps, budget: int | None = None):
    """``lax.scan(step, carry, arange(steps))``'s (carry, outputs) with a static step
    ``budget`` and ``steps`` traced (the shape of diffrax's ``max_steps``): the loop runs
    ``steps`` times (a ``fori_loop``) into outputs of ``budget`` rows, the rows past
    ``steps`` left zero; one program serves every count up to the budget (``bucket``).
    ``budget`` None: ``steps`` is static and the loop a scan (reverse-mode
    differentiable)."""
    import jax.numpy as jnp

    if budget is None:
        return jax.lax.scan(step, carry, jnp.arange(steps))
    shapes = jax.eval_shape(lambda c: step(c, jnp.asarray(0))[1], carry)
    rows = jax.tree_util.tree_map(lambda s: jnp.zeros((budget, *s.shape), s.dtype), shapes)

    def body(k, state):
        c, out = state
        c, o = step(c, k)
        return c, jax.tree_util.tree_map(lambda r, v: r.at[k].set(v), out, o)

    return jax.lax.fori_loop(0, steps, body, (carry, rows))
