"""Every figure renders, its legend lists only what is drawn, and its title gives the inputs."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
from figure_checks import absent_legend_entries, check_figure, figure_title  # noqa: E402

import jaxrod as jr  # noqa: E402
from jaxrod.magnet.diagram import figure_options  # noqa: E402
from jaxrod.plotting import _branch_segments  # noqa: E402

pytestmark = pytest.mark.xdist_group("figures")

PAPER = (2.2, 0.0236, 11.25 / 9.2)


def test_the_legend_check_catches_an_absent_item():
    fig, ax = plt.subplots()
    ax.plot([0, 1], [0, 1], "-", color="C0", label="drawn")
    ax.plot([], [], "k*", label="never drawn")
    ax.legend()
    assert absent_legend_entries(fig) == ["never drawn"]
    plt.close(fig)


@pytest.fixture(scope="module")
def paper_report():
    scene = jr.magnet_scene(*PAPER)
    return jr.folds(scene, n=12, branch=jr.diagram(scene, 12, figure_options()))


def test_diagram_figure(paper_report, tmp_path):
    fig = jr.diagram_figure(paper_report)
    check_figure(fig, tmp_path, "branch", ("G = 2.2", "M = 0.0236", "D = 1.2228", "N = 12"))
    # the curves reach both folds on both sides: each piece ends at a refined fold
    ends = {(round(xs[-1], 9), round(ys[-1], 9))
            for xs, ys, _ in _branch_segments(paper_report, "tip")[:-1]}
    folds = {(round(s * f.alpha_deg, 9), round(s * f.tip_deg, 9))
             for f in paper_report.folds for s in (1, -1)}
    assert ends == folds and len(folds) == 4


def test_diagram_is_dense_near_the_folds(paper_report):
    """In the figure's (alpha, tip) plane, in degrees: no step longer than 3 (the default
    steps reach 5.7) and two points within 1 of each fold (the default: 1.4 at the lower)."""
    a, t = np.degrees(paper_report.branch.alpha), np.degrees(paper_report.branch.tip)
    assert np.hypot(np.diff(a), np.diff(t)).max() < 3.0
    for f in paper_report.folds:
        assert np.sort(np.hypot(a - f.alpha_deg, t - f.tip_deg))[1] < 1.0


@pytest.mark.parametrize("M, hysteresis", [(PAPER[1], True), (0.005, False)])
def test_hysteresis_figure(M, hysteresis, tmp_path):
    scene = jr.magnet_scene(PAPER[0], M, PAPER[2])
    sweep = jr.sweep(scene, n=12, alpha_max_deg=45.0, step_deg=1.0)
    report = jr.folds(scene, n=12)
    fig = jr.hysteresis_figure(sweep, report)
    check_figure(fig, tmp_path, "sweep", ("G = 2.2", f"M = {M:.4g}"))
    title = figure_title(fig)
    assert ("hysteresis width" in title) == hysteresis
    assert ("no hysteresis" in title) == (not hysteresis)
    if not hysteresis:  # both directions visible: different widths and line styles
        styles = {(ln.get_linewidth(), ln.get_linestyle()) for ln in fig.axes[0].lines
                  if len(ln.get_xdata()) > 1}
        assert len(styles) == 2


def test_stability_diagram_figure(tmp_path):
    check_figure(jr.stability_diagram_figure(points=24), tmp_path, "stability")


def test_fold_curve_figure(tmp_path):
    point = jr.DesignPoint.from_groups(*PAPER)
    curves = jr.fold_curves(point, "D", 1.5, n=12)
    check_figure(jr.fold_curve_figure(curves, point), tmp_path, "foldcurve",
                 ("G = 2.2", "M = 0.0236"))


def test_design_map_figure(tmp_path):
    point = jr.DesignPoint.from_groups(*PAPER)
    spec = jr.MapSpec(point, jr.MapAxis.parse("D:1.15:1.45:6"), jr.MapAxis.parse("M:0.015:0.03:5"),
                      chunk=6)
    jr.bistability_map(spec, tmp_path / "map", progress=False)
    data = jr.read_map(tmp_path / "map")
    check_figure(jr.design_map_figure(data, spec), tmp_path, "map")


def test_conditioning_figure(tmp_path):
    # the figure only: arrays shaped like ``conditioning_near_fold``'s (its numbers are
    # checked by the conditioning benchmark's quick run)
    from jaxrod.plotting import CONDITIONING_LABELS

    distance = np.geomspace(1e-6, 1e-1, 6)
    study = {"distance_deg": distance, "dq": np.sqrt(distance)}
    study |= {key: 10.0 ** (k + 1) / np.sqrt(distance) ** (key == "full")
              for k, key in enumerate(CONDITIONING_LABELS)}
    check_figure(jr.conditioning_figure({"upper fold": study, "lower fold": study}), tmp_path,
                 "conditioning")


def test_fold_curve_figure_shades_only_the_sweeps_bistability(tmp_path):
    """G = 4.4, M = 0.0472 towards D = 1.01: the upper fold passes 90 degrees at D = 1.076
    and ends at a cusp at 103.6 degrees that the lower fold never meets. The shading (bistable
    in the sweep) stays within (0, 90] degrees and starts where the upper fold leaves it; the
    90-degree exit is named with its fold; the cusp is not called the end of the
    bistability. (The last release shaded up to 103.6 degrees and labelled that "cusp".)"""
    point = jr.DesignPoint.from_groups(4.4, 0.0472, 1.2228)
    curves = jr.fold_curves(point, "D", 1.01, n=12)
    exit_90 = [e for c in curves for e in c.special_points if e.kind == "alpha = 90 deg"]
    assert len(exit_90) == 1 and exit_90[0].curve == "upper"
    fig = jr.fold_curve_figure(curves)
    ax = fig.axes[0]
    shaded = [c for c in ax.collections if len(c.get_paths())]
    ys = np.concatenate([p.vertices[:, 1] for c in shaded for p in c.get_paths()])
    xs = np.concatenate([p.vertices[:, 0] for c in shaded for p in c.get_paths()])
    assert ys.max() <= 90.0 + 1e-9 and ys.min() > 0.0
    assert xs.min() >= exit_90[0].along_value - 1e-3
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert any("upper fold reaches 90 deg" in t for t in labels)
    assert not any("bistability ends" in t for t in labels)
    check_figure(fig, tmp_path, "foldcurve_beyond_90")


def test_design_map_figure_spans_the_grid_and_draws_every_kind_of_point(tmp_path):
    """Not bistable, invalid, beyond 90 degrees, not computed: each drawn and named (the last
    release drew the uncomputed strip white, like "not bistable"), and the axes end at the
    grid even where a cusp lies outside it."""
    point = jr.DesignPoint.from_groups(*PAPER)
    spec = jr.MapSpec(point, jr.MapAxis.parse("D:1.15:1.45:6"),
                      jr.MapAxis.parse("M:0.015:0.03:5"), chunk=6)
    x, y = spec.x.values(), spec.y.values()
    from jaxrod.magnet.batch import FOLD_BEYOND_90, INVALID_INPUT, NOT_BISTABLE

    reason = np.zeros((5, 6), np.int8)
    reason[:, 4:] = NOT_BISTABLE
    reason[0, 0], reason[1, 0], reason[4, :2] = INVALID_INPUT, FOLD_BEYOND_90, -1
    width = np.where(reason == 0, 10.0 + np.arange(30).reshape(5, 6), np.nan)
    data = {"x": x, "y": y, "status": reason, "width_deg": width,
            "capture_deg": width + 20.0, "release_deg": 2 * width + 20.0}
    cusps = [{"D": 1.6, "M": 0.02}]  # outside the grid
    fig = jr.design_map_figure(data, spec, cusps)
    ax = fig.axes[0]
    assert ax.get_xlim() == (x.min(), x.max()) and ax.get_ylim() == (y.min(), y.max())
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    for text in ("not bistable", "invalid input", "a fold beyond 90 deg", "not computed"):
        assert any(text in t for t in labels), (text, labels)
    assert any(h.get_hatch() for h in ax.get_legend().legend_handles if hasattr(h, "get_hatch"))
    check_figure(fig, tmp_path, "map_kinds")
