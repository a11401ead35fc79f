"""Physical inputs -> the paper's nondimensional groups G, A, M, C, D.

A circular wire of radius b = d/2 and length L has (paper, section "Variational model")

    area = pi b^2,   I = pi b^4 / 4,   J = 2 I,   B = E I,   C_t = G_s J,

and the energy scaled by B / L has the groups

    G = rho area g L^3 / B   = 4 rho g L^3 / (E b^2)                 (gravity)
    A = K_d area L^2 / B     = 4 K_d L^2 / (E b^2)                   (shape anisotropy)
    M = mu0 area M_r M_s a^3 / (3 B L) = 4 mu0 M_r M_s a^3 / (3 E b^2 L)   (dipole magnet)
    C = C_t / B              = 2 G_s / E = 1 / (1 + nu)              (twist; decouples)
    D = R_track / L                                                  (magnet track radius)

with a the magnet radius. ``L_stab = K_d / (rho g)`` (Corollary "Magnetic Stabilization")
is the length below which A > G, a sufficient condition for a stable upright rod.

Every function validates its inputs and raises ``ParameterError`` naming the parameter
and its valid range.
"""

from __future__ import annotations

import dataclasses
import math

MU0 = 4e-7 * math.pi  # vacuum permeability, T m / A (the SI value before 2019; 1e-10 relative)
STANDARD_GRAVITY = 9.81  # m / s^2, the value the paper's tables use


def gravity_group(youngs_modulus, density, gravity, diameter, length):
    """G = 4 rho g L^3 / (E b^2), b = diameter / 2 (pure arithmetic: works on JAX arrays)."""
    return 16.0 * density * gravity * length**3 / (youngs_modulus * diameter**2)


def anisotropy_group(youngs_modulus, anisotropy_constant, diameter, length):
    """A = 4 K_d L^2 / (E b^2)."""
    return 16.0 * anisotropy_constant * length**2 / (youngs_modulus * diameter**2)


def magnet_group(youngs_modulus, remanent_magnetisation, saturation_magnetisation, diameter,
                 length, magnet_diameter):
    """M = 4 mu0 M_r M_s a^3 / (3 E b^2 L), a = magnet_diameter / 2."""
    return (2.0 * MU0 * remanent_magnetisation * saturation_magnetisation * magnet_diameter**3
            / (3.0 * youngs_modulus * diameter**2 * length))


class ParameterError(ValueError):
    """An input outside its valid range; the message names the parameter and the range."""


def check_value(name: str, value, ok, requirement: str) -> float:
    """Return ``value`` as a float if it is finite and ``ok(value)``, else raise
    ``ParameterError`` naming the parameter and the ``requirement`` ("in (0, 90) degrees")."""
    try:
        x = float(value)
    except (TypeError, ValueError):
        x = math.nan
    if not (math.isfinite(x) and ok(x)):
        raise ParameterError(f"{name} must be {requirement}, got {value!r}")
    return x


def check_positive(name: str, value, unit: str = "") -> float:
    """Return ``value`` as a float if it is a finite number > 0, else raise."""
    return check_value(name, value, lambda x: x > 0.0,
                  f"a finite number > 0{' ' + unit if unit else ''}")


def check_nonnegative(name: str, value, unit: str = "") -> float:
    """Return ``value`` as a float if it is a finite number >= 0, else raise."""
    return check_value(name, value, lambda x: x >= 0.0,
                  f"a finite number >= 0{' ' + unit if unit else ''}")


def check_finite(name: str, value) -> float:
    """Return ``value`` as a float if it is finite, else raise."""
    return check_value(name, value, lambda x: True, "a finite number")


