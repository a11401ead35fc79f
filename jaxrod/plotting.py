"""Matplotlib figures from jaxrod results (the numerics never import this module)."""

from __future__ import annotations

import textwrap

import matplotlib

if not matplotlib.get_backend().lower().startswith("module://"):  # keep notebook backends
    matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from jaxrod.uniform.greenhill import greenhill_load, paper_bounds, stability_curve  # noqa: E402


def stability_diagram_figure(report: dict | None = None, G_range=(1e-2, 1e3), points: int = 200):
    """(G, A) stability diagram for both supports, paper bounds dashed, A2 against G.

    ``report`` (from ``jaxrod.reproduce.uniform_field_report``) places the experiments.
    """
    G = np.geomspace(*G_range, points)
    g_crit = greenhill_load()
    fig, (ax, ax2) = plt.subplots(1, 2, figsize=(12, 4.8))
    colours = {"clamped": "C0", "pinned": "C1"}
    for support, colour in colours.items():
        a_crit, a2 = stability_curve(G, support)
        ax.plot(G, a_crit, color=colour, lw=2, label=f"{support}: exact A_crit = -beta0(G)")
        bounds = np.array([paper_bounds(g, support, g_crit) for g in G])
        ax.plot(G, bounds[:, 0], "--", color=colour, lw=1, label=f"{support}: paper's bounds")
        ax.plot(G, bounds[:, 1], "--", color=colour, lw=1)
        ax2.plot(G, a2, color=colour, lw=2, label=f"{support}")
    ax.axvline(g_crit, color="0.5", lw=0.8, ls=":")
    ax.text(g_crit * 1.05, 2e-2, "G_crit", color="0.4")
    if report is not None:
        for key, marker in (("clamped", "o"), ("pinned", "s")):
            rows = report[key]
            ax.scatter([r["G"] for r in rows], [r["A"] for r in rows], marker=marker,
                       color=colours[key], edgecolor="k", zorder=5,
                       label=f"{key} experiments (field on)")
            for r in rows:
                ax.scatter([r["G"]], [1.2e-2], marker="x", color=colours[key],
                           zorder=5)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_ylim(1e-2, 2e3)
    ax.set_xlabel("G (gravity)")
    ax.set_ylabel("A (anisotropy)")
    ax.set_title("upright rod stable above each curve (x: field off, A = 0)")
    ax.legend(fontsize=7, loc="upper left")
    ax2.axhline(0.0, color="0.5", lw=0.8)
    ax2.set_xscale("log")
    ax2.set_yscale("symlog", linthresh=1e-2)
    ax2.set_xlabel("G")
    ax2.set_ylabel("A2  (A = A_crit + A2 r^2)")
    ax2.set_title("pitchfork coefficient: < 0 supercritical, > 0 subcritical")
    ax2.legend()
    fig.tight_layout()
    return fig


def _groups_title(scene) -> str:
    """'G = 2.2, M = 0.0236, D = 1.2229' for a magnet scene (empty without one)."""
    if scene is None:
        return ""
    return f"G = {float(scene.G):.4g}, M = {float(scene.M):.4g}, D = {float(scene.D):.5g}"


def _fold_points(report, y: str) -> list[tuple[float, float]]:
    """(alpha in degrees, tip in degrees or q) of every refined fold and its mirror image."""
    points = []
    for f in report.folds:
        v = f.tip_deg if y == "tip" else f.q
        points += [(f.alpha_deg, v), (-f.alpha_deg, -v)]
    return points


