"""Pictures of one cluster, coloured by attachment order.

What a picture shows:

* A lattice cluster is an image with a pixel per site, drawn nearest
  neighbour: where a site covers a pixel or more it is exact (squares drawn
  as scatter markers leave white seams at sub-pixel sizes). A panel with
  fewer pixels than sites shows blocks of sites, a pixel coloured when any
  site in it is occupied.
* An off-lattice cluster is disks (spheres) at their true size; where a
  disk is smaller than a pixel, it is drawn as sites are, a pixel per block.
* A 3D cluster is drawn as an engineering drawing: the top view (x-y) above
  the side view (x-z), the other side view (y-z) beside it, at one scale.
  Each shows depth: nearer particles hide farther ones, which fade towards
  white.
* The box is drawn (its absorbing walls), or the substrate (grey, seen from
  the side) with its periodic sides dashed and, where walkers are removed
  above it, the ceiling dotted.
* The title names the model, N, the seed and every parameter that differs
  from its default.

The sweep report's gallery draws its panels with ``draw_points``; ``dlasweep
grow -o FILE.png|.svg`` draws with ``draw_cluster``.
"""

from __future__ import annotations

import math
import textwrap
from pathlib import Path

import numpy as np

from .. import params as _params

DEFAULT_INCHES = 6.0
"""Side of ``draw_cluster``'s square picture unless asked otherwise."""

INCHES = (2.0, 40.0)
"""Sides a picture may have: below 2 inches the title has no room."""

PIXELS = (200, 16000)
"""Picture sides in pixels that ``dpi`` may give (Agg draws up to 2**16)."""

PANEL_PIXELS = 1000
"""Default resolution: a panel is at least this many pixels wide ..."""

MAX_PIXELS = 4000
"""... and the picture at most this many (then a pixel shows a block of sites)."""

_FONT_PER_INCH = 1.5
"""Title size in points per inch of picture, so the text keeps its share at any size."""

_GAP = 0.08
"""Inches between the panels and around them."""

_FOG = 0.75
"""How far the farthest particle of a 3D view fades towards white."""

_LABEL = 0.8
"""A 3D panel's label size over the title's."""

_LEGEND = ("colour: attachment order", "(purple first, yellow last)")

_VIEWS = ((0, 1), (0, 2), (1, 2))
"""A 3D cluster's panels: top view x-y, side views x-z and y-z."""


def check_size(inches, dpi=None):
    """Refuse a picture size that cannot be drawn.

    Parameters
    ----------
    inches : float
        Side of the square picture.
    dpi : float or None
        Dots per inch; None chooses them from the cluster (see ``cluster_figure``).

    Raises
    ------
    ValueError
        Starting with ``inches:`` or ``dpi:``, the value at fault.
    """
    if not INCHES[0] <= inches <= INCHES[1]:
        raise ValueError(f"inches: {inches:g} is not in [{INCHES[0]:g}, {INCHES[1]:g}]")
    if dpi is not None and not PIXELS[0] <= inches * dpi <= PIXELS[1]:
        raise ValueError(f"dpi: {dpi:g} makes a {inches:g}-inch picture {inches * dpi:.0f} pixels wide, "
                         f"not in [{PIXELS[0]}, {PIXELS[1]}]")


