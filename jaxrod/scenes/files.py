"""Scene files: a rig described in TOML (or JSON), read into a ``Scene`` and the map from the
file's keys to the scene's inputs.

A file in SI units (the default) or, with ``units = "nondimensional"``, in the groups:

    [rod]            length (m), radius (m), youngs_modulus (Pa), support ("clamped" at the
                     origin pointing along +z, or "pinned"), density (kg/m^3, with gravity),
                     stiffness_profile = [b0, b1, ...] (a taper: E I(s) / E I, Chebyshev
                     coefficients in 2 s - 1; the radius and E give E I)
    [magnetisation]  kind = "hard" (remanent, fixed in the material; remanence in A/m along
                     the tangent, or at angle_deg to it, or at a profile along s,
                     profile_deg = [c0, c1, ...] degrees, c0 + c1 s + ...; uniform fields
                     and magnets at a position; planar rods; its strength along s relative
                     to the load, strength_profile = [d0, d1, ...], Chebyshev coefficients in
                     2 s - 1, [1.0] uniform: uniform fields, planar rods) or "soft" (the
                     paper's wire, saturated along the tangent with polarity +d3; saturation
                     in A/m)
    [[field]]        kind = "uniform": B (T) or load (A_c M_r B L^2 / (E I)), angle_deg
                     (from +z toward +x); a soft wire in a uniform field: A (the paper's
                     anisotropy group), angle_deg;
                     kind = "dipole": a point magnet, by moment (A m^2) or remanence (A/m) and
                     diameter (m) of a sphere, or M (the paper's dipole group), at
                     position = [x, z] with moment_direction = [ux, uz] (on a straight rail
                     from there: rail = [ux, uz], along = t), or on the paper's circle:
                     path = "circle", radius (the paper's D), angle_deg (alpha; the moment
                     radially outward), or on any curve: path = "curve", coefficients =
                     [[x0, z0], [x1, z1], ...] (c(t) = a0 + a1 t + ...), t,
                     moment_along_path = true or moment_direction
    [gravity]        g (m/s^2, along -z: the rod standing up) or G (rho g A_c L^3 / (E I));
                     hanging = true: gravity along +z, the rod hanging from its clamp (the
                     same as a negative g or G)

and top-level ``geometry = "planar"`` (default) or ``"3d"``. The terms of the scene are
``bending``, ``gravity`` and ``field0``, ``field1``, ...; a file key names an input by its
dotted path (``field.0.angle_deg``, ``field.0.position.0``, ``gravity.g``), which maps to a
scene input by a constant factor (``FileScene.input_of``). Lengths of the scene are in rod
lengths; ``FileScene.length`` converts them back to the file's unit.
"""

from __future__ import annotations

import dataclasses
import difflib
import json
import math
from pathlib import Path

import numpy as np

from jaxrod.params import MU0, ParameterError
from jaxrod.scenes.file_entries import (
    angle_profile,
    chebyshev_form,
    check_plausible,
    coefficients,
    direction,
    fail,
    number,
    strength_profile,
    unknown_key,
    vector,
)
from jaxrod.scenes.framed import FramedSpec, framed_spec
from jaxrod.scenes.scene import Scene
from jaxrod.scenes.terms import (
    Anisotropy,
    Bending,
    Dipole,
    Gravity,
    PathDipole,
    PointDipole,
    ProgrammedDipole,
    ProgrammedMagnetisation,
    TaperedBending,
    Zeeman,
)

