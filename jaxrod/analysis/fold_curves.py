"""Deprecated path of ``jaxrod.bistability.fold_curves`` (an alias for one release)."""

from jaxrod.analysis import alias

alias('fold_curves')
