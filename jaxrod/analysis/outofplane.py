"""Deprecated path of ``jaxrod.three_d.outofplane`` (an alias for one release)."""

from jaxrod.analysis import alias

alias('outofplane')