#: Allowed keys of each table, SI and nondimensional.
TABLES = {
    "rod": {"si": ("length", "radius", "youngs_modulus", "support", "density",
                   "stiffness_profile", "twist_ratio", "bending_ratio", "contact_diameter"),
            "nondimensional": ("support", "stiffness_profile", "twist_ratio",
                               "bending_ratio", "contact_diameter")},
    "ends": {"si": ("rotation_turns", "tension", "shortening"),
             "nondimensional": ("rotation_turns", "tension", "shortening")},
    "magnetisation": {"si": ("kind", "remanence", "saturation", "angle_deg", "profile_deg",
                             "strength_profile"),
                      "nondimensional": ("kind", "angle_deg", "profile_deg", "strength_profile")},
    "gravity": {"si": ("g", "hanging"), "nondimensional": ("G", "hanging")},
}
FIELD_KEYS = {
    "uniform": {"si": ("kind", "B", "angle_deg", "azimuth_deg"),
                "nondimensional": ("kind", "load", "A", "angle_deg", "azimuth_deg")},
    "dipole": {"si": ("kind", "moment", "remanence", "diameter", "position",
                      "moment_direction", "path", "radius", "angle_deg", "rail", "along",
                      "coefficients", "t", "moment_along_path"),
               "nondimensional": ("kind", "M", "position", "moment_direction", "path",
                                  "radius", "angle_deg", "rail", "along", "coefficients", "t",
                                  "moment_along_path")},
}
TOP = ("units", "geometry", "rod", "ends", "magnetisation", "field", "gravity")

#: Plausible SI magnitudes: a value outside is a unit slip (a 30 T field, a 3 km rod).
@dataclasses.dataclass(frozen=True)
class FileScene:
    """A scene read from a file: the ``Scene``, the file keys that are scalar inputs
    (``inputs``: file key -> (scene key, factor), scene value = factor * file value), the
    rod's length in the file's unit (1 when nondimensional), the parsed file, and the
    magnets' radii in rod lengths by term name (``margins``: the clearance a path keeps)."""

    scene: Scene
    inputs: dict
    length: float
    data: dict
    margins: dict = dataclasses.field(default_factory=dict)
    framed: FramedSpec | None = None  # a rod that carries its frame (``scene`` is None)

    def input_of(self, key: str, what: str = "vary") -> tuple[str, float]:
        """(scene key, factor) of the file key ``key``; ParameterError (naming the option
        ``what`` and the nearest valid key) when it is not a scalar input."""
        if key not in self.inputs:
            near = difflib.get_close_matches(key, list(self.inputs), n=1)
            hint = f" (did you mean {near[0]!r}?)" if near else ""
            raise ParameterError(f"{what}: {key!r} is not a scalar input of this scene file"
                                 f"{hint}; its inputs: {', '.join(self.inputs)}")
        return self.inputs[key]

    def value(self, key: str) -> float:
        scene_key, factor = self.input_of(key)
        if self.framed is not None:
            return self.framed.value(scene_key) / factor
        return float(np.asarray(self.scene.value(scene_key))) / factor


def _toml():
    try:
        import tomllib
    except ModuleNotFoundError:  # Python 3.10
        raise ParameterError("TOML scene files and --set need Python >= 3.11 (tomllib); give "
                             "the scene as a .json file") from None
    return tomllib


def read(path: str | Path) -> dict:
    """The parsed file (TOML, or JSON for a .json file)."""
    path = Path(path)
    try:
        text = path.read_text()
    except OSError as err:
        raise ParameterError(f"scene file {str(path)!r}: {err.strerror}") from None
    try:
        if path.suffix.lower() == ".json":
            return json.loads(text)
        return _toml().loads(text)
    except (ValueError, json.JSONDecodeError) as err:
        raise ParameterError(f"scene file {path.name}: not valid "
                             f"{'JSON' if path.suffix.lower() == '.json' else 'TOML'}: "
                             f"{err}") from None


