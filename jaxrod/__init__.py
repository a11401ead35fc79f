"""jaxrod: differentiable equilibria and stability of ferromagnetic Kirchhoff rods."""

import jax

jax.config.update("jax_enable_x64", True)
