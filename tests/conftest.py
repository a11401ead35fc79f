import os
import sys

import pytest

sys.path.insert(0, os.path.dirname(__file__))
# The CLI's persistent compilation cache stays off in the test process (and the processes it
# starts): tests must not depend on, or write into, a user's cache.
os.environ.setdefault("JAXROD_NO_CACHE", "1")
# No persistent XLA compilation cache either: the test processes (xdist workers, and the
# benchmark scripts, notebooks and CLI runs they start) must not read executables that other
# processes are writing. A shared cache once took a worker down inside XLA's deserialisation
# (a fatal signal, not an exception), and pytest-xdist's grouped scheduling then waits forever
# for the lost worker. Each process compiles what it runs.
for _variable in ("JAX_COMPILATION_CACHE_DIR", "JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS"):
    os.environ.pop(_variable, None)

import jaxrod  # noqa: E402,F401  (sets float64)

#: Modules whose tests each run in their own subprocess: spread over the xdist workers one
#: test at a time. Every other module stays on one worker, so that its module-scoped fixtures
#: and compiled programs are built once.
SPREAD = {"test_benchmarks.py", "test_notebooks.py"}


def pytest_collection_modifyitems(config, items):
    for item in items:
        name = os.path.basename(str(item.fspath))
        if name not in SPREAD:
            item.add_marker(pytest.mark.xdist_group(name))
    # the long subprocess tests first, so that no worker is left with one at the end
    items.sort(key=lambda item: os.path.basename(str(item.fspath)) not in SPREAD)
