"""Scene files and the hard-magnetic rod: a cantilever in a uniform field against shooting
with scipy (an independent method), its snap when the field rotates, the paper's rig
written as a file against the paper's own fold path, and bad files."""

import contextlib
import io
import json
import math

import numpy as np
import pytest
from command_line import run_cli as _cli
from scipy.integrate import solve_ivp
from scipy.optimize import brentq, fsolve
from test_twisted import HELD  # a rod held at both ends

import jaxrod as jr
from jaxrod.params import ParameterError
from jaxrod.scenes.files import load, scene_from

CANTILEVER = """
[rod]
length = 0.05           # m
radius = 0.5e-3         # m
youngs_modulus = 1.0e6  # Pa
support = "clamped"     # at the origin, pointing along +z
[magnetisation]
kind = "hard"
remanence = 1.0e5       # A/m, along the tangent
[[field]]
kind = "uniform"
B = 1.25e-3             # T
angle_deg = 90          # from +z toward +x
"""
LAMBDA_PER_TESLA = 4000.0  # A_c M_r L^2 / (E I) for the file above: B = 1.25 mT gives 5


@pytest.fixture(scope="module")
def cantilever(tmp_path_factory):
    path = tmp_path_factory.mktemp("rigs") / "cantilever.toml"
    path.write_text(CANTILEVER)
    return path


# -- the independent reference: shooting on theta'' + G (1 - s) sin theta
#    + lam sin(a - theta) = 0, theta(0) = 0, theta'(1) = 0 -----------------------------------

def _shoot(k, lam, a, G, phi=None):
    def f(s, y):
        p = 0.0 if phi is None else phi(s)
        return [y[1], -lam * math.sin(a - y[0] - p) - G * (1 - s) * math.sin(y[0]),
                math.sin(y[0]), math.cos(y[0])]
    sol = solve_ivp(f, (0.0, 1.0), [0.0, k, 0.0, 0.0], method="DOP853", rtol=1e-13,
                    atol=1e-14)
    return sol.y[:, -1]


def shooting_equilibria(lam, a, G=0.0, k_max=12.0, count=241, phi=None):
    """Every equilibrium with |theta'(0)| <= k_max: (tip tangent deg, X1, X3) per root of
    theta'(1; k) = 0, bracketed on a grid of k and refined by brentq. ``phi``: the
    magnetisation's angle to the tangent along s (default 0)."""
    ks = np.linspace(-k_max, k_max, count)
    end = [_shoot(k, lam, a, G, phi)[1] for k in ks]
    out = []
    for k0, k1, f0, f1 in zip(ks[:-1], ks[1:], end[:-1], end[1:]):
        if f0 * f1 < 0:
            k = brentq(lambda k: _shoot(k, lam, a, G, phi)[1], k0, k1, xtol=1e-15,
                       rtol=1e-15)
            y = _shoot(k, lam, a, G, phi)
            out.append((math.degrees(y[0]), y[2], y[3]))
    return out


@pytest.mark.parametrize("angle_deg, load, g", [
    (30.0, 1.0, 0.0), (90.0, 5.0, 0.0), (150.0, 10.0, 0.0), (179.5, 20.0, 0.0),
    (120.0, 20.0, 0.0), (90.0, 5.0, 9.81), (179.5, 3.0, 9.81), (120.0, 5.0, -9.81)])
