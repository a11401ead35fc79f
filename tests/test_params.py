import math
import re

import pytest

from jaxrod.params import (
    NDFEB_MAGNET,
    NICKEL,
    Magnet,
    Material,
    ParameterError,
    Rod,
    check_groups,
    check_track_clearance,
    preset,
)


@pytest.mark.parametrize("E_gpa, L_cm, G, A", [
    (100, 8, "2.893", "61.44"), (100, 12, "9.764", "138.24"),
    (200, 10, "2.825", "48.00"), (200, 12, "4.882", "69.12"),
])
def test_clamped_groups_match_paper_table(E_gpa, L_cm, G, A):
    rod, support = preset(f"clamped-{L_cm}cm", E_gpa * 1e9)
    assert support == "clamped"
    assert f"{rod.G:.3f}" == G
    assert f"{rod.A(True):.2f}" == A
    assert rod.A(False) == 0.0


def test_permanent_magnet_groups_match_paper_table():
    # tab:parameters_radial: E = 200 GPa: G 2.2, M 0.0236, A 40.62; E = 100 GPa: 4.4, 0.0472, 81.25
    for E, G, M, A in ((200e9, "2.2", "0.0236", 40.62), (100e9, "4.4", "0.0472", 81.25)):
        rod, _ = preset("permanent-magnet", E)
        assert f"{rod.G:.1f}" == G
        assert f"{rod.M(NDFEB_MAGNET):.4f}" == M
        assert abs(rod.A(True) - A) < 0.01
    rod, _ = preset("permanent-magnet")
    assert rod.D(NDFEB_MAGNET) == pytest.approx(11.25 / 9.2, rel=1e-15)


def test_stabilisation_length_and_twist_ratio():
    rod = Rod(NICKEL, 50e-6, 0.1)
    assert f"{rod.stabilisation_length:.2f}" == "1.70"
    assert rod.C == pytest.approx(1.0 / 1.31)
    # L_stab is where A = G
    at = rod.with_length(rod.stabilisation_length)
    assert at.A(True) == pytest.approx(at.G, rel=1e-14)


@pytest.mark.parametrize("make, name", [
    (lambda: Rod(NICKEL, 50e-6, -0.1), "length (rod length)"),
    (lambda: Rod(NICKEL, 0.0, 0.1), "diameter (wire diameter)"),
    (lambda: Rod(NICKEL, math.nan, 0.1), "diameter (wire diameter)"),
    (lambda: NICKEL.with_youngs_modulus(-1.0), "E (Young's modulus)"),
    (lambda: Material("x", 1e9, math.inf, 1.0, 1.0), "density"),
    (lambda: Material("x", 1e9, 1e3, 1.0, 1.0, poisson_ratio=0.7), "Poisson"),
    (lambda: Magnet(-1e-3, 8e5, 0.1), "magnet-diameter"),
    (lambda: check_track_clearance(1.0), "D (track radius"),
    (lambda: check_track_clearance(1.05, 0.1), "tip cannot touch"),
    (lambda: check_groups(G=0.0), "G (gravity group)"),
    (lambda: check_groups(A=math.nan), "A (anisotropy group)"),
    (lambda: check_groups(M=-1.0), "M (magnet group)"),
    (lambda: preset("nope"), "preset"),
])
def test_bad_input_names_the_parameter(make, name):
    with pytest.raises(ParameterError, match=re.escape(name)):
        make()


def test_magnet_touching_rod_is_refused():
    rod = Rod(NICKEL, 50e-6, 0.1)
    with pytest.raises(ParameterError, match="tip cannot touch"):
        rod.D(Magnet(diameter=0.05, remanence=8e5, track_radius=0.12))
