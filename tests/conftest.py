import os
import sys

sys.path.insert(0, os.path.dirname(__file__))
# The CLI's persistent compilation cache stays off in the test process (and the processes it
# starts): tests must not depend on, or write into, a user's cache. (A long test process
# once aborted inside the cache's write of a compiled program.)
os.environ.setdefault("JAXROD_NO_CACHE", "1")

import jax  # noqa: E402
import pytest  # noqa: E402

import jaxrod  # noqa: E402,F401  (sets float64)


@pytest.fixture(autouse=True, scope="module")
def _release_compiled_programs():
    """Drop JAX's in-memory compiled programs after each test module. One process runs the
    whole suite and compiles hundreds of programs; each holds memory mappings of its machine
    code, and a late test module crashed inside XLA's compiler once they had piled up."""
    yield
    jax.clear_caches()
