"""Solvers over residual functions ``F(x, args)``: Newton, continuation."""

from jaxrod.solvers.newton import NewtonResult as NewtonResult
from jaxrod.solvers.newton import newton as newton
