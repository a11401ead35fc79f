"""Deprecated location: ``Branch`` is in ``jaxrod.equilibria.record`` (public: ``jr.Branch``
is not needed; results carry it). This module re-exports it for one release."""

import warnings

from jaxrod.equilibria.record import Branch, branch_from_runs

warnings.warn("jaxrod.analysis.branch moved to jaxrod.equilibria.record; the old path goes "
              "in the next release", DeprecationWarning, stacklevel=2)

__all__ = ["Branch", "branch_from_runs"]
