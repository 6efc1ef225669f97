"""Pictures of one cluster: the particles at their true size, coloured by attachment order.

The sweep report's gallery draws its panels with ``draw_points``; ``dlasweep
grow -o FILE.png|.svg`` draws with ``draw_cluster``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np


def draw_points(ax, points, lattice, inches, rasterized=True):
    """Particles at their true size (an ``inches``-wide panel), coloured by attachment order."""
    low, high = points[:, :2].min(axis=0) - 1, points[:, :2].max(axis=0) + 1
    extent = max((high - low).max(), 1.0)
    centre = (low + high) / 2
    ax.set_xlim(centre[0] - extent / 2, centre[0] + extent / 2)
    ax.set_ylim(centre[1] - extent / 2, centre[1] + extent / 2)
    ax.set_aspect("equal")
    ax.set_axis_off()
    points_per_unit = 72 * inches / extent
    ax.scatter(points[:, 0], points[:, 1], c=np.arange(len(points)), cmap="viridis",
               s=max(points_per_unit**2, 0.05), marker="s" if lattice else "o", linewidths=0,
               rasterized=rasterized)


def draw_cluster(points, params, path) -> Path:
    """Draw one cluster, coloured by attachment order, to a PNG or SVG file.

    Parameters
    ----------
    points : ndarray, (n, dim)
        Positions in attachment order; a 3D cluster is projected on x-y.
    params : dict
        The cluster's model parameters (``model``, ``dim`` are used).
    path : str or Path
        ``.png`` (particles rasterised) or ``.svg`` (every particle a vector shape).
    """
    path = Path(path)
    from matplotlib.figure import Figure  # here, so `import dlasweep` (and dask workers) skip matplotlib

    fig = Figure(figsize=(6.0, 6.0), layout="constrained")
    ax = fig.subplots()
    draw_points(ax, np.asarray(points, float), params.get("model", "lattice") == "lattice", 5.6,
                 rasterized=path.suffix.lower() != ".svg")
    projected = ", projected on x-y" if params.get("dim", 2) == 3 else ""
    ax.set_title(f"{params.get('model', 'lattice')} DLA, N={len(points)}{projected}", fontsize=9)
    fig.savefig(path, dpi=110)
    return path