def test_hard_magnetic_cantilever_against_shooting(cantilever, angle_deg, load, g):
    """Tip tangent angle and tip position of the scene file's cantilever (SI, gravity from
    the rod's density; g < 0 here: the rod hanging, [gravity] hanging = true) against
    shooting, 1e-9 degrees and 1e-11 rod lengths; the equilibrium reached by the ramp is
    stable."""
    settings = [f"field.0.angle_deg={angle_deg}", f"field.0.B={load / LAMBDA_PER_TESLA}"]
    if g:
        settings += ["rod.density=100", f"gravity.g={abs(g)}"]  # |G| = 1.96
        settings += ["gravity.hanging=true"] if g < 0 else []
    file = load_file(cantilever, settings)
    G = float(file.scene.terms["gravity"].G) if g else 0.0
    eq = jr.equilibrium(file.scene, n=32)
    assert eq.converged and eq.stable, eq.status
    refs = shooting_equilibria(load, math.radians(angle_deg), G)
    ref = min(refs, key=lambda r: abs(r[0] - eq.tip_tangent_deg))
    assert abs(eq.tip_tangent_deg - ref[0]) <= 1e-9
    X = eq.tip_position * file.length
    assert abs(X[0] / file.length - ref[1]) <= 1e-11 and abs(X[2] / file.length - ref[2]) <= 1e-11
    assert abs(eq.tip_angle_deg - math.degrees(math.atan2(ref[1], ref[2]))) <= 1e-9


@pytest.mark.parametrize("setting, phi", [
    ("magnetisation.angle_deg=20", lambda s: math.radians(20.0)),
    ("magnetisation.profile_deg=[10.0, -30.0, 45.0]",
     lambda s: math.radians(10.0 - 30.0 * s + 45.0 * s * s)),
])
def test_programmed_magnetisation_against_shooting(cantilever, setting, phi):
    """A remanence at an angle phi(s) to the tangent (constant, or a profile in s): the
    density -load cos(theta + phi(s) - a); theta'' + load sin(a - theta - phi(s)) = 0 by
    shooting; tip angle to 1e-9 degrees."""
    file = load_file(cantilever, [setting, "field.0.B=2.5e-3"])
    eq = jr.equilibrium(file.scene, n=32)
    assert eq.converged and eq.stable
    ref = min(shooting_equilibria(10.0, math.radians(90.0), phi=phi),
              key=lambda r: abs(r[0] - eq.tip_tangent_deg))
    assert abs(eq.tip_tangent_deg - ref[0]) <= 1e-9


def load_file(path, settings):
    return load(path, settings)


def test_spectral_convergence_of_the_tip_angle(cantilever):
    """Error of the tip angle against shooting falls spectrally with N (to round-off)."""
    file = load_file(cantilever, ["field.0.angle_deg=150", "field.0.B=2.5e-3"])
    ref = shooting_equilibria(10.0, math.radians(150.0))
    errors = []
    for n in (6, 10, 14, 20, 28):
        eq = jr.equilibrium(file.scene, n=n)
        errors.append(min(abs(eq.tip_tangent_deg - r[0]) for r in ref))
    assert errors[0] > 1e-6 and errors[-1] < 1e-10
    assert all(b < a or b < 1e-10 for a, b in zip(errors, errors[1:]))


def _fold_by_shooting(lam, a0, k0):
    """A fold in the field angle by shooting: theta'(1; k, a) = 0 and d theta'(1)/dk = 0,
    the second from the variational equation u'' = lam cos(a - theta) u, u(0) = 0,
    u'(0) = 1 integrated with the state (exact to the integrator's tolerance); solved by
    fsolve from (k0, a0)."""

    def F(v):
        k, a = v

        def rhs(s, y):
            return [y[1], -lam * math.sin(a - y[0]), y[3], lam * math.cos(a - y[0]) * y[2]]
        y = solve_ivp(rhs, (0.0, 1.0), [0.0, k, 0.0, 1.0], method="DOP853", rtol=1e-13,
                      atol=1e-14).y[:, -1]
        return [y[1], y[3]]

    k, a = fsolve(F, [k0, a0], xtol=1e-14)
    assert max(abs(r) for r in F([k, a])) < 1e-11
    return math.degrees(a)


