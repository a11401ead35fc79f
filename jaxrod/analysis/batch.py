"""Deprecated path of ``jaxrod.magnet.batch`` (an alias for one release)."""

from jaxrod.analysis import alias

alias('batch')