@dataclasses.dataclass(frozen=True)
class Material:
    """Bulk material data in SI units.

    ``poisson_ratio`` (or an explicit ``shear_modulus``) only sets the twist ratio C, which
    does not enter any equilibrium or stability result (twist decouples, tau = 0).
    """

    name: str
    youngs_modulus: float  # E, Pa
    density: float  # rho, kg / m^3
    anisotropy_constant: float  # K_d, J / m^3
    remanent_magnetisation: float  # M_r, A / m
    poisson_ratio: float = 0.31
    shear_modulus: float | None = None  # G_s, Pa; default E / (2 (1 + nu))

    def __post_init__(self):
        check_positive("E (Young's modulus)", self.youngs_modulus, "Pa")
        check_positive("rho (density)", self.density, "kg/m^3")
        check_nonnegative("K_d (demagnetising energy density)", self.anisotropy_constant, "J/m^3")
        check_nonnegative("M_r (magnetisation of the rod)", self.remanent_magnetisation, "A/m")
        nu = check_finite("nu (Poisson ratio)", self.poisson_ratio)
        if not -1.0 < nu < 0.5:
            raise ParameterError(f"nu (Poisson ratio) must lie in (-1, 0.5), got {nu!r}")
        if self.shear_modulus is not None:
            check_positive("shear modulus", self.shear_modulus, "Pa")

    def with_youngs_modulus(self, youngs_modulus: float) -> Material:
        return dataclasses.replace(self, youngs_modulus=youngs_modulus)


@dataclasses.dataclass(frozen=True)
class Magnet:
    """A uniformly magnetised sphere moved on a circle of radius ``track_radius``."""

    diameter: float  # m
    saturation_magnetisation: float  # M_s, A / m
    track_radius: float  # m, distance from the clamp to the magnet centre

    def __post_init__(self):
        check_positive("magnet diameter", self.diameter, "m")
        check_nonnegative("M_s (saturation magnetisation of the magnet)",
                          self.saturation_magnetisation, "A/m")
        check_positive("track radius", self.track_radius, "m")


@dataclasses.dataclass(frozen=True)
class Rod:
    """A circular wire of ``diameter`` and ``length`` (m) made of ``material``."""

    material: Material
    diameter: float
    length: float
    gravity: float = STANDARD_GRAVITY

    def __post_init__(self):
        check_positive("wire diameter", self.diameter, "m")
        check_positive("L (rod length)", self.length, "m")
        check_positive("g (gravitational acceleration)", self.gravity, "m/s^2")

    @property
    def radius(self) -> float:
        return 0.5 * self.diameter

    @property
    def bending_stiffness(self) -> float:
        """B = E I = E pi b^4 / 4, N m^2."""
        return self.material.youngs_modulus * math.pi * self.radius**4 / 4.0

    @property
    def G(self) -> float:
        """Gravity group 4 rho g L^3 / (E b^2)."""
        m = self.material
        return gravity_group(m.youngs_modulus, m.density, self.gravity, self.diameter,
                             self.length)

    def A(self, field_on: bool = True) -> float:
        """Anisotropy group 4 K_d L^2 / (E b^2); zero with the field off.

        The uniform-field scene assumes the field saturates the magnetisation along e3
        (m = e3). With no applied field the magnetisation follows the tangent, the
        demagnetising term vanishes and the rod is a plain Greenhill column (A = 0).
        """
        if not field_on:
            return 0.0
        m = self.material
        return anisotropy_group(m.youngs_modulus, m.anisotropy_constant, self.diameter,
                                self.length)

    @property
    def C(self) -> float:
        """Twist ratio C_t / B = 2 G_s / E."""
        m = self.material
        shear = m.shear_modulus
        if shear is None:
            shear = m.youngs_modulus / (2.0 * (1.0 + m.poisson_ratio))
        return 2.0 * shear / m.youngs_modulus

    def M(self, magnet: Magnet) -> float:
        """Dipole group 4 mu0 M_r M_s a^3 / (3 E b^2 L), a = magnet radius."""
        m = self.material
        return magnet_group(m.youngs_modulus, m.remanent_magnetisation,
                            magnet.saturation_magnetisation, self.diameter, self.length,
                            magnet.diameter)

    def D(self, magnet: Magnet) -> float:
        """Track radius over rod length; must exceed 1 + a / L so the magnet clears the rod."""
        d = magnet.track_radius / self.length
        check_track_clearance(d, 0.5 * magnet.diameter / self.length)
        return d

    @property
    def stabilisation_length(self) -> float:
        """L_stab = K_d / (rho g), m: A > G (stable upright, either support) iff L < L_stab."""
        m = self.material
        return m.anisotropy_constant / (m.density * self.gravity)

    def with_length(self, length: float) -> Rod:
        return dataclasses.replace(self, length=length)

    def with_youngs_modulus(self, youngs_modulus: float) -> Rod:
        return dataclasses.replace(self, material=self.material.with_youngs_modulus(youngs_modulus))


