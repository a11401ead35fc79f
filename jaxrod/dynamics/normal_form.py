"""The fold's normal form in time: how much later than the static fold a rod swept at a
finite rate switches (Gomez, Moulton and Vella, Nature Physics 2017; Liu, Gomez and Vella,
JMPS 2021).

Near a fold (v*, x*) of grad E(x; v) = 0 with the Hessian's kernel phi, the motion
x = x* + a(t) phi + ... of Lagrange's equations with the mass matrix M and a linear drag c
(``jaxrod.dynamics.integrate``) projects onto phi as

    m a'' + c m a' = -A (v - v*) - B a^2,
    m = phi . M phi,   A = phi . d(grad E)/dv,   B = D^3E[phi, phi, phi] / 2,

(``jaxrod.equilibria.folds``' dF/dv and d2F/dq2 with phi scaled to int phi = 1). With the
input moving at the rate eps past v*, v - v* = eps t, the scalings

    inertial   T_i = (m^2 / (|A B| eps))^(1/5):   x'' + k x' = -tau - x^2,   k = c T_i,
    damped     T_d = (c^2 m^2 / (|A B| eps))^(1/3):   x'' / k^(5/3) + x' = -tau - x^2

leave one parameter k. The solution that follows the stable branch x = sqrt(-tau) from
tau = -infinity escapes to -infinity at a finite tau*(k): the rod switches at the lag

    v_switch - v* = eps T tau*(k)

(T = T_i for k <= 1, T_d above). Its limits are power laws in eps:

    damped     (k -> infinity)  lag = tau_d (c^2 m^2 / |A B|)^(1/3) eps^(2/3),
               tau_d = 2.33810741..., the first zero of Ai(-tau) (x = -Ai'/Ai);
    inertial   (c = 0)          lag = tau_i (m^2 / |A B|)^(1/5) eps^(4/5),
               tau_i = 3.41167179... (Painleve I: x'' = -tau - x^2),

crossing over at the rate where the two are equal (slower: the drag dominates).
``escape_time`` integrates the scaled equation (classical RK4, a step shrinking as the
solution runs away, the tail beyond x = -X in closed form); tests/test_normal_form.py checks
tau_d against scipy's Airy zero and tau_i against scipy's solve_ivp.
"""

from __future__ import annotations

import dataclasses
import functools
import math

import jax.numpy as jnp
import numpy as np

from jaxrod.dynamics.modes import mass_matrix
from jaxrod.equilibria.equilibrium import DEFAULT_N, discretise
from jaxrod.equilibria.folds import Fold
from jaxrod.params import ParameterError
from jaxrod.scenes.scene import Scene

DAMPED_EXPONENT = 2.0 / 3.0
INERTIAL_EXPONENT = 4.0 / 5.0
_EPS_RICCATI = 1e-4  # below this x''/k^(5/3) is dropped (its effect on tau*: ~0.1%)


@functools.lru_cache(maxsize=256)
def escape_time(inertia: float, drag: float, tau0: float = -24.0, h0: float = 2e-3,
                escape: float = 1e8) -> float:
    """tau* of inertia x'' + drag x' = -tau - x^2 from the stable branch x ~ sqrt(-tau)
    at tau0 (``inertia`` = 0: the Riccati equation drag x' = -tau - x^2)."""
    # the stable branch's expansion in z = -tau: x = sqrt(z) + d1 + d2 + O(z^-5), from
    # inertia x_zz - drag x_z = z - x^2 order by order
    a, b, z = inertia, drag, -tau0
    x = (math.sqrt(z) + b / (4 * z) + a / (8 * z * z)
         - (5 / 16 * b * b / z**2 + 13 / 16 * a * b / z**3 + 49 / 64 * a * a / z**4)
         / (2 * math.sqrt(z)))
    v = -(0.5 / math.sqrt(z) - b / (4 * z * z) - a / (4 * z**3) + 25 / 64 * b * b * z**-3.5
          + 91 / 64 * a * b * z**-4.5 + 441 / 256 * a * a * z**-5.5)  # dx/dtau = -x_z

    def f(t, x, v):
        if inertia == 0.0:
            return (-t - x * x) / drag, 0.0
        return v, (-t - x * x - drag * v) / inertia

    h_max = h0 if inertia == 0.0 else min(h0, 0.5 * inertia / max(drag, 1e-300))
    t = tau0
    while x > -escape:
        h = h_max / max(1.0, abs(x) if inertia == 0.0 else math.sqrt(abs(x)))
        a1, b1 = f(t, x, v)
        a2, b2 = f(t + h / 2, x + h / 2 * a1, v + h / 2 * b1)
        a3, b3 = f(t + h / 2, x + h / 2 * a2, v + h / 2 * b2)
        a4, b4 = f(t + h, x + h * a3, v + h * b3)
        x += h / 6 * (a1 + 2 * a2 + 2 * a3 + a4)
        v += h / 6 * (b1 + 2 * b2 + 2 * b3 + b4)
        t += h
    # the tail from x = -X: drag x' = -x^2 -> drag / X; x'' = -x^2 / inertia -> 2 sqrt(3/2
    # inertia / X) (the run-away's own balance; the other terms are O(1/X) smaller there)
    return t + (drag / -x if inertia == 0.0 else 2.0 * math.sqrt(1.5 * inertia / -x))


