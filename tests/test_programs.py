"""How programs are compiled (``jaxrod.programs``): one program per call form and per
doubling of a loop's step count."""

import jax
import jax.numpy as jnp
import numpy as np

from jaxrod.programs import jit, loop_length, scan_first


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


def test_loop_lengths_are_doublings():
    assert [loop_length(k) for k in (1, 8, 9, 100, 128, 129, 1000)] == \
        [8, 8, 16, 128, 128, 256, 1024]
    assert all(k <= loop_length(k) < 2 * k for k in range(8, 5000))


def test_scan_first_takes_the_first_steps_only():
    """The first ``steps`` outputs and the carry equal lax.scan's over ``steps``; every step
    count up to the length runs one compiled program."""
    traces = []

    def step(c, k):
        return c * 1.5 + jnp.sin(k), (c, 2 * k)

    @jax.jit
    def run(c0, steps):
        traces.append(1)
        return scan_first(step, c0, steps, 64)

    for steps in (1, 37, 64):
        (c, (cs, ks)) = run(jnp.asarray(0.25), steps)
        c_ref, (cs_ref, ks_ref) = jax.lax.scan(step, jnp.asarray(0.25), jnp.arange(steps))
        assert c == c_ref
        np.testing.assert_array_equal(cs[:steps], cs_ref)
        np.testing.assert_array_equal(ks[:steps], ks_ref)
        assert np.all(cs[steps:] == 0.0) and np.all(ks[steps:] == 0)
    assert len(traces) == 1
