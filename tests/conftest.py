import os
import sys

sys.path.insert(0, os.path.dirname(__file__))
# The CLI's persistent compilation cache stays off in the test process (and the processes it
# starts): tests must not depend on, or write into, a user's cache. (A long test process
# once aborted inside the cache's write of a compiled program.)
os.environ.setdefault("JAXROD_NO_CACHE", "1")

import jaxrod  # noqa: E402,F401  (sets float64)
