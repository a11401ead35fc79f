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
