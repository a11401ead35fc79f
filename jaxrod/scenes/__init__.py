"""Scenes: the energy terms each physical set-up needs, and nothing else."""

from jaxrod.scenes.dipole import DipoleMagnet as DipoleMagnet
from jaxrod.scenes.uniform import UniformField as UniformField
