"""Deprecated path of ``jaxrod.magnet.contraction`` (an alias for one release)."""

from jaxrod.analysis import alias

alias('contraction')
