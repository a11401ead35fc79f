"""A scene file's rod that carries its frame: held at both ends (support =
"clamped-clamped"), or a 3D cantilever whose remanence is programmed at an angle to its
tangent. Its section's ratios, the far end's control (a dead tension or a shortening) and
turns, and the scene's loads, as ``jaxrod.twisted.TwistedRod`` takes them (``FramedSpec``),
and the file keys that are its inputs."""

from __future__ import annotations

import dataclasses

import numpy as np

from jaxrod.scenes.file_entries import fail, number
from jaxrod.scenes.terms import TaperedBending


@dataclasses.dataclass(frozen=True)
class FramedSpec:
    """support ("clamped-clamped" or "clamped"), twist_ratio (C / B, None: the rod's
    default), bending_ratio (B2 / B1), held at both ends exactly one of tension (T L^2 / B)
    and shortening, the far end's turns, and the loads (scene terms by name, the rod's
    uniform bending excluded, a taper among them), and contact_diameter (the rod's
    diameter in L where its strands may not pass through each other:
    ``TwistedRod.contact_diameter``; None: they may)."""

    support: str
    twist_ratio: float | None
    bending_ratio: float
    tension: float | None
    shortening: float | None
    turns: float
    loads: dict
    contact_diameter: float | None = None

    def value(self, key: str) -> float:
        """An input by its key: "turns", a field of this record, or a load's
        "term.field[.i]"."""
        if "." not in key:
            return float(getattr(self, key))
        name, field, *index = key.split(".")
        v = np.asarray(getattr(self.loads[name], field))
        return float(v[int(index[0])] if index else v)


def framed_spec(terms: dict, inputs: dict, tables: dict, per_tension: float,
                support: str, length: float = 1.0) -> FramedSpec:
    """The framed rod of a file's ``[rod]`` and ``[ends]`` tables and its terms; adds its
    keys to ``inputs`` (file key -> (input, factor)). ``per_tension``: T L^2 / B per unit
    of the file's tension (L^2 / (E I) in SI, 1 nondimensional); ``length``: the file's
    unit of length per rod length (L in SI, 1 nondimensional)."""
    rod, ends = tables["rod"], tables["ends"]
    ratios = {}
    for key in ("twist_ratio", "bending_ratio"):
        if key in rod:
            ratios[key] = number(rod, key, "rod.")
            if not ratios[key] > 0:
                fail(f"rod.{key}", f"must be > 0, got {rod[key]!r}")
            inputs[f"rod.{key}"] = (key, 1.0)
    tension = shortening = None
    if support == "clamped":
        pass
    elif ("tension" in ends) == ("shortening" in ends):
        fail("ends", "give tension (a dead load pulling the far end) or shortening (the far "
                     "end held at (1 - shortening) L), one of them")
    elif "tension" in ends:
        tension = per_tension * number(ends, "tension", "ends.")
        inputs["ends.tension"] = ("tension", per_tension)
    else:
        shortening = number(ends, "shortening", "ends.")
        if not 0.0 < shortening < 1.0:
            fail("ends.shortening", f"must be in (0, 1) (a fraction of the length), got "
                                    f"{shortening!r}")
        inputs["ends.shortening"] = ("shortening", 1.0)
    if support != "clamped":
        inputs["ends.rotation_turns"] = ("turns", 1.0)
    # the loads, and a taper (its stiffnesses scaled along the rod)
    loads = {name: t for name, t in terms.items()
             if name != "bending" or isinstance(t, TaperedBending)}
    contact = None
    if "contact_diameter" in rod:
        contact = number(rod, "contact_diameter", "rod.") / length
        if not 0.0 < contact <= 0.1:
            fail("rod.contact_diameter", f"must be in (0, 0.1] rod lengths (a slender rod's "
                                         f"diameter), got {rod['contact_diameter']!r}")
    return FramedSpec(support, ratios.get("twist_ratio"), ratios.get("bending_ratio", 1.0), tension,
                    shortening, number(ends, "rotation_turns", "ends.", required=False,
                                       default=0.0), loads, contact)
