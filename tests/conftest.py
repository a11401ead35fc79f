import atexit
import os
import shutil
import sys
import tempfile

import pytest

sys.path.insert(0, os.path.dirname(__file__))
# One fresh cache folder for this test session, shared by the test workers and every process
# they start (benchmark scripts, notebooks, the CLI): JAX's compilation cache, so that a
# program that several of them compile is compiled once, and the command line's store of
# traced programs (``jaxrod.stored``; the CLI keeps its caches on, as it does for users), so
# that a command run in several processes (a map interrupted and resumed, say) is traced once.
# Tests never read or write a user's cache. Created by the first process (the xdist
# controller), removed when it exits; the benchmark that measures compile times gives its
# children no cache of ours.
if "JAXROD_TEST_CACHE" not in os.environ:
    _cache = tempfile.mkdtemp(prefix="jaxrod-test-cache-")
    atexit.register(shutil.rmtree, _cache, ignore_errors=True)
    os.environ["JAXROD_TEST_CACHE"] = _cache
    os.environ["JAXROD_CACHE_DIR"] = _cache
    os.environ.setdefault("JAX_COMPILATION_CACHE_DIR", _cache)
    os.environ.setdefault("JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS", "0.2")

import jaxrod  # noqa: E402,F401  (sets float64)

#: Modules whose tests each run in their own subprocess: spread over the xdist workers one
#: test at a time. Every other module stays on one worker, so that its module-scoped fixtures
#: and compiled programs are built once.
SPREAD = {"test_benchmarks.py", "test_notebooks.py"}
#: Modules of the slow tier as a whole (``python -m pytest -m slow``): the benchmarks' quick
#: forms and the notebooks, each a process of its own.
SLOW = SPREAD


def pytest_collection_modifyitems(config, items):
    for item in items:
        name = os.path.basename(str(item.fspath))
        if name in SLOW:
            item.add_marker(pytest.mark.slow)
        if name not in SPREAD:
            item.add_marker(pytest.mark.xdist_group(name))
    # the long subprocess tests first, so that no worker is left with one at the end
    items.sort(key=lambda item: os.path.basename(str(item.fspath)) not in SPREAD)


#: Memory mappings above which a test process drops its compiled programs between modules.
#: XLA's CPU backend maps every executable's code and data; a worker that compiles many
#: distinct programs (each module its own scenes, degrees and shapes) approaches the kernel's
#: limit (vm.max_map_count, 65530 by default) and then aborts inside a compilation. The
#: mappings of repeated calls stay flat (tests/test_soak.py); this is only about how many
#: different programs one process holds.
MAPPINGS_HIGH = 25_000


def _mappings() -> int:
    try:
        with open("/proc/self/maps") as f:
            return sum(1 for _ in f)
    except OSError:  # not Linux: no such limit to watch
        return 0


@pytest.fixture(scope="module", autouse=True)
def _release_programs_when_mappings_are_high():
    yield
    if _mappings() > MAPPINGS_HIGH:
        import gc

        import jax

        jax.clear_caches()
        gc.collect()

