"""The picture of a cluster as a tree: each Horton-Strahler branch a line, wider and darker the higher its
order (``export.branch_polylines``), as PNG (or SVG through matplotlib)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..data.export import MARGIN, STROKE, branch_polylines
from .pictures import DEFAULT_INCHES, describe

DPI = 150
"""Dots per inch of a tree picture when none is asked."""


def tree_figure(cluster, *, seed=None, inches=DEFAULT_INCHES, dpi=None):
    """A matplotlib Figure of the cluster's branches, line width ``STROKE`` x order in particle diameters
    (at least a hair), coloured by order."""
    from matplotlib import colormaps
    from matplotlib.collections import LineCollection
    from matplotlib.figure import Figure

    points = cluster.points[:, :2].astype(np.float64)
    lo, hi = points.min(axis=0) - MARGIN, points.max(axis=0) + MARGIN
    span = float((hi - lo).max())
    fig = Figure(figsize=(inches, inches), dpi=dpi or DPI)
    ax = fig.add_axes((0.02, 0.06, 0.96, 0.86))
    centre = (lo + hi) / 2
    ax.set_xlim(centre[0] - span / 2, centre[0] + span / 2)
    ax.set_ylim(centre[1] - span / 2, centre[1] + span / 2)
    ax.set_aspect("equal")
    ax.set_axis_off()
    points_per_unit = 0.86 * inches * 72 / span
    by_order = {}
    for k, path in branch_polylines(cluster):
        by_order.setdefault(k, []).append(path)
    top = max(by_order, default=1)
    cmap = colormaps["viridis_r"]
    for k in sorted(by_order):
        ax.add_collection(LineCollection(by_order[k], linewidths=max(STROKE * k * points_per_unit, 0.15),
                                         colors=[cmap(0.15 + 0.85 * (k - 1) / max(top - 1, 1))],
                                         capstyle="round", joinstyle="round", label=f"order {k}"))
    fig.legend(loc="lower center", ncols=min(top, 8), fontsize=6, frameon=False, handlelength=1.5)
    head, changed = describe(cluster.params, len(points), seed, cluster.status)
    fig.suptitle(f"{head}{', ' if changed else ''}{', '.join(changed)}\n"
                 f"Horton-Strahler branches: width and colour by order (1 to {top})", fontsize=7)
    return fig


def draw_tree(cluster, path, *, seed=None, inches=DEFAULT_INCHES, dpi=None) -> Path:
    """Draw the cluster's tree (``tree_figure``) to a PNG or SVG file."""
    path = Path(path)
    fig = tree_figure(cluster, seed=seed, inches=inches, dpi=dpi)
    fig.savefig(path, dpi=fig.dpi)
    return path
