"""Time scale and drag of a physical rod.

Time: the nondimensional time of ``jaxrod.dynamics`` is t / T with

    T = L^2 sqrt(rho A_c / (E I))   (A_c = pi r^2, I = pi r^4 / 4),

and a linear drag c_phys (force per unit length per unit velocity, N s / m^2) is the
nondimensional damping c = c_phys T / (rho A_c).

Air: a thin cylinder moving across its axis at low Reynolds number Re = rho_f U d / mu
feels Lamb's drag per unit length (Lamb 1911, Oseen's approximation)

    f = 4 pi mu U / (1/2 - gamma - ln(Re / 8)),   gamma = 0.5772...,

linear in U up to the logarithm; ``lamb_drag`` gives the coefficient c_phys = f / U at a
reference speed (the snap's peak speed, found by iterating, ``jaxrod snap --medium air``).
Valid for Re << 1 (a 50 um wire at 1 m/s in air: Re ~ 3).
"""

from __future__ import annotations

import math

from jaxrod.params import ParameterError

EULER_GAMMA = 0.5772156649015329
#: Air at 20 C: dynamic viscosity (Pa s) and density (kg/m^3).
AIR = {"viscosity": 1.81e-5, "density": 1.204}


def time_scale(length: float, radius: float, youngs_modulus: float, density: float) -> float:
    """T = L^2 sqrt(rho A_c / (E I)), seconds (a solid round rod of the given radius)."""
    for name, v in (("length", length), ("radius", radius),
                    ("youngs_modulus", youngs_modulus), ("density", density)):
        if not (math.isfinite(v) and v > 0):
            raise ParameterError(f"{name} must be a finite number > 0, got {v!r}")
    area, inertia = math.pi * radius**2, math.pi * radius**4 / 4.0
    return length**2 * math.sqrt(density * area / (youngs_modulus * inertia))


def lamb_drag(radius: float, speed: float, viscosity: float = AIR["viscosity"],
              fluid_density: float = AIR["density"]) -> float:
    """Lamb's drag coefficient per unit length (N s / m^2) at ``speed`` (m/s)."""
    if not (speed > 0 and math.isfinite(speed)):
        raise ParameterError(f"speed must be a finite number > 0, got {speed!r}")
    re = fluid_density * speed * 2.0 * radius / viscosity
    denominator = 0.5 - EULER_GAMMA - math.log(re / 8.0)
    if denominator <= 0.5:
        raise ParameterError(f"Lamb's drag needs a small Reynolds number; Re = {re:.3g} here")
    return 4.0 * math.pi * viscosity / denominator


def nondimensional_damping(c_phys: float, length: float, radius: float,
                           youngs_modulus: float, density: float) -> float:
    """c = c_phys T / (rho A_c)."""
    T = time_scale(length, radius, youngs_modulus, density)
    return c_phys * T / (density * math.pi * radius**2)