def test_snap_when_the_field_rotates_round_the_cantilever(cantilever):
    """Load 5, the field rotating from 90 degrees: the bent rod follows it past 180 degrees
    and snaps at a fold; the fold's angle against shooting (with the variational equation)
    to 1e-9 degrees, and the fold met on the way back its mirror image."""
    file = load_file(cantilever, ["field.0.B=1.25e-3"])
    key, factor = file.input_of("field.0.angle_deg")
    folds = jr.folds(file.scene, key, factor * 90.0, factor * 359.0, n=24)
    assert len(folds) == 2 and all(f.converged for f in folds)
    up, down = (f.value / factor for f in folds)
    assert abs(up + down - 360.0) <= 1e-9  # the mirror symmetry a -> 2 pi - a
    ref = _fold_by_shooting(5.0, math.radians(up + 0.5), 1.5)
    assert abs(up - ref) <= 1e-9


def test_pitchfork_of_the_opposed_field_is_a_stability_change_without_fold(cantilever):
    """Field opposite the magnetisation: the straight rod loses stability at load pi^2/4
    with no fold (a pitchfork); the branch brackets it."""
    file = load_file(cantilever, ["field.0.angle_deg=180"])
    key, factor = file.input_of("field.0.B")
    b = jr.branch(file.scene, key, 0.0, factor * 1e-3, n=16)
    i = int(np.argmax(b.morse_index > 0))
    assert i > 0 and b.value[i - 1] < math.pi**2 / 4 < b.value[i]
    assert not jr.folds(file.scene, key, 0.0, factor * 1e-3, n=16, throw=False)


PAPER_RIG = """
units = "nondimensional"
[magnetisation]
kind = "soft"
[gravity]
G = {G!r}
[[field]]
kind = "dipole"
path = "circle"
M = {M!r}
radius = {D!r}
angle_deg = 0
"""


def test_the_papers_rig_as_a_scene_file_gives_the_papers_folds(tmp_path):
    from jaxrod.magnet.diagram import make_scene
    from jaxrod.magnet.folds import locate_folds
    from jaxrod.params import NDFEB_MAGNET, preset

    rod, _ = preset("permanent-magnet")
    G, M, D = rod.G, rod.M(NDFEB_MAGNET), rod.D(NDFEB_MAGNET)
    path = tmp_path / "paper.toml"
    path.write_text(PAPER_RIG.format(G=G, M=M, D=D))
    file = load(path)
    key, factor = file.input_of("field.0.angle_deg")
    found = jr.folds(file.scene, key, 0.0, factor * 90.0, n=16)
    paper = locate_folds(make_scene(G, M, D), n=16)
    assert len(found) == len(paper.folds) == 2
    for f, p in zip(sorted(found, key=lambda f: f.value), paper.folds):
        assert abs(f.value / factor - p.alpha_deg) <= 1e-10


def test_cli_equilibrium_and_folds_on_a_scene_file(cantilever):
    proc = _cli("equilibrium", str(cantilever), "--json")
    assert proc.returncode == 0, proc.stderr
    out = json.loads(proc.stdout)
    ref = min(shooting_equilibria(5.0, math.radians(90.0)),
              key=lambda r: abs(r[0] - out["tip_tangent_deg"]))
    assert abs(out["tip_tangent_deg"] - ref[0]) <= 1e-8
    assert abs(out["tip_position"][0] - 0.05 * ref[1]) <= 1e-12
    assert out["stable"] and out["converged"]
    proc = _cli("folds", str(cantilever), "--vary", "field.0.angle_deg", "--from", "90",
                "--to", "359", "--json")
    assert proc.returncode == 0, proc.stderr
    out = json.loads(proc.stdout)
    assert out["vary"] == "field.0.angle_deg" and len(out["folds"]) == 2 and out["converged"]
    assert {"value", "tip_angle_deg"} <= set(out["folds"][0])


