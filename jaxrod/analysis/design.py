"""Deprecated path of ``jaxrod.inverse.design`` (an alias for one release)."""

from jaxrod.analysis import alias

alias('design')
