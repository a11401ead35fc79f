import atexit
import os
import shutil
import sys
import tempfile

import pytest

sys.path.insert(0, os.path.dirname(__file__))
# The CLI's persistent compilation cache stays off in the test process (and the processes it
# starts): tests must not depend on, or write into, a user's cache.
os.environ.setdefault("JAXROD_NO_CACHE", "1")
# One fresh compilation cache for this test session, shared by the test workers and every
# process they start (benchmark scripts, notebooks, the CLI): a program that several of them
# compile is compiled once. Created by the first process (the xdist controller), removed when
# it exits; the benchmark that measures compile times gives its children no cache of ours.
if "JAX_COMPILATION_CACHE_DIR" not in os.environ:
    _cache = tempfile.mkdtemp(prefix="jaxrod-test-xla-")
    atexit.register(shutil.rmtree, _cache, ignore_errors=True)
    os.environ["JAX_COMPILATION_CACHE_DIR"] = _cache
    os.environ.setdefault("JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS", "0.2")

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
