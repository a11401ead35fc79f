"""Scene files: a rig described in TOML (or JSON), read into a ``Scene`` and the map from the
file's keys to the scene's inputs.

A file in SI units (the default) or, with ``units = "nondimensional"``, in the groups:

    [rod]            length (m), radius (m), youngs_modulus (Pa), support ("clamped" at the
                     origin pointing along +z, or "pinned"), density (kg/m^3, with gravity)
    [magnetisation]  kind = "hard" (remanent, fixed in the material; remanence in A/m along
                     the tangent, or at angle_deg to it, or at a profile along s,
                     profile_deg = [c0, c1, ...] degrees, c0 + c1 s + ...; uniform fields
                     and magnets at a position; planar rods) or "soft" (the paper's wire,
                     saturated along the tangent with polarity +d3; saturation in A/m)
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
    Zeeman,
)

#: Allowed keys of each table, SI and nondimensional.
TABLES = {
    "rod": {"si": ("length", "radius", "youngs_modulus", "support", "density"),
            "nondimensional": ("support",)},
    "magnetisation": {"si": ("kind", "remanence", "saturation", "angle_deg", "profile_deg"),
                      "nondimensional": ("kind", "angle_deg", "profile_deg")},
    "gravity": {"si": ("g", "hanging"), "nondimensional": ("G", "hanging")},
}
FIELD_KEYS = {
    "uniform": {"si": ("kind", "B", "angle_deg"),
                "nondimensional": ("kind", "load", "A", "angle_deg")},
    "dipole": {"si": ("kind", "moment", "remanence", "diameter", "position",
                      "moment_direction", "path", "radius", "angle_deg", "rail", "along",
                      "coefficients", "t", "moment_along_path"),
               "nondimensional": ("kind", "M", "position", "moment_direction", "path",
                                  "radius", "angle_deg", "rail", "along", "coefficients", "t",
                                  "moment_along_path")},
}
TOP = ("units", "geometry", "rod", "magnetisation", "field", "gravity")

#: Plausible SI magnitudes: a value outside is a unit slip (a 30 T field, a 3 km rod).
SI_LIMITS = {"length": (1e-6, 100.0, "m"), "radius": (1e-8, 1.0, "m"),
             "youngs_modulus": (1.0, 1e13, "Pa"), "density": (0.0, 1e5, "kg/m^3"),
             "remanence": (0.0, 1e7, "A/m"), "saturation": (0.0, 1e7, "A/m"),
             "B": (0.0, 5.0, "T"), "g": (0.0, 1e4, "m/s^2"), "moment": (0.0, 1e6, "A m^2"),
             "diameter": (0.0, 10.0, "m")}


def _fail(key: str, message: str):
    raise ParameterError(f"{key}: {message}")


def _unknown(where: str, key: str, allowed) -> None:
    near = difflib.get_close_matches(key, list(allowed), n=1)
    hint = f" (did you mean {near[0]!r}?)" if near else ""
    _fail(f"{where}{key}", f"unknown key{hint}; valid here: {', '.join(allowed)}")


def _number(data: dict, key: str, where: str, required: bool = True, default=None):
    if key not in data:
        if required:
            _fail(f"{where}{key}", "missing")
        return default
    v = data[key]
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
        _fail(f"{where}{key}", f"must be a finite number, got {v!r}")
    return float(v)


#: SI entries that are sizes or magnitudes: a negative value is a sign slip, never a mirror
#: image (a negative E, radius or magnet diameter would give the answer of its opposite).
#: A sign is meaningful for B (a reversed field), g (a hanging rod: negative g) and the rod's
#: remanence (a magnetisation against the tangent); a magnet's moment takes its direction
#: from ``moment_direction``.
POSITIVE = ("length", "radius", "youngs_modulus", "density", "diameter", "saturation",
            "moment")


def _plausible(table: dict, where: str) -> None:
    """An SI file's numbers within ``SI_LIMITS`` (a 30 T field, a 3 km rod: a unit slip),
    sizes and magnitudes (``POSITIVE``, and a magnet's remanence) not negative; entries
    that are not finite numbers are left to ``_number``."""
    for key, v in table.items():
        lo_hi = SI_LIMITS.get(key)
        if lo_hi is None or isinstance(v, bool) or not isinstance(v, (int, float)) \
                or not math.isfinite(v):
            continue
        sized = key in POSITIVE or (key == "remanence" and where.startswith("field"))
        if sized and v <= 0.0 and not (v == 0.0 and key in ("saturation", "moment")):
            _fail(f"{where}{key}", f"must be > 0 {lo_hi[2]} (a size or magnitude), got {v:g}")
        if lo_hi[0] <= abs(v) <= lo_hi[1]:
            continue
        _fail(f"{where}{key}", f"{v:g} {lo_hi[2]} is outside the plausible {lo_hi[0]:g} to "
                               f"{lo_hi[1]:g} {lo_hi[2]}: a unit slip? (SI units; or set "
                               "units = \"nondimensional\")")


def _vector(data: dict, key: str, where: str, default):
    if key not in data:
        return default
    v = data[key]
    if not isinstance(v, list) or len(v) != 2 or not all(
            isinstance(c, (int, float)) and not isinstance(c, bool) and math.isfinite(c)
            for c in v):
        _fail(f"{where}{key}", f"must be two finite numbers [x, z], got {v!r}")
    return [float(c) for c in v]


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
            _unknown("", key, TOP)
    units = data.get("units", "SI")
    if units not in ("SI", "si", "nondimensional"):
        _fail("units", f"must be \"SI\" or \"nondimensional\", got {units!r}")
    si = units.lower() == "si"
    system = "si" if si else "nondimensional"
    geometry = data.get("geometry", "planar")
    if geometry not in ("planar", "3d"):
        _fail("geometry", f"must be \"planar\" or \"3d\", got {geometry!r}")
    tables = {}
    for name in ("rod", "magnetisation", "gravity"):
        table = data.get(name, {})
        if not isinstance(table, dict):
            _fail(name, "must be a table")
        for key in table:
            if key not in TABLES[name][system]:
                _unknown(f"{name}.", key, TABLES[name][system])
        if si:
            _plausible(table, f"{name}.")
        tables[name] = table
    fields = data.get("field", [])
    if not isinstance(fields, list):
        _fail("field", "must be an array of tables ([[field]])")
    for i, field in enumerate(fields):
        if not isinstance(field, dict):
            _fail(f"field.{i}", "must be a table")
        if field.get("kind") not in FIELD_KEYS:
            _fail(f"field.{i}.kind", f"must be one of {', '.join(FIELD_KEYS)}, got "
                                     f"{field.get('kind')!r}")
        for key in field:
            if key not in FIELD_KEYS[field["kind"]][system]:
                _unknown(f"field.{i}.", key, FIELD_KEYS[field["kind"]][system])
        if si:
            _plausible(field, f"field.{i}.")
    rod = tables["rod"]
    support = rod.get("support", "clamped")
    if support not in ("clamped", "pinned"):
        _fail("rod.support", f"must be \"clamped\" or \"pinned\", got {support!r}")
    inputs: dict[str, tuple[str, float]] = {}
    margins: dict[str, float] = {}
    terms = {"bending": Bending()}
    if si:
        L = _number(rod, "length", "rod.")
        r = _number(rod, "radius", "rod.")
        E = _number(rod, "youngs_modulus", "rod.")
        if r >= L:
            _fail("rod.radius", f"{r:g} m is not below the length {L:g} m: not a slender rod")
        area, inertia = math.pi * r**2, math.pi * r**4 / 4.0
        bending = E * inertia
        if "density" in rod and not _number(rod, "density", "rod.") > 0:
            _fail("rod.density", "must be > 0 kg/m^3 (the rod's mass: its weight and inertia)")
    else:
        L = 1.0
    if "gravity" in data:
        g_table = tables["gravity"]
        hanging = g_table.get("hanging", False)
        if not isinstance(hanging, bool):
            _fail("gravity.hanging", f"must be true or false, got {hanging!r}")
        key = "g" if si else "G"
        if hanging and _number(g_table, key, "gravity.") < 0:
            _fail(f"gravity.{key}", "with hanging = true give the magnitude (>= 0): the rod "
                                    "hangs from its clamp, gravity along its axis")
        sign = -1.0 if hanging else 1.0  # hanging: gravity along +z, from the clamp to the tip
        if si:
            rho = _number(rod, "density", "rod.")
            per_g = sign * rho * area * L**3 / bending
            g = _number(g_table, "g", "gravity.")
            terms["gravity"] = Gravity(per_g * g)
            inputs["gravity.g"] = ("gravity.G", per_g)
        else:
            terms["gravity"] = Gravity(sign * _number(g_table, "G", "gravity."))
            inputs["gravity.G"] = ("gravity.G", sign)
    mag = tables["magnetisation"]
    kind = mag.get("kind")
    if fields and kind not in ("hard", "soft"):
        _fail("magnetisation.kind", f"must be \"hard\" or \"soft\", got {kind!r}")
    if si and fields:
        m_key = "remanence" if kind == "hard" else "saturation"
        magnetisation = _number(mag, m_key, "magnetisation.")
    profile = _profile(mag, kind, geometry)
    for i, field in enumerate(fields):
        where = f"field.{i}."
        fkind = field["kind"]
        name = f"field{i}"
        angle = math.radians(_number(field, "angle_deg", where, required=False, default=0.0))
        if fkind == "uniform":
            if not si and "A" in field:
                if kind != "soft":
                    _fail(f"{where}A", "the anisotropy group is the soft wire's "
                                       "(magnetisation.kind = \"soft\")")
                terms[name] = Anisotropy(_number(field, "A", where), _direction(angle))
                inputs[f"{where}A"] = (f"{name}.A", 1.0)
                continue
            per_b = area * magnetisation * L**2 / bending if si else 1.0
            load = per_b * _number(field, "B" if si else "load", where)
            inputs[f"{where}{'B' if si else 'load'}"] = (f"{name}.load", per_b)
            if profile is None:
                terms[name] = Zeeman(load, angle)
            else:
                terms[name] = ProgrammedMagnetisation(load, angle, profile)
                if len(profile) == 1 and len(fields) == 1:
                    inputs["magnetisation.angle_deg"] = (f"{name}.profile.0", math.pi / 180.0)
            inputs[f"{where}angle_deg"] = (f"{name}.angle", math.pi / 180.0)
            continue
        if profile is not None and field.get("path") in ("circle", "curve"):
            _fail("magnetisation.angle_deg" if "angle_deg" in mag else
                  "magnetisation.profile_deg", "a magnetisation at an angle to the tangent "
                  "acts in uniform fields and the fields of magnets at a position (not on a "
                  "circle or a curve)")
        # a dipole
        if si:
            if "moment" in field:
                moment = _number(field, "moment", where)
            else:
                a = 0.5 * _number(field, "diameter", where)
                moment = 4.0 / 3.0 * math.pi * a**3 * _number(field, "remanence", where)
            per_m = area * magnetisation * MU0 / (4.0 * math.pi * bending * L)
            M = per_m * moment
            m_key, m_factor = ("moment", per_m) if "moment" in field else (None, None)
        else:
            M = _number(field, "M", where)
            m_key, m_factor = "M", 1.0
        if m_key is not None:
            inputs[f"{where}{m_key}"] = (f"{name}.M", m_factor)
        half = 0.5 * _number(field, "diameter", where) / L if si and "diameter" in field \
            else 0.0
        if half > 0.0:
            margins[name] = half
        if field.get("path") == "circle":
            for key in ("position", "moment_direction", "rail", "along"):
                if key in field:
                    _fail(f"{where}{key}", "a magnet on the circle has its position and "
                                           "moment from radius and angle_deg")
            D = _number(field, "radius", where) / L
            if D <= 1.0 + half:
                _fail(f"{where}radius", f"the magnet ({D:g} rod lengths from the clamp) is "
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
            _fail(f"{where}path", f"must be \"circle\" or \"curve\" (or omitted), got "
                                  f"{field['path']!r}")
        for key in ("radius", "angle_deg"):
            if key in field:
                _fail(f"{where}{key}", "belongs to path = \"circle\"; a free magnet takes "
                                       "position and moment_direction")
        pos = _vector(field, "position", where, None)
        if pos is None:
            _fail(f"{where}position", "missing (or give path = \"circle\")")
        c = np.array([pos[0], 0.0, pos[1]]) / L
        u = _vector(field, "moment_direction", where, [0.0, 1.0])
        rail = _vector(field, "rail", where, [1.0, 0.0])
        for key, v in (("moment_direction", u), ("rail", rail)):
            if math.hypot(*v) == 0.0:
                _fail(f"{where}{key}", "must not be zero")
        along = _number(field, "along", where, required=False, default=0.0) / L
        rail = np.array([rail[0], 0.0, rail[1]]) / math.hypot(*rail)
        where_c = f"{where}along" if "along" in field else f"{where}position"
        if np.linalg.norm(c + along * rail) <= 1.0 + half:
            _fail(where_c, f"the magnet ({np.linalg.norm(c + along * rail):g} rod lengths from "
                           "the clamp) is within the rod's reach")
        inputs[f"{where}position.0"] = (f"{name}.position.0", 1.0 / L)
        inputs[f"{where}position.1"] = (f"{name}.position.2", 1.0 / L)
        if profile is not None:  # a distributed term of the positions
            if "along" in field or "rail" in field:
                _fail(f"{where}rail", "a programmed magnetisation takes a magnet at a "
                                      "position (no rail)")
            terms[name] = ProgrammedDipole(M, c, np.array([u[0], 0.0, u[1]]), profile)
            continue
        terms[name] = PointDipole(M, c, np.array([u[0], 0.0, u[1]]), rail, along)
        inputs[f"{where}along"] = (f"{name}.along", 1.0 / L)
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
        _fail(f"{where}coefficients", "must be a list of at least two [x, z] pairs (c(t) = "
                                      f"a0 + a1 t + ...), got {a!r}")
    for key in ("position", "rail", "along", "radius", "angle_deg"):
        if key in field:
            _fail(f"{where}{key}", "a magnet on a curve takes coefficients and t")
    coefficients = np.array([[x, 0.0, z] for x, z in a]) / L
    t = _number(field, "t", where, required=False, default=0.0)
    along = field.get("moment_along_path", False)
    if not isinstance(along, bool):
        _fail(f"{where}moment_along_path", f"must be true or false, got {along!r}")
    u = _vector(field, "moment_direction", where, [0.0, 1.0])
    term = PathDipole(M, coefficients, t, np.array([u[0], 0.0, u[1]]), float(along))
    c = np.asarray(term.centre())
    if np.linalg.norm(c) <= 1.0 + half:
        _fail(f"{where}t", f"the magnet ({np.linalg.norm(c):g} rod lengths from the clamp) is "
                           "within the rod's reach")
    return term


def _profile(mag: dict, kind, geometry: str):
    """The magnetisation's angle to the tangent, polynomial coefficients in s (radians), or
    None along the tangent: ``angle_deg`` (constant) or ``profile_deg`` ([c0, c1, ...])."""
    if "angle_deg" in mag and "profile_deg" in mag:
        _fail("magnetisation.profile_deg", "give angle_deg (a constant angle) or profile_deg "
                                           "(coefficients in s), not both")
    if "angle_deg" not in mag and "profile_deg" not in mag:
        return None
    key = "angle_deg" if "angle_deg" in mag else "profile_deg"
    if kind != "hard":
        _fail(f"magnetisation.{key}", "only a hard magnetisation is programmed at an angle "
                                      "to the tangent")
    if geometry != "planar":
        _fail(f"magnetisation.{key}", "a programmed magnetisation needs geometry = "
                                      "\"planar\" (the 3D rod's chart carries no d1)")
    if key == "angle_deg":
        return np.radians([_number(mag, "angle_deg", "magnetisation.")])
    c = mag["profile_deg"]
    if not isinstance(c, list) or not c or not all(
            isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
            for v in c):
        _fail("magnetisation.profile_deg", f"must be a list of finite numbers (degrees: "
                                           f"c0 + c1 s + c2 s^2 ...), got {c!r}")
    return np.radians(np.asarray(c, float))


def _direction(angle: float):
    return np.array([math.sin(angle), 0.0, math.cos(angle)])


#: The rigs that ship as scene files (``presets()``), by name.
RIGS = Path(__file__).resolve().parent.parent / "rigs"


def presets() -> list[str]:
    """The names of the rigs that ship with jaxrod (``load`` takes a name for a path)."""
    return sorted(p.stem for p in RIGS.glob("*.toml"))


def load(path: str | Path, settings: list[str] = ()) -> FileScene:
    """The scene of the file at ``path`` (or of the shipped rig of that name, ``presets``),
    with ``KEY=VALUE`` overrides (``apply_settings``)."""
    path = Path(path)
    if not path.exists() and str(path) in presets():
        path = RIGS / f"{path}.toml"
    return scene_from(apply_settings(read(path), list(settings)))
