import os
import sys

sys.path.insert(0, os.path.dirname(__file__))

import jaxrod  # noqa: E402,F401  (sets float64)
