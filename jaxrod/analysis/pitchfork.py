"""Deprecated path of ``jaxrod.uniform.pitchfork`` (an alias for one release)."""

from jaxrod.analysis import alias

alias('pitchfork')
