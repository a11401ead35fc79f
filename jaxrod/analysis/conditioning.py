"""Deprecated path of ``jaxrod.magnet.conditioning`` (an alias for one release)."""

from jaxrod.analysis import alias

alias('conditioning')