def apply_settings(data: dict, settings: list[str]) -> dict:
    """``data`` with ``KEY=VALUE`` overrides (dotted keys, list indices as numbers; the value
    parsed as a TOML value: numbers, strings in quotes, [x, z])."""
    import copy

    data = copy.deepcopy(data)
    for item in settings:
        key, sep, text = item.partition("=")
        if not sep:
            raise ParameterError(f"set: give KEY=VALUE, got {item!r}")
        try:
            value = _toml().loads(f"v = {text}")["v"]
        except ValueError:
            value = text  # a bare word: a string
        node, parts = data, key.strip().split(".")
        for i, part in enumerate(parts[:-1]):
            if isinstance(node, list) and not (part.isdigit() and int(part) < len(node)):
                raise ParameterError(f"set: {key!r} does not name an entry of the file ("
                                     f"{'.'.join(parts[:i]) or 'it'} has {len(node)} "
                                     f"entries, numbered from 0)")
            node = node[int(part)] if isinstance(node, list) \
                else node.setdefault(part, {}) if isinstance(node, dict) else None
            if node is None:
                raise ParameterError(f"set: {key!r} does not name an entry of the file")
        last = parts[-1]
        if isinstance(node, list) and last.isdigit() and int(last) < len(node):
            node[int(last)] = value
        elif isinstance(node, dict):
            node[last] = value
        else:
            raise ParameterError(f"set: {key!r} does not name an entry of the file")
    return data


