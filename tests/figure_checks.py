"""Checks shared by the tests that render figures."""

from __future__ import annotations

import matplotlib.colors as mcolors
import matplotlib.pyplot as plt
import numpy as np
from matplotlib.collections import Collection
from matplotlib.lines import Line2D
from matplotlib.patches import Patch


def _style(artist: Line2D) -> tuple:
    marker = artist.get_marker()
    colour = (artist.get_markeredgecolor() if marker not in ("None", "", None)
              and artist.get_linestyle() in ("None", "") else artist.get_color())
    return mcolors.to_rgba(colour), artist.get_linestyle(), marker


def _drawn(fig) -> tuple[list, list]:
    lines, filled = [], []
    for ax in fig.axes:
        lines += [ln for ln in ax.lines if len(ln.get_xdata()) > 0]
        filled += [p for p in ax.patches if isinstance(p, Patch)]
        filled += [c for c in ax.collections if isinstance(c, Collection)
                   and len(c.get_paths()) > 0]
    return lines, filled


def absent_legend_entries(fig) -> list[str]:
    """Legend labels with no drawn artist of the same style (colour, line style, marker)."""
    lines, filled = _drawn(fig)
    absent = []
    for ax in fig.axes:
        legend = ax.get_legend()
        if legend is None:
            continue
        for handle, text in zip(legend.legend_handles, legend.get_texts(), strict=True):
            label = text.get_text()
            if isinstance(handle, Line2D):
                ok = any(_style(ln) == _style(handle) for ln in lines)
            elif isinstance(handle, Patch | Collection):
                face = mcolors.to_rgba(handle.get_facecolor() if isinstance(handle, Patch)
                                       else handle.get_facecolor()[0])
                # a collection's faces: each of its colours (a colour-mapped mesh has one
                # per cell)
                faces = [np.atleast_2d(mcolors.to_rgba_array(f.get_facecolor()))
                         for f in filled]
                ok = any(np.allclose(row, face) for rows in faces for row in rows)
            else:
                ok = True
            if not ok:
                absent.append(label)
    return absent


def figure_title(fig) -> str:
    parts = [fig._suptitle.get_text()] if fig._suptitle is not None else []
    return " ".join(parts + [ax.get_title() for ax in fig.axes])


def check_figure(fig, tmp_path, name, title_has=()):
    """Render to PNG, then: no legend entry without a drawn artist, the title has each text."""
    path = tmp_path / f"{name}.png"
    fig.savefig(path, dpi=60)
    assert path.stat().st_size > 5000
    assert absent_legend_entries(fig) == []
    title = figure_title(fig)
    for text in title_has:
        assert text in title, f"{name}: {text!r} not in the title {title!r}"
    plt.close(fig)
