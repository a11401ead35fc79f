"""Deprecated path of ``jaxrod.bistability.design_map`` (an alias for one release)."""

from jaxrod.analysis import alias

alias('design_map')
