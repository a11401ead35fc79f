"""Deprecated path of ``jaxrod.inverse.fit`` and ``jaxrod.inverse.youngs`` (their names, for
one release)."""

from jaxrod.analysis import merged

merged("fit", globals())
