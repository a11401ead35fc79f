"""Deprecated path of ``jaxrod.magnet.reduction`` (an alias for one release)."""

from jaxrod.analysis import alias

alias('reduction')
