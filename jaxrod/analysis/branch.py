"""Deprecated path of ``jaxrod.equilibria.record`` (an alias for one release)."""

from jaxrod.analysis import alias

alias('branch')
