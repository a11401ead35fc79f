"""Deprecated path of ``jaxrod.uniform.greenhill`` (an alias for one release)."""

from jaxrod.analysis import alias

alias('greenhill')
