"""Deprecated path of ``jaxrod.inverse.calibration`` (an alias for one release)."""

from jaxrod.analysis import alias

alias('calibration')
