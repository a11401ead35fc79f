"""Physical inputs -> the paper's nondimensional groups G, A, M, C, D.

A circular wire of radius b = d/2 and length L has (paper, section "Variational model")

    area = pi b^2,   I = pi b^4 / 4,   J = 2 I,   B = E I,   C_t = G_s J,

and the energy scaled by B / L has the groups

    G = rho area g L^3 / B   = 4 rho g L^3 / (E b^2)                 (gravity)
    A = K_d area L^2 / B     = 4 K_d L^2 / (E b^2)                   (shape anisotropy)
    M = mu0 area M_r M_s a^3 / (3 B L) = 4 mu0 M_r M_s a^3 / (3 E b^2 L)   (dipole magnet)
    C = C_t / B              = 2 G_s / E = 1 / (1 + nu)              (twist; decouples)
    D = R_track / L                                                  (magnet track radius)

with a the magnet radius, M_r the rod's saturation magnetisation (``Material.
saturation_magnetisation``) and M_s the magnet's remanent magnetisation (``Magnet.remanence``),
in the paper's symbols. ``L_stab = K_d / (rho g)`` (Corollary "Magnetic Stabilization")
is the length below which A > G, a sufficient condition for a stable upright rod.

Every function validates its inputs and raises ``ParameterError`` naming the parameter
and its valid range.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

MU0 = 4e-7 * math.pi  # vacuum permeability, T m / A (the SI value before 2019; 1e-10 relative)
STANDARD_GRAVITY = 9.81  # m / s^2, the value the paper's tables use


def gravity_group(youngs_modulus, density, gravity, diameter, length):
    """G = 4 rho g L^3 / (E b^2), b = diameter / 2 (pure arithmetic: works on JAX arrays).

    Paper: the gravity group of eq. ``nondimensional_master_energy`` (section
    ``sec:model``).
    """
    return 16.0 * density * gravity * length**3 / (youngs_modulus * diameter**2)


def anisotropy_group(youngs_modulus, anisotropy_constant, diameter, length):
    """A = 4 K_d L^2 / (E b^2).

    K_d = mu0 M_s^2 / 4 is the shape-anisotropy constant of a thin wire. Paper: the
    stray-field group of eq. ``nondimensional_master_energy`` (section ``sec:model``).
    """
    return 16.0 * anisotropy_constant * length**2 / (youngs_modulus * diameter**2)


def magnet_group(youngs_modulus, saturation_magnetisation, remanence, diameter,
                 length, magnet_diameter):
    """M = 4 mu0 M_r M_s a^3 / (3 E b^2 L), a = magnet_diameter / 2.

    Paper: the Zeeman group of eq. ``permanent_magnet_energy`` (section
    ``sec:magnetic_regimes``).
    """
    return (2.0 * MU0 * saturation_magnetisation * remanence * magnet_diameter**3
            / (3.0 * youngs_modulus * diameter**2 * length))


class ParameterError(ValueError):
    """An input outside its valid range; the message names the parameter and the range."""


def check_value(name: str, value, ok, requirement: str) -> float:
    """Return ``value`` as a float if it is finite and ``ok(value)``, else raise
    ``ParameterError`` naming the parameter and the ``requirement`` ("in (0, 90) degrees")."""
    if isinstance(value, (str, bytes, bool)):
        x = math.nan
    else:
        try:
            x = float(value)
        except (TypeError, ValueError):
            x = math.nan
    if not (math.isfinite(x) and ok(x)):
        raise ParameterError(f"{name} must be {requirement}, got {value!r}")
    return x


@dataclasses.dataclass(frozen=True)
class ValidRange:
    """The values one input may take: an interval, with the reason for its bounds.

    Upper bounds mark where a larger value cannot be computed in reasonable time or memory
    (or is no longer physical); ``why`` says which, and goes into the error message.

    Paper: the bounds follow its hypotheses where it has them (D > 1: the magnet outside the
    rod's reach, eq. ``permanent_magnet_energy``).
    """

    label: str  # how messages name the input: "G (gravity group)"
    low: float
    high: float
    low_open: bool = True
    high_open: bool = False
    unit: str = ""
    why: str = ""

    def interval(self) -> str:
        unit = f" {self.unit}" if self.unit else ""
        return (f"{'(' if self.low_open else '['}{_short(self.low)}, {_short(self.high)}"
                f"{')' if self.high_open else ']'}{unit}")

    def contains(self, x):
        """Elementwise test (numpy arrays or floats); NaN is never contained."""
        above = (x > self.low) if self.low_open else (x >= self.low)
        below = (x < self.high) if self.high_open else (x <= self.high)
        return above & below

    def check(self, value) -> float:
        """``value`` as a float, or ParameterError naming the input, the range and why."""
        why = f" ({self.why})" if self.why else ""
        return check_value(self.label, value, self.contains,
                           f"a finite number in {self.interval()}{why}")

    def check_rows(self, values):
        """A batch as a float64 array; ParameterError naming the offending rows."""
        try:
            x = np.asarray(values, dtype=np.float64)
        except (TypeError, ValueError):
            raise ParameterError(f"{self.label} must be an array of numbers, got "
                                 f"{values!r:.60}") from None
        bad = np.flatnonzero(~(np.isfinite(x) & self.contains(x)))
        if bad.size:
            why = f" ({self.why})" if self.why else ""
            rows = ", ".join(str(int(i)) for i in bad[:8]) + (", ..." if bad.size > 8 else "")
            raise ParameterError(f"{self.label} must be finite and in {self.interval()}{why}; "
                                 f"{bad.size} row(s) are not: row {rows} (first value "
                                 f"{x.ravel()[bad[0]]!r})")
        return x


def _short(x: float) -> str:
    """A bound as people write it: 1e7, 1e3, 2.5e4, 0.5, 180."""
    if x == 0 or 1e-3 <= abs(x) < 1e3:
        return f"{x:g}"
    mantissa, exponent = f"{x:.6e}".split("e")
    mantissa = mantissa.rstrip("0").rstrip(".")
    return f"{mantissa}e{int(exponent)}"


_G_WHY = "beyond 1e7 the Airy layer of width G^(-1/3) at the support needs N > 256 modes"
#: Every input's valid range, in one place: the CLI and the Python API check against these.
RANGES = {
    # nondimensional groups
    "G": ValidRange("G (gravity group)", 0.0, 1e7, why=_G_WHY),
    "A": ValidRange("A (anisotropy group)", -1e9, 1e9, low_open=False,
                    why="A is compared with A_crit ~ G, and G <= 1e7"),
    "G-magnet": ValidRange("G (gravity group)", 0.0, 1e3,
                           why="the magnet scene's programs (N <= 64) resolve G <= 1e3"),
    "M": ValidRange("M (magnet group)", 0.0, 1e3, low_open=False,
                    why="beyond 1e3 the magnet's field dwarfs gravity and elasticity by more "
                        "than the programs resolve"),
    "D": ValidRange("D (track radius / rod length)", 1.0, 1e3,
                    why="D > 1 keeps the magnet off the rod; beyond 1e3 the field at the rod is "
                        "below round-off"),
    # discretisation
    "N": ValidRange("N (Chebyshev degree)", 4, 256, low_open=False,
                    why="beyond 256 the spectral matrices lose digits to round-off"),
    "N-magnet": ValidRange("N (Chebyshev degree)", 4, 64, low_open=False,
                           why="beyond 64 compiling the fold programs takes minutes; the fold "
                               "angles reach round-off by N = 16"),
    # physical inputs (SI)
    "E": ValidRange("E (Young's modulus)", 1e3, 1e13, low_open=False, unit="Pa",
                    why="from the softest gels to beyond diamond"),
    "density": ValidRange("density", 0.0, 1e5, unit="kg/m^3",
                          why="the densest element, osmium, is 2.3e4"),
    "gravity": ValidRange("gravity (acceleration)", 0.0, 1e4, unit="m/s^2"),
    "diameter": ValidRange("diameter (wire diameter)", 0.0, 1.0, unit="m",
                           why="a slender rod"),
    "length": ValidRange("length (rod length)", 0.0, 1e3, unit="m"),
    "rod-magnetisation": ValidRange("rod-magnetisation (saturation magnetisation of the "
                                    "rod)", 0.0, 1e7, low_open=False, unit="A/m",
                                    why="the strongest ferromagnets saturate near 2e6"),
    "remanence": ValidRange("remanence (magnetisation of the magnet)", 0.0, 1e7,
                            low_open=False, unit="A/m",
                            why="the strongest permanent magnets reach 1.2e6"),
    "anisotropy": ValidRange("K_d (demagnetising energy density)", 0.0, 1e8, low_open=False,
                             unit="J/m^3"),
    "magnet-diameter": ValidRange("magnet-diameter", 0.0, 10.0, unit="m"),
    "track-radius": ValidRange("track-radius", 0.0, 1e3, unit="m"),
    # angles (degrees)
    "alpha": ValidRange("alpha (magnet angle)", -90.0, 90.0, low_open=False, unit="deg"),
    "alpha-max": ValidRange("alpha-max (sweep amplitude)", 0.0, 90.0, unit="deg",
                            why="the magnet's track is the upper half circle"),
    "step": ValidRange("step (magnet step)", 0.0, 5.0, unit="deg",
                       why="a larger step skips the folds' neighbourhoods"),
    "alpha0": ValidRange("alpha0 (start of the track)", 0.0, 90.0, high_open=True, unit="deg"),
    "tilt": ValidRange("tilt (angle of the track to the meridian)", 0.0, 180.0,
                       low_open=False, unit="deg"),
    "t-max": ValidRange("t-max (length of the track)", 0.0, 180.0, unit="deg"),
    "angle": ValidRange("angles (switching angle)", -90.0, 90.0, high_open=True, unit="deg"),
    "sigma-deg": ValidRange("sigma-deg (measurement error per angle)", 0.0, 90.0,
                            high_open=True, unit="deg"),
}


def check(name: str, value) -> float:
    """Validate one input against ``RANGES[name]``; returns it as a float."""
    return RANGES[name].check(value)


def check_degree(n, name: str = "N") -> int:
    """An integer Chebyshev degree within ``RANGES[name]`` ("N" or "N-magnet")."""
    r = RANGES[name]
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or not r.contains(n):
        raise ParameterError(f"{r.label} must be an integer in {r.interval()} ({r.why}), "
                             f"got {n!r}")
    return int(n)


def _store(obj, field: str, value: float) -> None:
    """Store the validated float (a frozen dataclass keeps what it was given otherwise)."""
    object.__setattr__(obj, field, value)


@dataclasses.dataclass(frozen=True)
class Material:
    """Bulk material data in SI units.

    ``poisson_ratio`` (or an explicit ``shear_modulus``) only sets the twist ratio C, which
    does not enter any equilibrium or stability result (twist decouples, tau = 0).

    Paper: the material data of Table ``tab:material_para``; they enter the energy (eq.
    ``dimensional_master_energy``) only through the groups G, A, M.
    """

    name: str
    youngs_modulus: float  # E, Pa
    density: float  # rho, kg / m^3
    anisotropy_constant: float  # K_d, J / m^3
    saturation_magnetisation: float  # the rod's magnetisation when saturated (paper: M_r), A/m
    poisson_ratio: float = 0.31
    shear_modulus: float | None = None  # G_s, Pa; default E / (2 (1 + nu))

    def __post_init__(self):
        _store(self, "youngs_modulus", check("E", self.youngs_modulus))
        _store(self, "density", check("density", self.density))
        _store(self, "anisotropy_constant", check("anisotropy", self.anisotropy_constant))
        _store(self, "saturation_magnetisation",
               check("rod-magnetisation", self.saturation_magnetisation))
        nu = check_value("nu (Poisson ratio)", self.poisson_ratio, lambda x: -1.0 < x < 0.5,
                         "a finite number in (-1, 0.5)")
        _store(self, "poisson_ratio", nu)
        if self.shear_modulus is not None:
            _store(self, "shear_modulus", check("E", self.shear_modulus))

    def with_youngs_modulus(self, youngs_modulus: float) -> Material:
        return dataclasses.replace(self, youngs_modulus=youngs_modulus)


@dataclasses.dataclass(frozen=True)
class Magnet:
    """A uniformly magnetised sphere moved on a circle of radius ``track_radius``.

    Paper: the NdFeB sphere of Table ``tab:parameters_radial``; outside itself a point
    dipole, so its field enters eq. ``permanent_magnet_energy`` as M Phi(X).
    """

    diameter: float  # m
    remanence: float  # the magnet's remanent magnetisation (paper: M_s), A/m
    track_radius: float  # m, distance from the clamp to the magnet centre

    def __post_init__(self):
        _store(self, "diameter", check("magnet-diameter", self.diameter))
        _store(self, "remanence", check("remanence", self.remanence))
        _store(self, "track_radius", check("track-radius", self.track_radius))


@dataclasses.dataclass(frozen=True)
class Rod:
    """A circular wire of ``diameter`` and ``length`` (m) made of ``material``.

    Paper: the wires of Tables ``tab:clamped``, ``tab:pinned`` and
    ``tab:parameters_radial``; b = diameter / 2 and L = length in eq.
    ``nondimensional_master_energy``.
    """

    material: Material
    diameter: float
    length: float
    gravity: float = STANDARD_GRAVITY

    def __post_init__(self):
        if not isinstance(self.material, Material):
            raise ParameterError(f"material must be a Material, got {self.material!r:.60}")
        _store(self, "diameter", check("diameter", self.diameter))
        _store(self, "length", check("length", self.length))
        _store(self, "gravity", check("gravity", self.gravity))

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
        return magnet_group(m.youngs_modulus, m.saturation_magnetisation,
                            magnet.remanence, self.diameter, self.length,
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
    D = check("D", D)
    a = check_value("magnet radius / rod length", magnet_radius, lambda x: 0.0 <= x < 1e3,
                    "a finite number in [0, 1e3)")
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
        check("G", G)
    if A is not None:
        check("A", A)
    if M is not None:
        check("M", M)
    if D is not None:
        check_track_clearance(D)


#: The permanent-magnet scene's inputs: its groups, and the physical inputs in the order of
#: ``jaxrod.design_point.DesignPoint.values``, with their units.
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
    saturation_magnetisation=4.8e5,
)

NDFEB_MAGNET = Magnet(diameter=15e-3, remanence=8e5, track_radius=11.25e-2)

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