def scene_from(data: dict) -> FileScene:
    """The scene of a parsed file (module docstring); ParameterError naming the key for
    unknown keys (with the nearest valid one), missing entries, unit slips and a magnet
    within the rod's reach."""
    if not isinstance(data, dict):
        raise ParameterError("scene file: must hold tables ([rod], [[field]], ...)")
    for key in data:
        if key not in TOP:
            unknown_key("", key, TOP)
    units = data.get("units", "SI")
    if units not in ("SI", "si", "nondimensional"):
        fail("units", f"must be \"SI\" or \"nondimensional\", got {units!r}")
    si = units.lower() == "si"
    system = "si" if si else "nondimensional"
    geometry = data.get("geometry", "planar")
    if geometry not in ("planar", "3d"):
        fail("geometry", f"must be \"planar\" or \"3d\", got {geometry!r}")
    tables = {}
    for name in ("rod", "ends", "magnetisation", "gravity"):
        table = data.get(name, {})
        if not isinstance(table, dict):
            fail(name, "must be a table")
        for key in table:
            if key not in TABLES[name][system]:
                unknown_key(f"{name}.", key, TABLES[name][system])
        if si:
            check_plausible(table, f"{name}.")
        tables[name] = table
    fields = data.get("field", [])
    if not isinstance(fields, list):
        fail("field", "must be an array of tables ([[field]])")
    for i, field in enumerate(fields):
        if not isinstance(field, dict):
            fail(f"field.{i}", "must be a table")
        if field.get("kind") not in FIELD_KEYS:
            fail(f"field.{i}.kind", f"must be one of {', '.join(FIELD_KEYS)}, got "
                                     f"{field.get('kind')!r}")
        for key in field:
            if key not in FIELD_KEYS[field["kind"]][system]:
                unknown_key(f"field.{i}.", key, FIELD_KEYS[field["kind"]][system])
        if si:
            check_plausible(field, f"field.{i}.")
    rod = tables["rod"]
    support = rod.get("support", "clamped")
    if support not in ("clamped", "pinned", "clamped-clamped"):
        fail("rod.support", f"must be \"clamped\", \"pinned\" or \"clamped-clamped\", got "
                            f"{support!r}")
    held = support == "clamped-clamped"
    if held and geometry != "3d":
        fail("rod.support", "\"clamped-clamped\" (both ends held, the far end turned) needs "
                            "geometry = \"3d\"")
    # a rod that carries its frame: held at both ends, or a 3D cantilever programmed at an
    # angle to its tangent (its remanence in the material frame)
    framed = held or (geometry == "3d" and support == "clamped" and any(
        k in tables["magnetisation"] for k in ("angle_deg", "profile_deg",
                                               "strength_profile")))
    for table, keys, ok, what in (
            ("rod", ("twist_ratio", "bending_ratio"), framed, "a rod that carries its frame "
             "(support = \"clamped-clamped\", or a 3D rod programmed at an angle)"),
            ("ends", tuple(tables["ends"]), held, "a rod held at both ends (support = "
             "\"clamped-clamped\")"),
            ("rod", ("contact_diameter",), held, "a rod held at both ends (support = "
             "\"clamped-clamped\")")):
        for key in keys:
            if key in tables[table] and not ok:
                fail(f"{table}.{key}", f"belongs to {what}")
    inputs: dict[str, tuple[str, float]] = {}
    margins: dict[str, float] = {}
    taper = coefficients(rod, "stiffness_profile", "rod.", chebyshev_form("E I(s) / E I"))
    terms = {"bending": Bending() if taper is None else TaperedBending(taper)}
    for k in range(0 if taper is None else len(taper)):
        inputs[f"rod.stiffness_profile.{k}"] = (f"bending.stiffness.{k}", 1.0)
    if si:
        L = number(rod, "length", "rod.")
        r = number(rod, "radius", "rod.")
        E = number(rod, "youngs_modulus", "rod.")
        if r >= L:
            fail("rod.radius", f"{r:g} m is not below the length {L:g} m: not a slender rod")
        area, inertia = math.pi * r**2, math.pi * r**4 / 4.0
        bending = E * inertia
        if "density" in rod and not number(rod, "density", "rod.") > 0:
            fail("rod.density", "must be > 0 kg/m^3 (the rod's mass: its weight and inertia)")
    else:
        L = 1.0
    if "gravity" in data:
        g_table = tables["gravity"]
        hanging = g_table.get("hanging", False)
        if not isinstance(hanging, bool):
            fail("gravity.hanging", f"must be true or false, got {hanging!r}")
        key = "g" if si else "G"
        if hanging and number(g_table, key, "gravity.") < 0:
            fail(f"gravity.{key}", "with hanging = true give the magnitude (>= 0): the rod "
                                    "hangs from its clamp, gravity along its axis")
        sign = -1.0 if hanging else 1.0  # hanging: gravity along +z, from the clamp to the tip
        if si:
            rho = number(rod, "density", "rod.")
            per_g = sign * rho * area * L**3 / bending
            g = number(g_table, "g", "gravity.")
            terms["gravity"] = Gravity(per_g * g)
            inputs["gravity.g"] = ("gravity.G", per_g)
        else:
            terms["gravity"] = Gravity(sign * number(g_table, "G", "gravity."))
            inputs["gravity.G"] = ("gravity.G", sign)
    mag = tables["magnetisation"]
    kind = mag.get("kind")
    if fields and kind not in ("hard", "soft"):
        fail("magnetisation.kind", f"must be \"hard\" or \"soft\", got {kind!r}")
    if si and fields:
        m_key = "remanence" if kind == "hard" else "saturation"
        magnetisation = number(mag, m_key, "magnetisation.")
    profile = angle_profile(mag, kind, "framed" if framed else geometry)
    strength = strength_profile(mag, kind, "framed" if framed else geometry, fields)
    for i, field in enumerate(fields):
        where = f"field.{i}."
        fkind = field["kind"]
        name = f"field{i}"
        angle = math.radians(number(field, "angle_deg", where, required=False, default=0.0))
        if fkind == "uniform":
            azimuth = math.radians(number(field, "azimuth_deg", where, required=False,
                                          default=0.0))
            if azimuth != 0.0 and geometry != "3d":
                fail(f"{where}azimuth_deg", "a planar rod's field lies in its plane (x-z); "
                                            "geometry = \"3d\" for a field out of it")
            if not si and "A" in field:
                if kind != "soft":
                    fail(f"{where}A", "the anisotropy group is the soft wire's "
                                       "(magnetisation.kind = \"soft\")")
                axis = direction(angle)
                terms[name] = Anisotropy(number(field, "A", where), np.array(
                    [axis[0] * math.cos(azimuth), axis[0] * math.sin(azimuth), axis[2]]))
                inputs[f"{where}A"] = (f"{name}.A", 1.0)
                continue
            per_b = area * magnetisation * L**2 / bending if si else 1.0
            load = per_b * number(field, "B" if si else "load", where)
            inputs[f"{where}{'B' if si else 'load'}"] = (f"{name}.load", per_b)
            if profile is None and strength is None:
                terms[name] = Zeeman(load, angle, azimuth)
            else:
                terms[name] = ProgrammedMagnetisation(
                    load, angle, np.zeros(1) if profile is None else profile,
                    np.ones(1) if strength is None else strength, azimuth)
                if profile is not None and len(profile) == 1 and len(fields) == 1:
                    inputs["magnetisation.angle_deg"] = (f"{name}.profile.0", math.pi / 180.0)
                if strength is not None and len(fields) == 1:
                    for k in range(len(strength)):
                        inputs[f"magnetisation.strength_profile.{k}"] = (
                            f"{name}.strength.{k}", 1.0)
            inputs[f"{where}angle_deg"] = (f"{name}.angle", math.pi / 180.0)
            if geometry == "3d" and not isinstance(terms[name], Anisotropy):
                inputs[f"{where}azimuth_deg"] = (f"{name}.azimuth", math.pi / 180.0)
            continue
        if profile is not None and field.get("path") in ("circle", "curve"):
            fail("magnetisation.angle_deg" if "angle_deg" in mag else
                  "magnetisation.profile_deg", "a magnetisation at an angle to the tangent "
                  "acts in uniform fields and the fields of magnets at a position (not on a "
                  "circle or a curve)")
        # a dipole
        if si:
            if "moment" in field:
                moment = number(field, "moment", where)
            else:
                a = 0.5 * number(field, "diameter", where)
                moment = 4.0 / 3.0 * math.pi * a**3 * number(field, "remanence", where)
            per_m = area * magnetisation * MU0 / (4.0 * math.pi * bending * L)
            M = per_m * moment
            m_key, m_factor = ("moment", per_m) if "moment" in field else (None, None)
        else:
            M = number(field, "M", where)
            m_key, m_factor = "M", 1.0
        if m_key is not None:
            inputs[f"{where}{m_key}"] = (f"{name}.M", m_factor)
        half = 0.5 * number(field, "diameter", where) / L if si and "diameter" in field \
            else 0.0
        if half > 0.0:
            margins[name] = half
        if field.get("path") == "circle":
            for key in ("position", "moment_direction", "rail", "along"):
                if key in field:
                    fail(f"{where}{key}", "a magnet on the circle has its position and "
                                           "moment from radius and angle_deg")
            D = number(field, "radius", where) / L
            if D <= 1.0 + half:
                fail(f"{where}radius", f"the magnet ({D:g} rod lengths from the clamp) is "
                                        "within the rod's reach (radius > length + magnet "
                                        "radius)")
            terms[name] = Dipole(M, D, angle)
            inputs[f"{where}radius"] = (f"{name}.D", 1.0 / L)
            inputs[f"{where}angle_deg"] = (f"{name}.alpha", math.pi / 180.0)
            continue
        if field.get("path") == "curve":
            terms[name] = _curve_dipole(field, where, M, L, half)
            inputs[f"{where}t"] = (f"{name}.t", 1.0)
            continue
        if "path" in field:
            fail(f"{where}path", f"must be \"circle\" or \"curve\" (or omitted), got "
                                  f"{field['path']!r}")
        for key in ("radius", "angle_deg"):
            if key in field:
                fail(f"{where}{key}", "belongs to path = \"circle\"; a free magnet takes "
                                       "position and moment_direction")
        pos = vector(field, "position", where, None)
        if pos is None:
            fail(f"{where}position", "missing (or give path = \"circle\")")
        c = np.array([pos[0], 0.0, pos[1]]) / L
        u = vector(field, "moment_direction", where, [0.0, 1.0])
        rail = vector(field, "rail", where, [1.0, 0.0])
        for key, v in (("moment_direction", u), ("rail", rail)):
            if math.hypot(*v) == 0.0:
                fail(f"{where}{key}", "must not be zero")
        along = number(field, "along", where, required=False, default=0.0) / L
        rail = np.array([rail[0], 0.0, rail[1]]) / math.hypot(*rail)
        where_c = f"{where}along" if "along" in field else f"{where}position"
        if np.linalg.norm(c + along * rail) <= 1.0 + half:
            fail(where_c, f"the magnet ({np.linalg.norm(c + along * rail):g} rod lengths from "
                           "the clamp) is within the rod's reach")
        inputs[f"{where}position.0"] = (f"{name}.position.0", 1.0 / L)
        inputs[f"{where}position.1"] = (f"{name}.position.2", 1.0 / L)
        if profile is not None:  # a distributed term of the positions
            if "along" in field or "rail" in field:
                fail(f"{where}rail", "a programmed magnetisation takes a magnet at a "
                                      "position (no rail)")
            terms[name] = ProgrammedDipole(M, c, np.array([u[0], 0.0, u[1]]), profile)
            continue
        terms[name] = PointDipole(M, c, np.array([u[0], 0.0, u[1]]), rail, along)
        inputs[f"{where}along"] = (f"{name}.along", 1.0 / L)
    if framed:
        spec = framed_spec(terms, inputs, tables, L**2 / bending if si else 1.0, support, L)
        return FileScene(None, inputs, L, data, margins, spec)
    scene = Scene(terms, geometry=geometry, support=support)
    return FileScene(scene, inputs, L, data, margins)