def check_track_clearance(D: float, magnet_radius: float = 0.0) -> float:
    """Validate D (track radius / L) against the magnet radius a / L (both in rod lengths).

    Every point of the rod lies within distance 1 of the clamp, so the rod can never reach
    the magnet iff D - 1 > a / L; with no radius given, D > 1 is required.
    """
    D = check_positive("D (track radius / rod length)", D)
    a = check_nonnegative("magnet radius / rod length", magnet_radius)
    if D <= 1.0 + a:
        if a > 0.0:
            raise ParameterError(
                f"D (track radius / rod length) must exceed 1 + a/L = {1.0 + a:.6g} so the rod "
                f"tip cannot touch the magnet (magnet radius a/L = {a:.6g}), got {D!r}")
        raise ParameterError(f"D (track radius / rod length) must be > 1, got {D!r}")
    return D


def check_groups(G=None, A=None, M=None, D=None) -> None:
    """Validate nondimensional groups that are given (None = not used by the scene)."""
    if G is not None:
        check_positive("G (gravity group)", G)
    if A is not None:
        check_finite("A (anisotropy group)", A)
    if M is not None:
        check_nonnegative("M (magnet group)", M)
    if D is not None:
        check_track_clearance(D)


#: The permanent-magnet scene's inputs: its groups, and the physical inputs in the order of
#: ``jaxrod.analysis.fold_curves.DesignPoint.values``, with their units.
GROUP_NAMES = ("G", "M", "D")
PHYSICAL_NAMES = ("E", "density", "gravity", "diameter", "length", "rod-magnetisation",
                  "remanence", "magnet-diameter", "track-radius")
UNITS = {"G": "", "M": "", "D": "", "E": "Pa", "density": "kg/m^3", "gravity": "m/s^2",
         "diameter": "m", "length": "m", "rod-magnetisation": "A/m", "remanence": "A/m",
         "magnet-diameter": "m", "track-radius": "m"}


# --- the paper's data (Table tab:material_para and the experiments' geometry) -------------

#: Young's moduli bracketing the literature range the paper uses for nickel, Pa.
NICKEL_E_RANGE = (100e9, 200e9)

NICKEL = Material(
    name="nickel",
    youngs_modulus=200e9,
    density=9e3,
    anisotropy_constant=1.5e5,
    remanent_magnetisation=4.8e5,
)

NDFEB_MAGNET = Magnet(diameter=15e-3, saturation_magnetisation=8e5, track_radius=11.25e-2)

#: The paper's experiments: name -> (wire diameter m, length m, support).
EXPERIMENTS = {
    "clamped-8cm": (50e-6, 0.08, "clamped"),
    "clamped-10cm": (50e-6, 0.10, "clamped"),
    "clamped-12cm": (50e-6, 0.12, "clamped"),
    "pinned-0.3mm": (0.3e-3, 0.11, "pinned"),
    "pinned-0.7mm": (0.7e-3, 0.11, "pinned"),
    "permanent-magnet": (50e-6, 0.092, "clamped"),
}


def preset(name: str, youngs_modulus: float = NICKEL.youngs_modulus) -> tuple[Rod, str]:
    """The nickel rod of one of the paper's experiments, and its support.

    ``youngs_modulus`` picks a value in the paper's literature range (100-200 GPa).
    The permanent-magnet experiment's magnet is ``NDFEB_MAGNET``.
    """
    if name not in EXPERIMENTS:
        raise ParameterError(f"preset must be one of {sorted(EXPERIMENTS)}, got {name!r}")
    diameter, length, support = EXPERIMENTS[name]
    return Rod(NICKEL.with_youngs_modulus(youngs_modulus), diameter, length), support
