"""How programs are compiled (``jaxrod.programs``): one program per call form."""

import numpy as np
import pytest

from jaxrod.programs import jit


def test_one_program_whatever_the_call_form():
    """f(x), f(x, n=3), f(x, 3) and f(x=x): one trace; a dynamic argument given (by position
    or keyword, a Python or a numpy float) is an input, one more program; a new static
    value, another."""
    traces = []

    @jit(static_argnames=("n",))
    def f(x, n=3, scale=1.0):
        traces.append(n)
        return x * n * scale

    x = np.arange(4.0)
    answers = [f(x), f(x, n=3), f(x, 3), f(x=x)]
    assert traces == [3]
    answers += [f(x, 3, 1.0), f(x, scale=np.float64(1.0)), f(scale=1.0, x=x, n=3)]
    assert traces == [3, 3]
    assert all(np.array_equal(a, 3.0 * x) for a in answers)
    f(x, 4)
    assert traces == [3, 3, 4]


def test_a_wrong_call_is_reported_as_python_reports_it():
    @jit(static_argnames=("n",))
    def g(x, n, scale=1.0):
        return x * n * scale

    for call in (lambda: g(1.0, scale=2.0), lambda: g(1.0, 2, n=2), lambda: g(1.0, 2, k=1)):
        with pytest.raises(TypeError):
            call()


def test_a_program_compiled_ahead_serves_the_call_of_its_shapes():
    """compile_ahead with a placeholder of the input's shape: the program is traced and
    compiled on another thread, and the later calls of that shape compile nothing (counted
    with jax.monitoring); a call of another shape or static value compiles as always."""
    import threading

    import jax

    compiled_here = []

    def listener(name, _, **kw):
        if name.endswith("backend_compile_duration") and \
                threading.current_thread() is threading.main_thread():
            compiled_here.append(name)

    jax.monitoring.register_event_duration_secs_listener(listener)
    traces = []

    @jit(static_argnames=("n",))
    def f(x, scale, n=2):
        traces.append(x.shape)
        return x * scale * n

    f.compile_ahead(jax.ShapeDtypeStruct((3,), np.float64), 2.0, n=2)
    x = np.arange(3.0)
    assert np.array_equal(f(x, 0.5), x)
    assert np.array_equal(f(x, scale=3.0, n=2), 6.0 * x)
    assert traces == [(3,)] and compiled_here == []
    assert np.array_equal(f(np.arange(4.0), 1.0), 2.0 * np.arange(4.0))
    assert np.array_equal(f(x, 1.0, n=3), 3.0 * x)
    jax.monitoring.unregister_event_duration_listener(listener)
    assert traces == [(3,), (4,), (3,)] and len(compiled_here) == 2