def _curve_dipole(field: dict, where: str, M, L, half):
    """A magnet on a curve c(t) = sum_k a_k t^k: ``coefficients`` = [[x0, z0], [x1, z1],
    ...] (the file's length unit), ``t`` (default 0), the moment along
    ``moment_direction`` or, with ``moment_along_path = true``, along the curve."""
    a = field.get("coefficients")
    if not isinstance(a, list) or len(a) < 2 or not all(
            isinstance(p, list) and len(p) == 2 and all(
                isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
                for v in p) for p in a):
        fail(f"{where}coefficients", "must be a list of at least two [x, z] pairs (c(t) = "
                                      f"a0 + a1 t + ...), got {a!r}")
    for key in ("position", "rail", "along", "radius", "angle_deg"):
        if key in field:
            fail(f"{where}{key}", "a magnet on a curve takes coefficients and t")
    coefficients = np.array([[x, 0.0, z] for x, z in a]) / L
    t = number(field, "t", where, required=False, default=0.0)
    along = field.get("moment_along_path", False)
    if not isinstance(along, bool):
        fail(f"{where}moment_along_path", f"must be true or false, got {along!r}")
    u = vector(field, "moment_direction", where, [0.0, 1.0])
    term = PathDipole(M, coefficients, t, np.array([u[0], 0.0, u[1]]), float(along))
    c = np.asarray(term.centre())
    if np.linalg.norm(c) <= 1.0 + half:
        fail(f"{where}t", f"the magnet ({np.linalg.norm(c):g} rod lengths from the clamp) is "
                           "within the rod's reach")
    return term


RIGS = Path(__file__).resolve().parent.parent / "rigs"


def presets() -> list[str]:
    """The names of the rigs that ship with jaxrod (``load`` takes a name for a path)."""
    return sorted(p.stem for p in RIGS.glob("*.toml"))


def load(path: str | Path, settings: list[str] = (), framed: bool = False) -> FileScene:
    """The scene of the file at ``path`` (or of the shipped rig of that name, ``presets``),
    with ``KEY=VALUE`` overrides (``apply_settings``). A rod that carries its frame (held at
    both ends, or a 3D rod programmed at an angle) only where ``framed`` (the commands that
    take it say so)."""
    path = Path(path)
    if not path.exists() and str(path) in presets():
        path = RIGS / f"{path}.toml"
    file = scene_from(apply_settings(read(path), list(settings)))
    if file.framed is not None and not framed:
        raise ParameterError("rod.support: a rod that carries its frame (held at both ends, "
                             "or a 3D rod programmed at an angle) is taken by jaxrod "
                             "equilibrium, branch, folds, fit, foldcurve and map, "
                             "not by this command")
    return file
