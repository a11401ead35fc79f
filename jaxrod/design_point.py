"""A design point of the paper's permanent-magnet rig: the groups (G, M, D) or the nine
physical inputs, validated once, and the valid range of each input (the clearance of the
magnet included). Fold curves, maps, fits and designs start from one."""

from __future__ import annotations

import dataclasses
import math

from jaxrod.params import (
    GROUP_NAMES,
    PHYSICAL_NAMES,
    RANGES,
    Magnet,
    ParameterError,
    Rod,
    check_track_clearance,
    gravity_group,
    magnet_group,
)


def groups_of(kind: str, values):
    """(G, M, D) of a design point's values (traced arithmetic)."""
    if kind == "groups":
        return values[0], values[1], values[2]
    E, rho, g, d, L, m_rod, m_magnet, d_magnet, R = (values[i] for i in range(9))
    return (gravity_group(E, rho, g, d, L), magnet_group(E, m_rod, m_magnet, d, L, d_magnet),
            R / L)


@dataclasses.dataclass(frozen=True)
class DesignPoint:
    """Where a fold curve starts: the groups (G, M, D) or the nine physical inputs.

    ``magnet_radius`` (a / L, groups only) makes the clearance check refuse magnets the rod
    could touch; physical points take it from the magnet diameter.

    Paper: the inputs of eq. ``permanent_magnet_energy`` (groups) or of Table
    ``tab:parameters_radial`` (physical).
    """

    kind: str  # "groups" or "physical"
    values: tuple[float, ...]
    magnet_radius: float = 0.0

    @classmethod
    def from_groups(cls, G, M, D, magnet_radius: float | None = None) -> DesignPoint:
        point = cls("groups", (float(G), float(M), float(D)), float(magnet_radius or 0.0))
        point.check()
        return point

    @classmethod
    def from_physical(cls, rod: Rod, magnet: Magnet) -> DesignPoint:
        m = rod.material
        point = cls("physical", (m.youngs_modulus, m.density, rod.gravity, rod.diameter,
                                 rod.length, m.saturation_magnetisation,
                                 magnet.remanence, magnet.diameter,
                                 magnet.track_radius))
        point.check()
        return point

    @property
    def names(self) -> tuple[str, ...]:
        return GROUP_NAMES if self.kind == "groups" else PHYSICAL_NAMES

    def index(self, name: str) -> int:
        if name not in self.names:
            other = PHYSICAL_NAMES if self.kind == "groups" else GROUP_NAMES
            hint = (" (that is a physical input: give the point by physical inputs, e.g. a "
                    "preset)" if name in other and self.kind == "groups" else
                    " (that is a group: give the point by --G --M --D)" if name in other
                    else "")
            raise ParameterError(f"vary must be one of {', '.join(self.names)}, got "
                                 f"{name!r}{hint}")
        return self.names.index(name)

    def groups(self) -> tuple[float, float, float]:
        return tuple(float(v) for v in groups_of(self.kind, self.values))

    def radius(self) -> float:
        """Magnet radius over rod length, a / L."""
        if self.kind == "groups":
            return self.magnet_radius
        return 0.5 * self.values[7] / self.values[4]

    def replace(self, name: str, value: float) -> DesignPoint:
        values = list(self.values)
        values[self.index(name)] = float(value)
        return dataclasses.replace(self, values=tuple(values))

    def check(self) -> None:
        """Validate the point against ``jaxrod.params.RANGES``, its inputs and the groups
        they make (ParameterError naming the offending input)."""
        for name, v in zip(self.names, self.values, strict=True):
            range_of(name).check(v)
        G, M, D = self.groups()
        if self.kind == "physical":
            for name, v in (("G", G), ("M", M)):
                if not range_of(name).contains(v):
                    r = range_of(name)
                    raise ParameterError(f"{r.label} = {v:.4g} from the physical inputs is "
                                         f"outside {r.interval()} ({r.why})")
        check_track_clearance(D, self.radius())

    def as_dict(self) -> dict:
        G, M, D = self.groups()
        out = {name: v for name, v in zip(self.names, self.values, strict=True)}
        return out | {"G": G, "M": M, "D": D, "magnet_radius_over_L": self.radius()}


def range_of(name: str):
    """The ``jaxrod.params.RANGES`` entry of a design input (a group or a physical input)."""
    return RANGES["G-magnet" if name == "G" else name]


def valid_range(point: DesignPoint, name: str) -> tuple[float, float]:
    """The open interval of the input ``name`` (others fixed) where the point is valid:
    positive inputs, and a magnet that clears the rod (D > 1 + a / L)."""
    lo, hi = _clearance_range(point, name)
    r = range_of(name)
    return max(lo, r.low), min(hi, r.high)


def _clearance_range(point: DesignPoint, name: str) -> tuple[float, float]:
    point.index(name)  # validates the name
    v = point.values
    if point.kind == "groups":
        if name == "D":
            return 1.0 + point.magnet_radius, math.inf
        return (0.0, math.inf)
    L, d_magnet, R = v[4], v[7], v[8]
    if name == "track-radius":
        return L + 0.5 * d_magnet, math.inf
    if name == "length":
        return 0.0, R - 0.5 * d_magnet
    if name == "magnet-diameter":
        return 0.0, 2.0 * (R - L)
    return 0.0, math.inf


def check_target(point: DesignPoint, name: str, to: float) -> float:
    """Validate the end value of a fold curve against ``valid_range``."""
    lo, hi = valid_range(point, name)
    v0 = point.values[point.index(name)]
    if not math.isfinite(to) or not lo < to < hi:
        raise ParameterError(f"to: {name} must stay in ({lo:.6g}, {hi:.6g}) (positive inputs, "
                             f"a magnet that clears the rod), got {to!r}")
    if to == v0:
        raise ParameterError(f"to: must differ from the starting {name} = {v0!r}")
    return float(to)