def draw_points(ax, points, lattice, inches, rasterized=True, *, view=(0, 1), params=None, frame=None):
    """Draw particles at their true size, coloured by attachment order, on one panel.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        The panel; its axes are turned off and its limits set.
    points : ndarray, (n, dim)
        Positions in attachment order.
    lattice : bool
        Sites (an image, a pixel per site) or unit-diameter disks.
    inches : float
        The panel's width: it sizes the disks, and with the figure's dpi
        the lattice image.
    rasterized : bool
        Off-lattice: disks as pixels (False: every disk a vector shape).
    view : (int, int)
        The coordinates across and up; in 3D the third is depth, seen from
        the side the right-handed axes face.
    params : dict, optional
        Model parameters; given, the box or substrate is drawn too.
    frame : ndarray, (dim, 2), optional
        Limits of every coordinate, equal spans (from ``_square``), so that
        the panels of one figure share a scale; by default the cluster's.
    """
    points = np.asarray(points) if lattice else np.asarray(points, float)  # 10^8 sites: no float copy
    n, dim = points.shape
    if frame is None:
        frame = _square(_frame(points, lattice, dim, params), lattice)
    h, v = view
    ax.set_xlim(*frame[h])
    ax.set_ylim(*frame[v])
    ax.set_aspect("equal")
    ax.set_axis_off()
    span = frame[h, 1] - frame[h, 0]
    pixels = round(inches * ax.figure.dpi)
    if n and (lattice or span > pixels):  # disks below a pixel: blocks, as sites (10^8 disks: no scatter)
        _site_image(ax, points, view, frame[[h, v], 0], span, pixels)
    elif n:
        keys = (np.arange(n),)  # the last attached drawn last ...
        near = None
        if dim == 3:
            depth, towards = _depth(view)
            near = towards * points[:, depth]
            near = (near - near.min()) / max(np.ptp(near), 1.0)  # 0 farthest, 1 nearest
            keys = (keys[0], near)  # ... and in 3D the nearest
        shown = np.lexsort(keys)
        xy, colours = points[shown][:, [h, v]], _colours(shown, n, None if near is None else near[shown])
        area = max((72 * inches / span) ** 2, 0.05)  # a unit diameter, in points squared
        areas = [area]
        if dim == 3:
            # A sphere: a darker body under a lighter cap towards a light at the upper left, each
            # particle's pair in one collection so that nearer spheres still cover farther ones.
            xy = np.stack([xy, xy + [-0.12, 0.12]], axis=1).reshape(-1, 2)
            cap = colours + (1.0 - colours) * 0.4
            colours[:, :3] *= 0.8
            colours = np.stack([colours, cap], axis=1).reshape(-1, 4)
            areas = [area, 0.4 * area]
        disks = ax.scatter(xy[:, 0], xy[:, 1], c=colours, marker="o", linewidths=0, rasterized=rasterized)
        disks.set_sizes(areas)  # cycled over the particles (or pairs): SVG defines each shape once
    if params is not None and params["size"] > 0:
        _draw_walls(ax, _walls(lattice, dim, params), view, frame, params["seed_shape"] == "line")


def _depth(view):
    """The coordinate a 3D view looks along, and +1 when a larger one is nearer the viewer (-1 else)."""
    h, v = view
    (depth,) = set(range(3)) - {h, v}
    return depth, int(np.cross(np.eye(3)[h], np.eye(3)[v])[depth])


def _colours(index, n, near):
    """RGBA of particles ``index`` of ``n``: viridis by attachment order, faded towards white as ``near``
    (theirs, 0 farthest to 1 nearest) falls."""
    from matplotlib import colormaps

    rgba = colormaps["viridis"](index / max(n - 1, 1))
    if near is not None:
        rgba[:, :3] += (1.0 - rgba[:, :3]) * (_FOG * (1.0 - near))[:, None]
    return rgba


SITE_CHUNK = 1 << 22
"""Sites placed in the image at a time: memory of a few chunks, not of 10^8 sites' float copies and sort."""