def _branch_segments(report, y: str):
    """The diagram cut where its stability changes, each piece closed by the refined fold
    between them (so that both pieces end exactly at the Moore-Spence fold, with no gap)."""
    b = report.branch
    a = np.degrees(b.alpha)
    v = np.degrees(b.tip) if y == "tip" else np.asarray(b.q)
    stable = np.asarray(b.stable)
    folds = _fold_points(report, y)
    scale = np.array([max(np.ptp(a), 1e-12), max(np.ptp(v), 1e-12)])
    cuts = np.nonzero(stable[1:] != stable[:-1])[0]
    segments, start, joint = [], 0, None
    for i in cuts:
        mid = np.array([(a[i] + a[i + 1]) / 2, (v[i] + v[i + 1]) / 2])
        near = min(folds, key=lambda p: np.linalg.norm((np.array(p) - mid) / scale),
                   default=None)
        end = tuple(mid) if near is None or np.linalg.norm(
            (np.array(near) - mid) / scale) > 0.05 else near
        xs, ys = list(a[start:i + 1]), list(v[start:i + 1])
        if joint is not None:
            xs, ys = [joint[0]] + xs, [joint[1]] + ys
        segments.append((np.array(xs + [end[0]]), np.array(ys + [end[1]]), bool(stable[i])))
        start, joint = i + 1, end
    xs, ys = list(a[start:]), list(v[start:])
    if joint is not None:
        xs, ys = [joint[0]] + xs, [joint[1]] + ys
    segments.append((np.array(xs), np.array(ys), bool(stable[-1])))
    return segments


def diagram_figure(report):
    """Tip angle and q against alpha for a ``FoldReport``: stable solid, unstable dashed,
    the Moore-Spence folds circled (both signs of alpha), G, M, D in the title.

    For smooth curves trace the diagram with ``jaxrod.magnet.diagram.figure_options``
    (as ``jaxrod branch`` does); each piece ends exactly at its refined fold.
    """
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(12, 4.6))
    for ax, y in ((ax1, "tip"), (ax2, "q")):
        for xs, ys, stable in _branch_segments(report, y):
            ax.plot(xs, ys, "-" if stable else "--", color="C0" if stable else "C3", lw=1.6)
        points = np.array(_fold_points(report, y)).reshape(-1, 2)
        ax.plot(points[:, 0], points[:, 1], "o", mfc="none", mec="k", ms=9, ls="none")
        ax.set_xlabel("magnet angle alpha (deg)")
        ax.set_ylabel("tip angle (deg)" if y == "tip" else "q = int theta")
        ax.set_xlim(-90, 90)
        ax.grid(alpha=0.3)
    handles = [ax1.plot([], [], "-", color="C0", label="stable")[0],
               ax1.plot([], [], "--", color="C3", label="unstable")[0]]
    if report.folds:
        handles.append(ax1.plot([], [], "o", mfc="none", mec="k", ms=9, ls="none",
                                label="fold (Moore-Spence)")[0])
    ax1.legend(handles=handles, fontsize=8, loc="upper left")
    title = "planar equilibria of the rod under the magnet"
    width = report.hysteresis_width_deg
    details = [t for t in (_groups_title(report.scene), f"N = {report.n}",
                           f"hysteresis width {width:.4f} deg" if width is not None
                           else "no pair of folds") if t]
    fig.suptitle(f"{title}: " + ", ".join(details), fontsize=11)
    fig.tight_layout()
    return fig


