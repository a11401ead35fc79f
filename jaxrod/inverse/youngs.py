"""Young's modulus from measured switching angles (paper, permanent-magnet experiment): the
calibration of ``jaxrod.inverse.fit`` with E (and optionally the offset) free, as one call
with a flat result.

The measured angles, in the order of the experiment's protocol and with the sign of the
magnet angle alpha (positive towards e1):

    0 cw_capture    clockwise sweep (alpha increasing), the rod snaps onto the magnet
    1 cw_release    clockwise sweep, the rod lets go
    2 ccw_capture   counter-clockwise sweep (alpha decreasing), snaps on
    3 ccw_release   counter-clockwise sweep, lets go

are modelled by the folds of the planar branch (``fold_angles``) and an optional constant
offset delta of the angular scale (a misaligned track):

    cw_capture = -alpha_lower + delta,    cw_release = alpha_upper + delta,
    ccw_capture = alpha_lower + delta,    ccw_release = -alpha_upper + delta.

With E the only material unknown, G and M scale as 1/E (``gravity_group``,
``magnet_group``) and D does not depend on E. The fit minimises
0.5 sum_i ((model_i - measured_i) / sigma)^2 over (E, delta) with the generic fit on the
shipped rig (``jaxrod.inverse.scene_fit``: optax's L-BFGS direction, Armijo line search,
Gauss-Newton scaling, the folds tracked by Moore-Spence and differentiated implicitly). A
``FitSetup`` (the groups at a reference modulus) becomes the physical design point with
those groups (``point_of``). The standard deviation of E follows from the
Gauss-Newton covariance at the optimum. ``model_angles`` (a continuation from the straight
rod per call) is the independent reference the tests build synthetic data with.
"""

from __future__ import annotations

import dataclasses
import math

import jax
import jax.numpy as jnp
import numpy as np

from jaxrod.design_point import DesignPoint
from jaxrod.inverse.fit import (
    ANGLE_NAMES,  # noqa: F401  (the angles' order)
    OFFSET,
    calibrate_rows,
    fit,
    parse_angles,
)
from jaxrod.inverse.scene_fit import SceneFit
from jaxrod.magnet.folds import fold_angles
from jaxrod.params import NDFEB_MAGNET, ParameterError, check, check_track_clearance, preset
from jaxrod.programs import jit


@jax.tree_util.register_dataclass
@dataclasses.dataclass(frozen=True)
class FitSetup:
    """The experiment that ``fit_youngs_modulus`` models: G and M at the reference modulus
    E_ref (both scale as 1/E) and the track ratio D (default: the paper's permanent-magnet
    rig, ``setup_from_preset``). Paper: Corollary ``cor:permanent_physical_parameters``."""

    G_ref: float
    M_ref: float
    D: float
    E_ref: float

    def __post_init__(self):
        # concrete values are checked; traced or placeholder leaves (jax rebuilds the
        # dataclass inside programs) are not
        values = (self.G_ref, self.M_ref, self.D, self.E_ref)
        if all(isinstance(v, (int, float, np.integer, np.floating)) for v in values):
            check("G-magnet", self.G_ref)
            check("M", self.M_ref)
            check_track_clearance(self.D)
            check("E", self.E_ref)


def setup_from_preset(name: str = "permanent-magnet") -> FitSetup:
    rod, _ = preset(name)
    return FitSetup(rod.G, rod.M(NDFEB_MAGNET), rod.D(NDFEB_MAGNET),
                    rod.material.youngs_modulus)


def model_angles(params, setup: FitSetup, n: int = 12):
    """The four switching angles (degrees) at p = (log E, delta_deg), and a converged flag."""
    scale = setup.E_ref / jnp.exp(params[0])
    alphas, converged = fold_angles(setup.G_ref * scale, setup.M_ref * scale, setup.D, n=n)
    return angles_from_folds(alphas, params[1]), converged


def angles_from_folds(alphas, offset):
    """The four switching angles (degrees) from the folds (radians, lower first)."""
    return jnp.array([-1.0, 1.0, 1.0, -1.0]) * jnp.degrees(alphas[jnp.array([0, 1, 0, 1])]) \
        + offset


class FitResult(dict):
    """E_Pa, E_std_Pa, offset_deg, offset_std_deg, residuals_deg (None where not measured),
    converged, iterations, reduced_chi2, reason (why not converged), warning (poor fit)."""


