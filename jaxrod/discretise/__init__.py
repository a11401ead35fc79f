"""Discretisations of the rod's configuration: the planar angle theta(s)."""

from jaxrod.discretise.planar import PlanarDiscretisation as PlanarDiscretisation
from jaxrod.discretise.planar import planar_discretisation as planar_discretisation
