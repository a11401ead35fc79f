"""``python -m jaxrod.cli``."""

from jaxrod.cli import run

run()
