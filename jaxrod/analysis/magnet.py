"""Deprecated path of ``jaxrod.magnet.diagram``, ``jaxrod.magnet.folds`` and
``jaxrod.magnet.sweep`` (their names, for one release)."""

from jaxrod.analysis import merged

merged("magnet", globals())
