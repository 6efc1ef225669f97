"""The look of every figure dlasweep draws for a report (and the benchmark's chart): panels, colours, PNG.

matplotlib is imported inside these helpers, so that ``import dlasweep`` (and a dask worker) skips it.
"""

from __future__ import annotations

import numpy as np

MAX_PANELS = 12
"""Most panels a figure draws (and items the write-up lists): the first ones, the rest said in words."""
_MIN_WIDTH = 6.5
"""Inches: the narrowest figure, whatever its panels."""


def new_figure(n_panels=1, width=4.0, height=3.4, sharey=False):
    """A grid of panels on a Figure of its own (no pyplot state, no backend switch); ``sharey``: one y-axis."""
    from matplotlib.figure import Figure  # here, so `import dlasweep` (and dask workers) skip matplotlib

    cols = min(n_panels, 4)
    rows = -(-n_panels // cols)
    # A one-panel figure still needs room for its title and a legend below it.
    fig = Figure(figsize=(max(width * cols, _MIN_WIDTH), height * rows), layout="constrained")
    axes = fig.subplots(rows, cols, squeeze=False, sharey=sharey).ravel()
    for ax in axes[n_panels:]:
        ax.set_visible(False)
    return fig, axes[:n_panels]


def save_figure(fig, path):
    """Write a figure of the report (or the benchmark's) as a PNG."""
    fig.savefig(path, dpi=110)


def colour_of(i):
    """The i-th colour of the report's plots (tab10, cycling)."""
    from matplotlib import colormaps

    return colormaps["tab10"](i % 10)


def mark_missing(ax, xs, ys):
    """A red cross on the bottom edge for every x whose y is missing: nothing silently vanishes."""
    xs, lost = np.asarray(xs, float), ~np.isfinite(np.asarray(ys, float))
    if lost.any():
        ax.scatter(xs[lost], np.full(lost.sum(), 0.03), transform=ax.get_xaxis_transform(),
                   marker="x", color="C3", s=40, zorder=3)
        ax.dataLim.update_from_data_x(xs[lost], ignore=False)
        ax.autoscale_view()


def log_x(ax):
    ax.set_xscale("log")
    # A narrow log range otherwise labels its minor ticks on top of each other.
    ax.tick_params(axis="x", which="minor", labelbottom=False)