BAD = [
    ("[rod]\nlenght = 0.05\n", "rod.lenght", "length"),
    (CANTILEVER.replace("youngs_modulus = 1.0e6  # Pa\n", ""), "rod.youngs_modulus", "missing"),
    (CANTILEVER.replace("B = 1.25e-3", "B = 30.0"), "field.0.B", "unit slip"),
    (CANTILEVER.replace("length = 0.05", "length = 3000.0"), "rod.length", "unit slip"),
    (CANTILEVER.replace('kind = "uniform"\nB = 1.25e-3             # T\nangle_deg = 90',
                        'kind = "dipole"\nmoment = 1.0\nposition = [0.01, 0.03]'),
     "field.0.position", "reach"),
    (CANTILEVER.replace('kind = "hard"', 'kind = "permanent"'), "magnetisation.kind", "hard"),
    ("[rod]\nlength = 0.05\n[[field]]\nkind = \"uniform\"\nB = 1e-3\nangel_deg = 90\n",
     "field.0.angel_deg", "angle_deg"),
    (CANTILEVER.replace("remanence = 1.0e5", "remanence = 1.0e5\nstrength_profile = [1.0, nan]"),
     "magnetisation.strength_profile", "finite"),
    (HELD.replace("tension = 5.0", "tension = 5.0\nshortening = 0.03"), "ends", "one of"),
    (HELD.replace("tension = 5.0", ""), "ends", "one of"),
    (HELD.replace("twist_ratio = 0.769", "twist_ratio = 0.0"), "rod.twist_ratio", "> 0"),
    (HELD.replace("tension = 5.0", "shortening = 1.5"), "ends.shortening", "(0, 1)"),
    (HELD.replace('geometry = "3d"', 'geometry = "planar"'), "rod.support", "3d"),
    (HELD.replace('"clamped-clamped"', '"clamped"'), "rod.twist_ratio", "carries its frame"),
    (HELD.replace("twist_ratio = 0.769", "twist_ratio = 0.769\ncontact_diameter = 0.5"),
     "rod.contact_diameter", "(0, 0.1]"),
    (CANTILEVER.replace("length = 0.05", "length = 0.05\ncontact_diameter = 1e-3"),
     "rod.contact_diameter", "both ends"),
]


@pytest.mark.parametrize("text, key, words", BAD)
def test_bad_scene_files_name_the_key(text, key, words, tmp_path):
    import tomllib

    with pytest.raises(ParameterError, match=key.replace(".", r"\.")) as err:
        scene_from(tomllib.loads(text))
    assert words in str(err.value)