@dataclasses.dataclass(frozen=True)
class NormalForm:
    """The fold's normal form in time (module docstring): the fold's input ``value`` and
    its key ``vary``, the modal ``mass`` m, ``drive`` A, ``curvature`` B and the drag c."""

    vary: str
    value: float
    mass: float
    drive: float
    curvature: float
    damping: float

    @property
    def _ab(self) -> float:
        return abs(self.drive * self.curvature) / self.mass**2  # |A B| / m^2

    @property
    def damped_prefactor(self) -> float:
        """P_d in lag = P_d eps^(2/3) (the input's units; inf without drag)."""
        if self.damping == 0.0:
            return math.inf
        return escape_time(0.0, 1.0) * (self.damping**2 / self._ab) ** (1.0 / 3.0)

    @property
    def inertial_prefactor(self) -> float:
        """P_i in lag = P_i eps^(4/5)."""
        return escape_time(1.0, 0.0) * (1.0 / self._ab) ** 0.2

    @property
    def crossover_rate(self) -> float:
        """The rate where the two power laws meet (slower: the drag dominates; 0 without
        drag)."""
        if self.damping == 0.0:
            return 0.0
        return (self.damped_prefactor / self.inertial_prefactor) ** (
            1.0 / (INERTIAL_EXPONENT - DAMPED_EXPONENT))

    def lag(self, rate: float) -> float:
        """The switch's lag behind the fold at the rate ``rate`` (the input's units per
        unit time), from the scaled equation with both inertia and drag: > 0, in the
        direction of the sweep."""
        eps = abs(float(rate))
        if not (math.isfinite(eps) and eps > 0):
            raise ParameterError(f"rate must be a finite number other than 0, got {rate!r}")
        T_i = (1.0 / (self._ab * eps)) ** 0.2
        k = self.damping * T_i
        if k <= 1.0:
            return eps * T_i * escape_time(1.0, round(k, 12))
        T_d = (self.damping**2 / (self._ab * eps)) ** (1.0 / 3.0)
        inertia = k ** (-5.0 / 3.0)
        return eps * T_d * escape_time(0.0 if inertia < _EPS_RICCATI else
                                       round(inertia, 12), 1.0)

    def as_dict(self) -> dict:
        return {"vary": self.vary, "value": self.value, "mass": self.mass,
                "drive": self.drive, "curvature": self.curvature, "damping": self.damping,
                "damped": {"exponent": DAMPED_EXPONENT, "prefactor": self.damped_prefactor},
                "inertial": {"exponent": INERTIAL_EXPONENT,
                             "prefactor": self.inertial_prefactor},
                "crossover_rate": self.crossover_rate}


def normal_form(scene: Scene, fold: Fold, damping: float, n: int = DEFAULT_N) -> NormalForm:
    """The normal form in time of ``fold`` (of ``scene``, from ``jr.folds`` at degree
    ``n``) with the linear drag ``damping``."""
    if not fold.converged:
        raise ParameterError("fold: the fold did not converge; refine it first")
    if not (math.isfinite(damping) and damping >= 0):
        raise ParameterError(f"damping must be a finite number >= 0, got {damping!r}")
    disc = discretise(scene, n)
    if np.shape(fold.state) != (disc.size,):
        raise ParameterError(f"fold: its state is not of degree {n}")
    at = scene.replace(fold.vary, fold.value)
    phi = jnp.asarray(fold.null_vector)
    m = float(phi @ mass_matrix(at, jnp.asarray(fold.state), disc) @ phi)
    return NormalForm(vary=fold.vary, value=fold.value, mass=m, drive=fold.dF_dvalue,
                      curvature=0.5 * fold.d2F_dq2, damping=float(damping))