def hysteresis_figure(sweep: dict, report=None, scene=None):
    """Tip angle against magnet angle for both sweep directions (the experiment's protocol),
    snaps as dotted jumps, folds starred, G, M, D in the title.

    Where there is no hysteresis both directions follow one curve: the counter-clockwise
    sweep is then drawn dashed on top of the clockwise one, and the title says so.
    """
    scene = scene if scene is not None else getattr(report, "scene", None)
    fig, ax = plt.subplots(figsize=(7.5, 5))
    styles = {"cw": dict(color="C1", lw=3.0, ls="-", alpha=0.8, zorder=2),
              "ccw": dict(color="C0", lw=1.4, ls="--", zorder=3)}
    labels = {"cw": "clockwise sweep (alpha increasing)",
              "ccw": "counter-clockwise sweep (alpha decreasing)"}
    snapped = np.asarray(sweep["snapped"], bool)
    for direction in ("cw", "ccw"):
        sel = np.asarray(sweep["direction"]) == direction
        if not sel.any():
            continue
        a, t, jump = sweep["alpha_deg"][sel], sweep["tip_deg"][sel], snapped[sel]
        # break the line at each snap: the jump itself is drawn dotted
        breaks = np.nonzero(jump)[0]
        pieces = np.split(np.arange(a.size), breaks)
        for k, piece in enumerate(pieces):
            ax.plot(a[piece], t[piece], **styles[direction],
                    label=labels[direction] if k == 0 else None)
        for i in breaks:
            if i > 0:
                ax.plot([a[i - 1], a[i]], [t[i - 1], t[i]], ":", color="0.3", lw=1.2,
                        zorder=1)
    if breaks_drawn := snapped.any():
        ax.plot([], [], ":", color="0.3", lw=1.2, label="snap (energy descent)")
    if report is not None and report.folds:
        for f in report.folds:
            for sign in (1, -1):
                ax.plot(sign * f.alpha_deg, sign * f.tip_deg, "k*", ms=11, zorder=4)
        ax.plot([], [], "k*", ms=11, ls="none", label="fold (Moore-Spence)")
    ax.set_xlabel("magnet angle alpha (deg)")
    ax.set_ylabel("tip angle (deg)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="upper left")
    width = None if report is None else report.hysteresis_width_deg
    state = (f"hysteresis width {width:.4f} deg" if width is not None and breaks_drawn
             else "no hysteresis: both directions on one curve")
    ax.set_title(", ".join(t for t in ("hysteresis sweep", _groups_title(scene), state) if t),
                 fontsize=10)
    fig.tight_layout()
    return fig


CONDITIONING_LABELS = {
    "full": "full Newton (Hessian)",
    "bordered": "pseudo-arclength (bordered)",
    "moore_spence": "Moore-Spence",
    "w_problem": "mean-zero correction w",
    "reduced": "reduced 2x2 (F = dF/dq = 0)",
}


def conditioning_figure(studies: dict):
    """Condition numbers against distance to the fold, one panel per fold.

    ``studies``: {title: output of ``conditioning_near_fold``}.
    """
    cols = min(2, len(studies))
    rows = -(-len(studies) // cols)
    fig, axes = plt.subplots(rows, cols, figsize=(6.2 * cols, 4.6 * rows), squeeze=False)
    for ax, (title, c) in zip(axes.flat, studies.items()):
        for key, label in CONDITIONING_LABELS.items():
            ax.loglog(c["distance_deg"], c[key], "o-", ms=3, label=label)
        ax.set_xlabel("|alpha - alpha*| (deg)")
        ax.set_ylabel("2-norm condition number")
        ax.set_title(title)
        ax.grid(alpha=0.3, which="both")
    axes[0][0].legend(fontsize=8)
    fig.tight_layout()
    return fig


def bistable_band(curves, points: int = 400):
    """(x, lower, upper, bistable) on a common grid of the varied input: both fold curves of
    ``fold_curves`` interpolated where both exist, and where the rod is bistable in the
    magnet's sweep (both folds in (0, 90] degrees, lower below upper)."""
    lo, up = ({c.name: c for c in curves}[name] for name in ("lower", "upper"))
    start = max(lo.along_values.min(), up.along_values.min())
    stop = min(lo.along_values.max(), up.along_values.max())
    if not start < stop:
        x = np.zeros(0)
        return x, x, x, np.zeros(0, bool)
    x = np.linspace(start, stop, points)
    order = lambda c: np.argsort(c.along_values)
    on = lambda c: np.interp(x, c.along_values[order(c)], c.values[order(c)])
    a_lo, a_up = on(lo), on(up)
    bistable = (a_lo > 0.0) & (a_up <= 90.0) & (a_up > a_lo)
    return x, a_lo, a_up, bistable


def fold_curve_figure(curves, point=None):
    """Magnet angle of both folds against the varied input (``fold_curves``): shaded where
    the rod is bistable in the magnet's sweep (both folds in (0, 90] degrees), the points where
    a fold leaves (0, 90] marked and named, alpha = 90 degrees dotted, and the cusp, called
    the end of the bistability only where it is (both curves meet there, within 90 degrees);
    the design point they start from (``point``) in the title."""
    fig, ax = plt.subplots(figsize=(7.5, 5))
    by_name = {c.name: c for c in curves}
    vary = curves[0].along
    for name, colour in (("lower", "C0"), ("upper", "C3")):
        c = by_name[name]
        label = {"lower": "lower fold (capture)", "upper": "upper fold (release)"}[name]
        ax.plot(c.along_values, c.values, "-", color=colour, lw=2, label=label)
    x, a_lo, a_up, bistable = bistable_band(curves)
    if bistable.any():
        ax.fill_between(x, a_lo, a_up, where=bistable, color="0.85", zorder=0,
                        label="bistable: both folds in (0, 90] deg")
    cusps = [p for c in curves for p in c.cusps]
    if cusps:
        c = cusps[0]
        ends = all(k.reaches_cusp for k in curves) and 0.0 < c.value <= 90.0
        label = (f"cusp: bistability ends at {vary} = {c.along_value:.8g}" if ends else
                 f"cusp of a fold curve at {c.value:.4g} deg ({vary} = "
                 f"{c.along_value:.6g}): " + ("beyond 90 deg, outside the sweep" if c.value > 90
                                              else "not where both folds meet"))
        ax.plot(c.along_value, c.value, "k*" if ends else "k1", ms=13, label=label)
    for e in (p for c in curves for p in c.special_points if p.kind.startswith("alpha")):
        ax.plot(e.along_value, e.value, "kx", ms=9,
                label=f"{e.curve} fold reaches {e.kind[len('alpha = '):]} at "
                      f"{vary} = {e.along_value:.6g}")
    if max(np.max(c.values) for c in curves) > 80.0:
        ax.axhline(90.0, color="0.5", lw=0.8, ls=":")
    from jaxrod.params import UNITS

    unit = UNITS[vary]
    ax.set_xlabel(vary + (f" ({unit})" if unit else ""))
    ax.set_ylabel("magnet angle at the fold, alpha* (deg)")
    if point is not None:
        G, M, D = point.groups()
        ax.set_title(f"folds from G = {G:.4g}, M = {M:.4g}, D = {D:.6g}", fontsize=10)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    return fig


def design_map_figure(data: dict, spec, cusps=(), crossings=()):
    """Hysteresis width over the map's two inputs (a cell per grid point), capture and release
    angles as contour lines, the points that are not bistable in grey, those not computed or
    not converged hatched, the cusp curve (where the bistability ends), the grid points
    where a fold lies beyond 90 degrees and, from the fold curves, where the upper fold
    reaches 90 degrees (``crossings``); the axes span the grid exactly; the fixed inputs in
    the title."""
    from matplotlib.patches import Patch

    from jaxrod.params import UNITS

    fig, ax = plt.subplots(figsize=(8, 5.6))
    X, Y = np.meshgrid(data["x"], data["y"])
    from jaxrod.magnet.batch import (
        BISTABLE,
        FOLD_BEYOND_90,
        INVALID_INPUT,
        NOT_BISTABLE,
        NOT_CONVERGED,
    )

    status = data["status"]
    width = np.where(status == BISTABLE, data["width_deg"], np.nan)
    handles = []
    if np.isfinite(width).any():
        # one cell per grid point (no interpolation between points of different kinds)
        from matplotlib.colors import BoundaryNorm
        from matplotlib.ticker import MaxNLocator

        levels = MaxNLocator(12).tick_values(np.nanmin(width), np.nanmax(width))
        filled = ax.pcolormesh(X, Y, width, shading="nearest", cmap="viridis",
                               norm=BoundaryNorm(levels, 256))
        fig.colorbar(filled, ax=ax, label="hysteresis width (deg)")
        for name, colour in (("capture_deg", "w"), ("release_deg", "0.2")):
            field = np.where(status == BISTABLE, data[name], np.nan)
            if np.isfinite(field).sum() >= 4:
                lines = ax.contour(X, Y, field, levels=6, colors=colour, linewidths=0.7)
                ax.clabel(lines, fontsize=6, fmt="%.0f")
    # every point is drawn as what it is: cells of the grid (pcolormesh) for the non-bistable
    # and the unknown, so that none of them looks like another
    for mask, style, label in (
            (status == NOT_BISTABLE, {"color": "0.8"}, "not bistable"),
            (status == FOLD_BEYOND_90, {"color": "#f2b8b5"},
             "a fold beyond 90 deg (outside the sweep)"),
            (status == INVALID_INPUT, {"color": "0.55"},
             "invalid input (the magnet would touch the rod)"),
            ((status == -1) | (status == NOT_CONVERGED), {"color": "none", "hatch": "xx",
                                                          "ec": "0.4"},
             "not computed, or no solver converged")):
        if mask.any():
            ax.pcolormesh(X, Y, np.where(mask, 1.0, np.nan), shading="nearest",
                          cmap=_single(style.get("color", "none")), zorder=1)
            if "hatch" in style:
                ax.contourf(X, Y, mask.astype(float), levels=[0.5, 1.5], colors="none",
                            hatches=["xx"], zorder=2)
            handles.append(Patch(facecolor=style["color"], hatch=style.get("hatch"),
                                 edgecolor=style.get("ec", "0.8"), label=label))
    if cusps:
        ax.plot([c[spec.x.name] for c in cusps], [c[spec.y.name] for c in cusps], "k*-",
                ms=8, label="cusp (bistability ends)")
    if crossings:
        ax.plot([c[spec.x.name] for c in crossings], [c[spec.y.name] for c in crossings],
                "r^", ms=6, mec="k", label="fold curves: upper fold reaches 90 deg")
    ax.set_xlim(data["x"].min(), data["x"].max())
    ax.set_ylim(data["y"].min(), data["y"].max())
    unit = lambda n: f" ({UNITS[n]})" if UNITS[n] else ""
    ax.set_xlabel(spec.x.name + unit(spec.x.name))
    ax.set_ylabel(spec.y.name + unit(spec.y.name))
    fixed = ", ".join(f"{name} = {value:.4g}" for name, value in zip(
        spec.point.names, spec.point.values, strict=True)
        if name not in (spec.x.name, spec.y.name))
    ax.set_title("bistable region: width filled; capture (white) and release (dark) angles\n"
                 + "\n".join(textwrap.wrap(f"{fixed}, N = {spec.n}", 95)), fontsize=9)
    lines, labels = ax.get_legend_handles_labels()
    if lines or handles:
        ax.legend(handles=lines + handles, fontsize=8, loc="upper right")
    fig.tight_layout()
    return fig


def _single(colour: str):
    """A colour map of one colour (``colour``, or transparent for "none")."""
    from matplotlib.colors import ListedColormap

    return ListedColormap([(0, 0, 0, 0) if colour == "none" else colour])


def profile_figure(profiles: list, calibration=None):
    """Profile likelihoods (chi^2 minimised over the other free inputs) of each fitted
    input, with the Laplace (quadratic) approximation and the 68% level (chi^2_min + 1)."""
    fig, axes = plt.subplots(1, len(profiles), figsize=(4.2 * len(profiles), 3.6),
                             squeeze=False)
    for ax, prof in zip(axes[0], profiles):
        scale, unit = (1e9, "GPa") if prof["name"] == "E" else (1.0, "")
        x = np.asarray(prof["values"]) / scale
        ax.plot(x, prof["chi2"], "o-", ms=3, label="profile")
        if prof["laplace_chi2"] is not None:
            ax.plot(x, prof["laplace_chi2"], "--", label="Laplace")
        ax.axhline(prof["chi2_min"] + 1.0, color="0.5", lw=0.8, label=r"$\chi^2_{min}+1$")
        ax.axvline(prof["estimate"] / scale, color="0.7", lw=0.8)
        if not unit:
            from jaxrod.params import UNITS

            unit = "deg" if prof["name"] == "offset" else UNITS.get(prof["name"], "")
        ax.set_xlabel(f"{prof['name']}" + (f" ({unit})" if unit else ""))
        ax.set_ylabel(r"$\chi^2$")
    axes[0][0].legend(fontsize=8)
    fig.tight_layout()
    return fig