def _site_image(ax, sites, view, low, span, pixels):
    """Occupied sites (or disks' centres) as an image of at most ``pixels`` across, a pixel per block.

    ``low`` are the frame's lower edges (half-integers for sites). Of the
    sites sharing a pixel the nearest shows (3D), and of those the last
    attached.
    """
    n, dim = sites.shape
    h, v = view
    block = max(1, math.ceil(span / pixels))
    cells = math.ceil(span / block)
    far, reach = 0, 1
    if dim == 3:
        depth, towards = _depth(view)
        ends = towards * np.array([sites[:, depth].min(), sites[:, depth].max()], np.int64)
        far, reach = int(ends.min()), max(int(np.ptp(ends)), 1)
    shows = np.full(cells * cells, -1, np.int64)  # each pixel's largest rank: nearness, then attachment order
    for start in range(0, n, SITE_CHUNK):
        chunk = sites[start:start + SITE_CHUNK]
        flat = (((chunk[:, v] - low[1]) // block).astype(np.int64) * cells
                + ((chunk[:, h] - low[0]) // block).astype(np.int64))
        rank = np.arange(start, start + len(chunk), dtype=np.int64)
        if dim == 3:
            rank += (towards * chunk[:, depth].astype(np.int64) - far) * n
        np.maximum.at(shows, flat, rank)
    pixel = np.flatnonzero(shows >= 0)
    top = shows[pixel] % n
    near = (towards * sites[top, depth] - far) / reach if dim == 3 else None
    rgba = np.zeros((cells * cells, 4), np.uint8)  # transparent where no site is occupied
    rgba[pixel] = np.round(_colours(top, n, near) * 255)
    reach = cells * block
    ax.imshow(rgba.reshape(cells, cells, 4), origin="lower", interpolation="nearest",
              extent=(low[0], low[0] + reach, low[1], low[1] + reach))


def _walls(lattice, dim, params):
    """Where walkers are confined: (low, high) per coordinate, nan where open.

    A box: its absorbing walls on every side. A substrate: its periodic
    sides across, its surface below (particle centres stand half a spacing
    above it) and the ceiling where walkers are removed (box launch, or
    several walkers), else open.
    """
    size = params["size"]
    if params["seed_shape"] != "line":
        low = -(size // 2) - 0.5 if lattice else -size / 2  # sites -(size//2).. ; walls at +-size/2 off-lattice
        return np.tile([low, low + size], (dim, 1))
    across = -0.5 if lattice else 0.0  # sites 0..size-1; coordinates in [0, size) off-lattice
    ceiling = size - 0.5 if lattice else float(size)
    walls = np.tile([across, across + size], (dim, 1))
    walls[-1] = -0.5, ceiling if params["launch"] == "box" or params["walkers"] > 1 else np.nan
    return walls


def _draw_walls(ax, walls, view, frame, line):
    """The box (solid), or the substrate (grey), its periodic sides (dashed) and ceiling (dotted)."""
    from matplotlib.patches import Rectangle

    h, v = view
    up = len(walls) - 1
    (x0, x1), (y0, y1) = walls[h], walls[v]
    style = dict(color="0.25", linewidth=0.8, zorder=3)
    if not line:
        ax.add_patch(Rectangle((x0, y0), x1 - x0, y1 - y0, fill=False, gid="box", **style))
        return
    if v != up:  # the top view: the substrate under the whole periodic cell
        ax.add_patch(Rectangle((x0, y0), x1 - x0, y1 - y0, facecolor="0.9", edgecolor="0.25", linestyle="--",
                               linewidth=0.8, zorder=-1, gid="substrate"))
        return
    ax.add_patch(Rectangle((x0, frame[v, 0]), x1 - x0, y0 - frame[v, 0], facecolor="0.6", linewidth=0, zorder=-1,
                           gid="substrate"))
    ax.vlines([x0, x1], y0, frame[v, 1], linestyles="--", gid="periodic", **style)
    if np.isfinite(y1):
        ax.hlines(y1, x0, x1, linestyles=":", gid="ceiling", **style)


def _frame(points, lattice, dim, params):
    """Limits (dim, 2) holding the particles, a margin, and the box or substrate; site edges on a lattice."""
    low = points.min(axis=0) - 1.5 if len(points) else np.zeros(dim)  # a radius and a spacing of margin
    high = points.max(axis=0) + 1.5 if len(points) else np.zeros(dim)
    if params is not None and params["size"] > 0:
        walls = _walls(lattice, dim, params)
        low, high = np.fmin(low, walls[:, 0] - 1), np.fmax(high, walls[:, 1] + 1)
        if params["seed_shape"] == "line":
            low[-1] = walls[-1, 0] - 1 - 0.04 * (high - low).max()  # a band of substrate in view
    if lattice:
        low, high = np.floor(low - 0.5) + 0.5, np.ceil(high - 0.5) + 0.5
    return np.stack([low, high], axis=1)


def _square(frame, lattice, span=None):
    """``frame`` widened about its centre to the same span on every coordinate (whole sites on a lattice).

    ``span`` (at least the frame's widest) widens it further.
    """
    width = frame[:, 1] - frame[:, 0]
    span = max(width.max(), 1.0) if span is None else span
    # On a lattice the edges stay between sites: the frame grows by whole sites.
    low = frame[:, 0] - (span - width) // 2 if lattice else frame[:, 0] - (span - width) / 2
    return np.stack([low, low + span], axis=1)


def describe(params, n, seed=None, status=_params.Status.ok.name):
    """A cluster in words: model, N, seed, status, and every parameter that differs from its default.

    Returns
    -------
    head : str
        ``lattice DLA in 2D, N = 1000, seed 3``.
    changed : list of str
        ``stickiness=0.3`` and so on, in the order of ``params.PARAMETERS``.
    """
    p = _params.resolve(**params)
    usual = _params.resolve(model=p["model"], dim=p["dim"])  # the defaults, neighbours made explicit for dim
    head = f"{p['model']} DLA in {p['dim']}D, N = {n}" + ("" if seed is None else f", seed {seed}")
    if status != _params.Status.ok.name:
        head += f", stopped: {status}"
    changed = [f"{name}={_params.text(p[name])}"
               for name in _params.PARAMETERS if p[name] != usual[name]]
    return head, changed


def cluster_figure(points, params, *, seed=None, status=_params.Status.ok.name, inches=DEFAULT_INCHES, dpi=None,
                   rasterized=True):
    """One cluster's picture: a square figure with its title.

    Parameters
    ----------
    points : ndarray, (n, dim)
        Positions in attachment order.
    params : dict
        The cluster's model parameters (missing ones take their defaults).
    seed, status
        Named in the title (``status`` only when it is not ``ok``).
    inches : float
        Side of the figure.
    dpi : float, optional
        Dots per inch. By default a panel gets at least ``PANEL_PIXELS``,
        whole pixels per lattice site, and the picture at most
        ``MAX_PIXELS``.
    rasterized : bool
        Off-lattice: disks as pixels (False: vector shapes, for SVG).

    Returns
    -------
    matplotlib.figure.Figure
        2D: one panel under the title. 3D: the three views, the title in
        the fourth quarter.
    """
    from matplotlib.figure import Figure  # here, so `import dlasweep` (and dask workers) skip matplotlib

    check_size(inches, dpi)
    p = _params.resolve(**params)
    dim, lattice = p["dim"], p["model"] == "lattice"
    points = np.asarray(points) if lattice else np.asarray(points, float)
    head, changed = describe(p, len(points), seed, status)
    font = _FONT_PER_INCH * inches
    if dim == 2:
        text = [head, *textwrap.wrap(", ".join(changed), 80), " ".join(_LEGEND)]
        band = (len(text) + 0.6) * 1.25 * font / 72  # the title's height in inches
        panel = inches - band - 2 * _GAP
    else:
        text = [*head.split(", "), *changed, *_LEGEND, "paler: farther"]  # in the fourth quarter
        band = 1.5 * _LABEL * font / 72  # the height of a panel's label
        panel = (inches - 2 * band - _GAP) / 2
    frame = _square(_frame(points, lattice, dim, p), lattice)
    natural = frame[0, 1] - frame[0, 0]
    if dpi is None:
        per_site = max(1, math.ceil(PANEL_PIXELS / natural))
        dpi = min(MAX_PIXELS, math.ceil((per_site * natural + 4) * inches / panel)) / inches

    # The layout in whole pixels, so that panel edges fall on pixel edges.
    side, gap, band = int(inches * dpi), math.ceil(_GAP * dpi), math.ceil(band * dpi)
    across = side - band - 2 * gap if dim == 2 else (side - 2 * band - gap) // 2
    if lattice:
        # Whole pixels per site, or whole sites per pixel: the frame widens to fill the panel.
        natural = int(natural)
        if across >= natural:
            span = across // (across // natural)
            across = span * (across // natural)
        else:
            span = math.ceil(natural / across) * across
        frame = _square(frame, lattice, span)
    fig = Figure(figsize=(_inches(side, dpi),) * 2, dpi=dpi)
    if dim == 2:
        places = [((side - across) // 2, gap)]
    else:  # the top view above the side view x-z, the side view y-z beside it, labels above each
        left, right = (side - 2 * across - gap) // 2, (side + gap) // 2
        places = [(left, gap + across + band), (left, gap), (right, gap)]
    for (x, y), view in zip(places, _VIEWS):
        ax = fig.add_axes((x / side, y / side, across / side, across / side))
        draw_points(ax, points, lattice, across / dpi, rasterized, view=view, params=p, frame=frame)
        if dim == 3:
            names = "-".join("xyz"[a] for a in view)
            ax.text(0.0, 1.0, f" {'top' if view == (0, 1) else 'side'} view {names}", transform=ax.transAxes,
                    va="bottom", fontsize=_LABEL * font, color="0.3")
    x = 0.5 if dim == 2 else right / side
    fig.text(x, 1 - gap / side, "\n".join(text), ha="center" if dim == 2 else "left", va="top", fontsize=font,
             linespacing=1.25)
    return fig


def _inches(pixels, dpi):
    """Inches that make exactly ``pixels`` at ``dpi`` (Agg truncates the canvas to whole pixels)."""
    inches = pixels / dpi
    return inches if inches * dpi >= pixels else np.nextafter(inches, np.inf)


def draw_cluster(points, params, path, *, seed=None, status=_params.Status.ok.name, inches=DEFAULT_INCHES,
                 dpi=None) -> Path:
    """Draw one cluster to a PNG or SVG file (``cluster_figure`` says what it shows).

    Parameters
    ----------
    points, params
        As for ``cluster_figure``.
    path : str or Path
        ``.png``, or ``.svg`` (disks as vector shapes, a lattice as its image).
    seed, status, inches, dpi
        As for ``cluster_figure``.
    """
    path = Path(path)
    fig = cluster_figure(points, params, seed=seed, status=status, inches=inches, dpi=dpi,
                         rasterized=path.suffix.lower() != ".svg")
    fig.savefig(path, dpi=fig.dpi)
    return path