def point_of(setup: FitSetup) -> DesignPoint:
    """The physical design point with the setup's groups at E = E_ref: the paper's rig
    (``setup_from_preset``) with the density scaled to give G_ref, the track radius to give
    D, the magnet's diameter reduced where the rod would touch it, and the rod's and the
    magnet's magnetisations scaled alike to give M_ref (G ~ density, M ~ remanence times
    rod-magnetisation, D = track radius / length)."""
    rod, _ = preset("permanent-magnet")
    base = DesignPoint.from_physical(rod, NDFEB_MAGNET).replace("E", setup.E_ref)
    length = base.values[base.index("length")]
    gap = (setup.D - 1.0) * length  # the track radius less the rod's length
    d_magnet = min(base.values[base.index("magnet-diameter")], gap)
    point = (base.replace("track-radius", setup.D * length)
             .replace("magnet-diameter", d_magnet))
    G, M, _ = point.groups()
    root = math.sqrt(setup.M_ref / M)
    value = lambda name: point.values[point.index(name)]
    point = (point.replace("density", value("density") * setup.G_ref / G)
             .replace("remanence", value("remanence") * root)
             .replace("rod-magnetisation", value("rod-magnetisation") * root))
    try:
        point.check()
    except ParameterError as err:
        raise ParameterError(f"setup: no physical point of the paper's rig has G = "
                             f"{setup.G_ref:g}, M = {setup.M_ref:g}, D = {setup.D:g} at E = "
                             f"{setup.E_ref:g} Pa ({err}); use jaxrod.fit with a physical "
                             "DesignPoint") from None
    return point


def fit_result(cal: SceneFit, fit_offset: bool) -> FitResult:
    """A calibration as the flat ``FitResult`` of the E-only fit (E_Pa and E_std_Pa None
    when E was not fitted, or E_std_Pa when the angles do not fix it)."""
    est, std = cal.estimates, cal.std
    used = [r for r in cal.residuals if r is not None]
    dof = max(len(used) - (2 if fit_offset else 1), 1)
    chi2 = float(np.sum(np.square(used))) / cal.sigma**2
    return FitResult(
        E_Pa=est.get("E"), E_std_Pa=std.get("E"), offset_deg=est.get(OFFSET, 0.0),
        offset_std_deg=std.get(OFFSET, 0.0) if fit_offset else 0.0,
        residuals_deg=cal.residuals, converged=cal.converged, iterations=cal.iterations,
        reduced_chi2=chi2 / dof, reason=cal.reason, warning="; ".join(cal.warnings) or None)


def fit_youngs_modulus(measured, sigma_deg: float = 1.0, fit_offset: bool = False,
                       setup: FitSetup | None = None, E0: float = 150e9) -> FitResult:
    """Fit E (and optionally the offset) to measured switching angles in degrees.

    ``measured`` holds the four angles in ``ANGLE_NAMES`` order; nan marks one that was not
    measured. With the offset free, at least two angles are needed. ``E_std_Pa`` is None
    when the angles do not fix E. The calibration ``jaxrod.inverse.fit.fit`` with
    free = ("E",) or ("E", "offset").

    Model: the four angles (capture and release, both directions) from the folds of
    Proposition ``thm:planar_fold`` plus the offset. Paper: Corollary
    ``cor:permanent_physical_parameters``.
    """
    _, mask = parse_angles(measured, sigma_deg)
    if fit_offset and mask.sum() < 2:
        raise ParameterError("angles: fitting the offset needs at least two angles")
    check("E", E0)
    point = point_of(setup or setup_from_preset())
    cal = fit(measured, _free(fit_offset), point, sigma_deg=sigma_deg, start={"E": E0})
    return fit_result(cal, fit_offset)


def _free(fit_offset: bool) -> tuple[str, ...]:
    return ("E", OFFSET) if fit_offset else ("E",)


def fit_batch(measured, sigma_deg: float = 1.0, fit_offset: bool = False,
              setup: FitSetup | None = None, E0: float = 150e9,
              method: str = "auto", progress: bool = False) -> list[FitResult]:
    """Many independent fits, one per row of ``measured``: ``jaxrod.inverse.fit.fit_batch``
    (``method`` "vmap", "loop" or "auto"; ``progress``; Ctrl-C keeps the fits done) with E
    (and the offset) free, each as a ``FitResult``.

    Paper: Corollary ``cor:permanent_physical_parameters`` (one fit per row).
    """
    check("E", E0)
    point = point_of(setup or setup_from_preset())
    cals = calibrate_rows(measured, _free(fit_offset), point, sigma_deg=sigma_deg,
                          start={"E": E0}, method=method, progress=progress)
    return [fit_result(c, fit_offset) for c in cals]


def loss_profile(measured, E_values, sigma_deg: float = 1.0, fit_offset: bool = False,
                 setup: FitSetup | None = None):
    """0.5 chi^2 over a grid of E (offset at its best value for each E when fitted)."""
    measured, mask = parse_angles(measured, sigma_deg)
    setup = setup or setup_from_preset()
    return np.asarray(_loss_profile_program(
        np.log(np.asarray(E_values, np.float64)), np.nan_to_num(measured), mask,
        float(sigma_deg), bool(fit_offset), setup))


@jit
def _loss_profile_program(log_e, measured, mask, sigma_deg, fit_offset, setup):
    """``loss_profile`` at each log E (one program for every grid of the same length)."""

    def at(log_e):
        model, ok = model_angles(jnp.array([log_e, 0.0]), setup)
        d = jnp.where(mask, measured - model, 0.0)
        delta = jnp.where(fit_offset, jnp.sum(d) / jnp.sum(mask), 0.0)
        r = jnp.where(mask, (d - delta) / sigma_deg, 0.0)
        return jnp.where(ok, 0.5 * jnp.sum(r**2), jnp.nan)

    return jax.vmap(at)(log_e)