@pytest.mark.parametrize("text, key, words", BAD)
def test_every_bad_scene_file_exits_2_with_one_line_naming_the_key(text, key, words,
                                                                    tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text(text)
    proc = _cli("equilibrium", str(bad))
    lines = proc.stderr.strip().splitlines()
    assert proc.returncode == 2 and len(lines) == 1 and key in lines[0], proc.stderr


def test_bad_scene_files_exit_2_with_one_line(cantilever, tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text(BAD[2][0])
    for argv, word in [(("equilibrium", str(bad)), "field.0.B"),
                       (("folds", str(cantilever), "--vary", "rod.support", "--from", "0.04",
                         "--to", "0.06"), "rod.support"),
                       (("equilibrium", str(cantilever), "--set", "field.0.B=3e3"), "B"),
                       (("equilibrium", str(tmp_path / "missing.toml")), "missing.toml")]:
        proc = _cli(*argv)
        lines = proc.stderr.strip().splitlines()
        assert proc.returncode == 2 and len(lines) == 1 and word in lines[0], proc.stderr


def test_the_shipped_permanent_magnet_rig_in_si_gives_the_presets_folds():
    """The paper's experiment as the shipped SI scene file: the same folds as
    ``jaxrod folds --preset permanent-magnet`` (the groups from the physical inputs) to
    1e-10 degrees; the shipped rigs all load."""
    from jaxrod.magnet.diagram import make_scene
    from jaxrod.magnet.folds import locate_folds
    from jaxrod.params import NDFEB_MAGNET, preset
    from jaxrod.scenes.files import presets

    assert {"permanent-magnet", "hard-magnetic-cantilever"} <= set(presets())
    file = load("permanent-magnet")
    rod, _ = preset("permanent-magnet")
    paper = locate_folds(make_scene(rod.G, rod.M(NDFEB_MAGNET), rod.D(NDFEB_MAGNET)), n=16)
    key, factor = file.input_of("field.0.angle_deg")
    found = sorted(jr.folds(file.scene, key, 0.0, factor * 90.0, n=16),
                   key=lambda f: f.value)
    assert len(found) == len(paper.folds) == 2
    for f, p in zip(found, paper.folds):
        assert abs(f.value / factor - p.alpha_deg) <= 1e-10
        assert abs(f.tip_angle_deg - p.tip_deg) <= 1e-9
    assert load("hard-magnetic-cantilever").scene.terms["field0"].load == pytest.approx(5.0)


RAIL = """
units = "nondimensional"
[magnetisation]
kind = "soft"
[gravity]
G = 2.2
[[field]]
kind = "dipole"
M = 0.25
position = [0.0, 1.2]        # on a straight rail at height 1.2 rod lengths
moment_direction = [0.0, 1.0]
"""


def _rail_position_of_k(k, guess, G=2.2, M=0.25, z=1.2):
    """Shooting in the natural parameter k = theta'(0): the rail position x and the tip X
    with theta'' = -G (1 - s) sin theta + P1 cos theta - P2 sin theta, P = M grad Phi(X)
    (the Euler-Lagrange equation of the endpoint potential), theta'(1) = 0, X = int d3."""
    def grad_phi(X1, X3, x):
        r = np.array([X1 - x, X3 - z])
        m = np.array([0.0, 1.0])
        rn = math.hypot(*r)
        return m / rn**3 - 3.0 * np.dot(m, r) * r / rn**5

    def F(v):
        x, X1, X3 = v
        P = M * grad_phi(X1, X3, x)

        def rhs(s, y):
            return [y[1], -G * (1 - s) * math.sin(y[0]) + P[0] * math.cos(y[0])
                    - P[1] * math.sin(y[0]), math.sin(y[0]), math.cos(y[0])]
        y = solve_ivp(rhs, (0.0, 1.0), [0.0, k, 0.0, 0.0], method="DOP853", rtol=1e-13,
                      atol=1e-14).y[:, -1]
        return [y[1], y[2] - X1, y[3] - X3]

    return fsolve(F, guess, xtol=1e-13)


def rail_folds_by_shooting(M, z):
    """(release, capture) of the rail rig at (M, z): the extrema of the rail position along
    the branch parametrised by theta'(0) (shooting)."""
    from scipy.optimize import minimize_scalar

    guess = {"x": np.array([1.0, 0.2, 0.97])}

    def rail(k, sign):
        v = _rail_position_of_k(k, guess["x"], M=M, z=z)
        guess["x"] = v
        return sign * v[0]

    lo = minimize_scalar(lambda k: rail(k, 1.0), bounds=(0.4, 0.8), method="bounded",
                         options={"xatol": 1e-10})
    hi = minimize_scalar(lambda k: rail(k, -1.0), bounds=(1.1, 1.55), method="bounded",
                         options={"xatol": 1e-10})
    return -hi.fun, lo.fun


def test_a_magnet_on_a_straight_rail_folds_against_shooting(tmp_path):
    """The paper's soft wire and a magnet moved along a straight rail above it (moment up):
    capture and release are folds in the rail position, found by the engine along
    field.0.position.0 and, independently, as the extrema of the rail position along the
    branch parametrised by theta'(0) (shooting); agreement to 1e-9 rod lengths."""
    path = tmp_path / "rail.toml"
    path.write_text(RAIL)
    file = load(path)
    key, factor = file.input_of("field.0.position.0")
    folds = jr.folds(file.scene, key, 0.0, 1.5, n=24)
    assert len(folds) == 2
    release, capture = sorted(f.value / factor for f in folds)[::-1]
    ref_release, ref_capture = rail_folds_by_shooting(0.25, 1.2)
    assert abs(capture - ref_capture) <= 1e-9
    assert abs(release - ref_release) <= 1e-9


def test_cli_foldcurve_on_a_scene_file_passes_the_cusp_of_the_pitchfork(tmp_path):
    """The snap's fold in the field angle, followed in B down from 1.25 mT: its two branches
    meet at a cusp where the field opposes the magnetisation at load pi^2/4 (the imperfect
    pitchfork's organising centre), here B = pi^2 / (4 * 4000) T, the field at 180 degrees:
    the cusp refined (it was the bracket's midpoint, 7.5e-5 off), to 1e-12 T and 1e-9 deg;
    foldcurve.png beside the JSON."""
    proc = _cli("foldcurve", "hard-magnetic-cantilever", "--vary", "field.0.angle_deg",
                "--from", "90", "--to", "359", "--along", "field.0.B", "--along-to", "3e-4",
                "--json", "--out", str(tmp_path / "curve"))
    assert proc.returncode == 0, proc.stderr
    out = json.loads(proc.stdout)
    (cusp,) = out["cusps"]
    assert cusp["converged"] and out["converged"] and out["status"] == "success"
    assert abs(cusp["along"] - math.pi**2 / 4 / LAMBDA_PER_TESLA) <= 1e-12
    assert abs(cusp["value"] - 180.0) <= 1e-9
    assert (tmp_path / "curve" / "foldcurve.png").stat().st_size > 0


def test_cli_map_on_a_scene_file(tmp_path):
    """The rail's folds on a 2 x 2 grid of the magnet's strength and height: map.json, map.png
    and the store map.zarr; a point's fold count and first fold as jr.folds gives them
    there."""
    path = tmp_path / "rail.toml"
    path.write_text(RAIL)
    out_dir = tmp_path / "map"
    proc = _cli("map", str(path), "--vary", "field.0.position.0", "--from", "0", "--to", "1.5",
                "--x", "field.0.M:0.15:0.25:2", "--y", "field.0.position.1:1.2:1.35:2",
                "--out", str(out_dir), "--json")
    assert proc.returncode == 0, proc.stderr
    assert (out_dir / "map.png").exists()
    data = json.loads((out_dir / "map.json").read_text())
    file = load(path, ["field.0.M=0.25", "field.0.position.1=1.2"])
    key, factor = file.input_of("field.0.position.0")
    folds = jr.folds(file.scene, key, 0.0, 1.5, n=16)
    assert data["count"][0][1] == len(folds) == 2
    assert abs(data["first"][0][1] - folds[0].value / factor) <= 1e-9
    assert data["count"][1][0] == 0  # higher and weaker: no loop
    # the map's store: read back as the map, and the same command again resumes it (nothing
    # left to compute) to the same map.json
    from jaxrod.bistability.fold_map import read_fold_map

    stored = read_fold_map(out_dir / "map.zarr")
    assert stored.count.tolist() == data["count"]
    again = _cli("map", str(path), "--vary", "field.0.position.0", "--from", "0", "--to",
                 "1.5", "--x", "field.0.M:0.15:0.25:2", "--y", "field.0.position.1:1.2:1.35:2",
                 "--out", str(out_dir), "--json")
    assert again.returncode == 0, again.stderr
    assert json.loads((out_dir / "map.json").read_text()) == data


def test_a_rail_at_any_angle_is_a_load_path(tmp_path):
    """The magnet moved along a rail (position + along * rail): along a horizontal rail from
    x0 = 0.5 the folds are those in the horizontal position, shifted by x0; along a tilted
    rail the magnet's centre is where the rail puts it."""
    path = tmp_path / "rail.toml"
    path.write_text(RAIL)
    direct = load(path)
    key, _ = direct.input_of("field.0.position.0")
    ref = [f.value for f in jr.folds(direct.scene, key, 0.0, 1.5, n=16)]
    railed = load(path, ["field.0.position=[0.5, 1.2]", "field.0.rail=[2.0, 0.0]"])
    key, factor = railed.input_of("field.0.along")
    got = [f.value / factor for f in jr.folds(railed.scene, key, -0.5, 1.0, n=16)]
    assert len(got) == len(ref) == 2
    assert all(abs(g + 0.5 - r) <= 1e-10 for g, r in zip(got, ref))
    tilted = load(path, ["field.0.position=[0.0, 1.5]", "field.0.rail=[1.0, -1.0]",
                         "field.0.along=0.5"])
    c = np.asarray(tilted.scene.terms["field0"].centre())
    assert np.allclose(c, [0.5 / math.sqrt(2), 0.0, 1.5 - 0.5 / math.sqrt(2)], atol=1e-15)
    with pytest.raises(ParameterError, match="field.0.along"):
        load(path, ["field.0.position=[0.0, 1.5]", "field.0.rail=[0.0, -1.0]",
                    "field.0.along=0.8"])


def test_cli_sweep_of_a_scene_file_snaps_past_the_fold():
    """The field rotating round the hard-magnetic cantilever (load 5), quasi-statically in
    steps of 0.1 degrees: the rod snaps at the first step past the fold (212.1477 degrees,
    refined by jr.folds); at a finite rate it snaps later."""
    file = load("hard-magnetic-cantilever")
    key, factor = file.input_of("field.0.angle_deg")
    fold = jr.folds(file.scene, key, factor * 90.0, factor * 300.0, n=16)[0].value / factor
    proc = _cli("sweep", "hard-magnetic-cantilever", "--vary", "field.0.angle_deg", "--from",
                "90", "--to", "300", "--step", "0.1", "--json")
    assert proc.returncode == 0, proc.stderr
    (snap,) = json.loads(proc.stdout)["switches"]
    assert fold < snap <= fold + 0.1 + 1e-9
    proc = _cli("sweep", "hard-magnetic-cantilever", "--vary", "field.0.angle_deg", "--from",
                "90", "--to", "240", "--rate", "5", "--damping", "2", "--json")
    assert proc.returncode == 0, proc.stderr
    (late,) = json.loads(proc.stdout)["switches"]
    assert fold < late < fold + 20.0  # 10.6 degrees late at this speed
    proc = _cli("sweep", "hard-magnetic-cantilever", "--vary", "field.0.angle_deg", "--from",
                "90", "--to", "180", "--rate", "5", "--damping", "2", "--json")
    assert proc.returncode == 0 and json.loads(proc.stdout)["switches"] == []  # no fold


def test_cli_snap_and_sweep_outputs_of_a_scene_file(tmp_path):
    """jaxrod snap RIG --fold 1: the snap from the first fold of the field's rotation round
    the hard-magnetic cantilever; the rod comes to rest on an equilibrium that shooting
    finds at the value it was moved to (1e-8 deg). jaxrod sweep RIG --out writes the sweep's
    CSV (one row a value, the snap marked), JSON and figure."""
    from jaxrod.cli import main

    with contextlib.redirect_stdout(io.StringIO()) as out:
        assert main(["snap", "hard-magnetic-cantilever", "--vary", "field.0.angle_deg",
                     "--from", "90", "--to", "300", "--fold", "1", "--t-end", "40",
                     "--json"]) == 0
    s = json.loads(out.getvalue())
    assert 212.0 < s["fold_value"] < s["value"] < 212.3 and s["duration"] is not None
    landings = [math.degrees(math.atan2(x1, x3)) for _, x1, x3 in
                shooting_equilibria(5.0, math.radians(s["value"]))]
    assert min(abs(t - s["rest_tip_deg"]) for t in landings) <= 1e-8
    with contextlib.redirect_stdout(io.StringIO()):
        assert main(["sweep", "hard-magnetic-cantilever", "--vary", "field.0.angle_deg",
                     "--from", "90", "--to", "220", "--step", "5", "--quiet", "--out",
                     str(tmp_path / "sweep")]) == 0
    rows = (tmp_path / "sweep" / "sweep.csv").read_text().splitlines()
    assert rows[0].startswith("field.0.angle_deg,tip_angle_deg") and len(rows) == 28
    assert sum(int(r.split(",")[4]) for r in rows[1:]) == 1  # one snap
    summary = json.loads((tmp_path / "sweep" / "sweep.json").read_text())
    assert summary["complete"] and len(summary["snaps"]) == 1
    assert (tmp_path / "sweep" / "sweep.png").stat().st_size > 0
