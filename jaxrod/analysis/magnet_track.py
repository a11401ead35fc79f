"""Deprecated path of ``jaxrod.three_d.track`` (an alias for one release)."""

from jaxrod.analysis import alias

alias('magnet_track')
