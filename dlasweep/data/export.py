"""A cluster for other programs: a table (.csv), a mesh (.ply, .obj) or the tree as vector paths (.svg).

* ``.csv``: ``id, parent, x, y(, z), diffusion_time``, a row per particle in
  attachment order (as fogleman/dlaf writes), parent -1 for none.
* ``.ply`` (binary) and ``.obj``: a triangle mesh for Blender, ParaView or
  MeshLab: each particle a sphere of unit diameter (``mesh="spheres"``: an
  icosahedron), or each bond a tube from a particle to its parent
  (``mesh="tubes"``: a hexagonal prism). 2D clusters lie in the z = 0 plane.
* ``.svg``: the tree as paths, one polyline per Horton-Strahler branch,
  from its junction to its tip, stroke width by order (``STROKE``), in
  particle diameters (lattice spacings), y up; 3D clusters seen along z.
  For a plotter or a laser cutter. (``pictures.draw_cluster`` draws the
  disks.)

Every writer streams: ``CHUNK`` particles at a time are turned into text or
bytes and written, so a cluster of 10^7 particles takes no second copy of
itself (a mesh takes 12 vertices a particle), and nothing is left at the
path when writing fails (the file is written under a temporary name and
renamed).
"""

from __future__ import annotations

import contextlib
import os
from pathlib import Path

import numpy as np

from .paths import writable

FORMATS = (".csv", ".ply", ".obj", ".svg")
MESHES = ("spheres", "tubes")
PICTURES = (".png", ".svg")
SUFFIXES = (".nc", *PICTURES, *(s for s in FORMATS if s not in PICTURES))
"""Every file a cluster is written to (``write_cluster``): a dataset, a picture, a table or a mesh."""
MESH_FILES = (".ply", ".obj")
STYLES = ("disks", "tree")
"""How a picture shows a cluster: its particles, or its tree (one line per Horton-Strahler branch)."""
CHUNK = 1 << 16
"""Particles turned into text or bytes at a time (a sixteenth of it for meshes: 12 vertices and
20 faces a particle), so that a file's memory beside the cluster stays a few chunks' worth whatever its size
(docs/performance.md, "Data files")."""
RADIUS = 0.5
"""Radius of a particle's sphere: unit diameter, as the model's disks (and lattice sites)."""
TUBE_RADIUS = 0.25
"""Radius of a bond's tube."""
TUBE_SIDES = 6
STROKE = 0.3
"""SVG stroke width of a branch of order k: ``STROKE * k`` particle diameters."""
MARGIN = 2.0
"""Space around the SVG drawing, in particle diameters."""


def export_cluster(source, path, *, cluster=None, mesh="spheres") -> Path:
    """Write a cluster to ``path`` in the format its extension names (module docstring).

    Parameters
    ----------
    source : dlasweep.Cluster or xarray.Dataset
        A grown cluster, or a dataset (``open_sweep``) with ``cluster`` the
        position of the stored cluster to write.
    path : str or Path
        Ending in .csv, .ply, .obj or .svg.
    cluster : int, optional
        With a dataset: which cluster (``ragged.cluster_points``'s index).
    mesh : {"spheres", "tubes"}
        What a .ply or .obj file draws.

    Returns
    -------
    Path

    Raises
    ------
    ValueError
        An unknown extension or mesh, or a cluster without parents where
        the format needs them (tubes, .svg, .csv); IndexError: no such
        cluster; OSError: a path that cannot be written (``paths.writable``).
        Nothing is written then.
    """
    path = Path(path)
    check(path, mesh)
    writable(path)
    if not hasattr(source, "points"):
        from .ragged import read_cluster  # here, so that exporting a grown cluster needs no xarray

        if cluster is None:
            raise TypeError("cluster: give the index of the stored cluster to export")
        source = read_cluster(source, cluster)
    suffix = path.suffix.lower()
    if source.parents is None and (suffix in (".csv", ".svg") or mesh == "tubes"):
        raise ValueError(f"{path}: this cluster has no parents (a file written before they were stored)")
    write = {".csv": _csv, ".ply": _ply, ".obj": _obj, ".svg": _svg}[suffix]
    tmp = path.with_name(f".{path.name}.tmp{os.getpid()}")
    try:
        with open(tmp, "wb") as f:
            write(source, f, mesh)
        os.replace(tmp, path)
    finally:
        with contextlib.suppress(FileNotFoundError):
            tmp.unlink()
    return path


def write_cluster(cluster, path, seed=0, *, style="disks", mesh="spheres", picture=None):
    """Write one cluster to ``path`` as its extension (one of ``SUFFIXES``) says.

    ``.nc``: the dataset of one cluster (``netcdf.cluster_dataset``); ``.png``
    and ``.svg``: its picture in ``style`` (``picture``: ``inches`` and
    ``dpi``, as ``pictures.draw_cluster``; a tree's ``.svg`` is the vector
    paths ``export_cluster`` writes); ``.csv``, ``.ply``, ``.obj``:
    ``export_cluster`` (``mesh`` for the meshes).
    """
    path, picture = Path(path), picture or {}
    suffix = path.suffix.lower()
    if suffix == ".nc":
        from .netcdf import cluster_dataset, save  # here: only a dataset needs netCDF

        save(cluster_dataset(cluster, seed), path)
    elif suffix in PICTURES and style == "tree":
        if suffix == ".svg":
            export_cluster(cluster, path)
        else:
            from ..reporting.tree_picture import draw_tree  # here: only a tree's picture needs it

            draw_tree(cluster, path, seed=seed, **picture)
    elif suffix in PICTURES:
        from ..reporting.pictures import draw_cluster  # here: only a picture needs matplotlib

        draw_cluster(cluster.points, cluster.params, path, seed=seed, status=cluster.status, **picture)
    else:
        export_cluster(cluster, path, mesh=mesh)


def needs_parents(path, style="disks", mesh="spheres") -> bool:
    """Whether ``write_cluster`` needs the cluster's parents for ``path``: a table, a tree, tubes."""
    suffix = Path(path).suffix.lower()
    return suffix == ".csv" or (suffix in PICTURES and style == "tree") or (suffix in MESH_FILES and mesh == "tubes")


def check(path, mesh="spheres"):
    """Refuse an extension or a mesh ``export_cluster`` does not write (ValueError naming it)."""
    path = Path(path)
    if path.suffix.lower() not in FORMATS:
        raise ValueError(f"{path}: expected a file ending in {', '.join(FORMATS)}")
    if mesh not in MESHES:
        raise ValueError(f"mesh: {mesh!r} is not one of {', '.join(MESHES)}")


def _chunks(n, per=1):
    """(start, stop) of the blocks of ``CHUNK // per`` particles (at least one) that cover 0..n-1."""
    size = max(CHUNK // per, 1)
    for start in range(0, n, size):
        yield start, min(start + size, n)


def _xyz(points, start, stop) -> np.ndarray:
    """Particles start..stop-1 as float64 (k, 3), z = 0 for 2D."""
    out = np.zeros((stop - start, 3))
    out[:, :points.shape[1]] = points[start:stop]
    return out


# .csv ---------------------------------------------------------------------

def _csv(cluster, f, mesh):
    points = cluster.points
    dim = points.shape[1]
    exact = points.dtype.kind in "iu"
    f.write((",".join(["id", "parent", *"xyz"[:dim], "diffusion_time"]) + "\n").encode())
    row = ",".join(["%d", "%d", *(["%d" if exact else "%.17g"] * dim), "%d"]) + "\n"
    for start, stop in _chunks(len(points)):
        block = np.empty((stop - start, dim + 3), object)
        block[:, 0] = np.arange(start, stop)
        block[:, 1] = cluster.parents[start:stop]
        block[:, 2:2 + dim] = points[start:stop]
        block[:, -1] = cluster.steps[start:stop]
        _rows(f, row, block)


def _rows(f, row, block):
    """Write each row of the 2D array ``block`` through the printf format ``row`` (one formatting call:
    ``numpy.savetxt`` formats row by row, several times slower: docs/performance.md, "Data files")."""
    if len(block):
        f.write(((row * len(block)) % tuple(block.ravel().tolist())).encode())


# meshes -------------------------------------------------------------------

def _icosahedron():
    """Vertices (12, 3) on the unit sphere and faces (20, 3), outward."""
    t = (1 + 5 ** 0.5) / 2
    v = np.array([[-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0], [0, -1, t], [0, 1, t], [0, -1, -t], [0, 1, -t],
                  [t, 0, -1], [t, 0, 1], [-t, 0, -1], [-t, 0, 1]], float)
    faces = np.array([[0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9], [5, 11, 4],
                      [11, 10, 2], [10, 7, 6], [7, 1, 8], [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8], [3, 8, 9],
                      [4, 9, 5], [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1]])
    return v / np.linalg.norm(v, axis=1, keepdims=True), faces


def _prism_faces():
    """Faces of a tube: ring 0 (vertices 0..S-1) to ring 1 (S..2S-1), two triangles a side."""
    s = np.arange(TUBE_SIDES)
    nxt = (s + 1) % TUBE_SIDES
    return np.concatenate([np.stack([s, nxt, s + TUBE_SIDES], 1), np.stack([nxt, nxt + TUBE_SIDES, s + TUBE_SIDES], 1)])


def _mesh_blocks(cluster, mesh):
    """(vertices, faces) per chunk, faces numbered across the whole mesh: the mesh in pieces."""
    points = cluster.points
    if mesh == "spheres":
        unit, faces = _icosahedron()
        for start, stop in _chunks(len(points), 16):
            centres = _xyz(points, start, stop)
            first = np.arange(start, stop)[:, None, None] * len(unit)
            yield (centres[:, None, :] + RADIUS * unit[None]).reshape(-1, 3), (faces[None] + first).reshape(-1, 3)
        return
    faces = _prism_faces()
    angle = 2 * np.pi * np.arange(TUBE_SIDES) / TUBE_SIDES
    done = 0
    for start, stop in _chunks(len(points), 16):
        child = np.arange(start, stop)[cluster.parents[start:stop] >= 0]
        a = _xyz(points, start, stop)[child - start]
        b = np.zeros_like(a)
        b[:, :points.shape[1]] = points[cluster.parents[child]]
        d = b - a
        if cluster.params.get("seed_shape") == "line":  # a bond across a periodic side: the nearest image
            period = cluster.params["size"]
            d[:, :points.shape[1] - 1] -= period * np.round(d[:, :points.shape[1] - 1] / period)
        ends = np.stack([a, a + d], 1)
        d /= np.linalg.norm(d, axis=1, keepdims=True)
        helper = np.where(np.abs(d[:, 2:3]) < 0.9, [[0.0, 0.0, 1.0]], [[1.0, 0.0, 0.0]])
        u = np.cross(d, helper)
        u /= np.linalg.norm(u, axis=1, keepdims=True)
        v = np.cross(d, u)
        ring = TUBE_RADIUS * (np.cos(angle)[None, :, None] * u[:, None] + np.sin(angle)[None, :, None] * v[:, None])
        vertices = (ends[:, :, None, :] + ring[:, None]).reshape(-1, 3)
        first = (done + np.arange(len(child)))[:, None, None] * 2 * TUBE_SIDES
        done += len(child)
        yield vertices, (faces[None] + first).reshape(-1, 3)


def _mesh_size(cluster, mesh) -> tuple:
    """Vertices and faces of the whole mesh."""
    if mesh == "spheres":
        return 12 * len(cluster.points), 20 * len(cluster.points)
    bonds = int((cluster.parents >= 0).sum())
    return 2 * TUBE_SIDES * bonds, 2 * TUBE_SIDES * bonds


def _ply(cluster, f, mesh):
    vertices, faces = _mesh_size(cluster, mesh)
    f.write("\n".join([
        "ply", "format binary_little_endian 1.0",
        f"comment dlasweep cluster: {len(cluster.points)} particles as {mesh}, lengths in particle diameters",
        f"element vertex {vertices}", "property float x", "property float y", "property float z",
        f"element face {faces}", "property list uchar uint vertex_indices", "end_header", ""]).encode("ascii"))
    for v, _ in _mesh_blocks(cluster, mesh):
        f.write(v.astype("<f4").tobytes())
    face = np.dtype([("n", "u1"), ("v", "<u4", (3,))])
    for _, tri in _mesh_blocks(cluster, mesh):
        block = np.empty(len(tri), face)
        block["n"], block["v"] = 3, tri
        f.write(block.tobytes())


def _obj(cluster, f, mesh):
    vertices, faces = _mesh_size(cluster, mesh)
    f.write(f"# dlasweep cluster: {len(cluster.points)} particles as {mesh}, lengths in particle diameters\n"
            f"# {vertices} vertices, {faces} faces\n".encode())
    for v, _ in _mesh_blocks(cluster, mesh):
        _rows(f, "v %.6f %.6f %.6f\n", v)
    for _, tri in _mesh_blocks(cluster, mesh):
        _rows(f, "f %d %d %d\n", tri + 1)


# .svg ---------------------------------------------------------------------

def branch_polylines(cluster):
    """Every Horton-Strahler branch of a cluster as (order, xy): its path from its junction to its tip,
    seen along z, lowest orders first; a branch that crosses a substrate's periodic side comes in pieces.

    Returns
    -------
    iterator of (int, ndarray (k, 2))
    """
    # numba's kernels: loaded here, so that the CLI builds its options without them
    from ..measures.tree import branch_paths, strahler

    points = cluster.points[:, :2]
    nodes, offsets, orders = branch_paths(cluster.parents, strahler(cluster.parents))
    period = cluster.params["size"] if cluster.params.get("seed_shape") == "line" else 0
    for j, k in enumerate(orders):
        path = points[nodes[offsets[j]:offsets[j + 1]]]
        if period and len(path) > 1:
            jumps = np.flatnonzero(np.abs(np.diff(path[:, 0].astype(np.float64))) > period / 2) + 1
            for piece in np.split(path, jumps):
                if len(piece) > 1:
                    yield int(k), piece
        else:
            yield int(k), path


def _svg(cluster, f, mesh):
    points = cluster.points[:, :2]
    lo, hi = points.min(axis=0) - MARGIN, points.max(axis=0) + MARGIN
    width, height = hi - lo
    f.write(
        f'<svg xmlns="http://www.w3.org/2000/svg" viewBox="{lo[0]:g} {-hi[1]:g} {width:g} {height:g}" '
        f'width="{width:g}mm" height="{height:g}mm">\n'
        f"<!-- dlasweep cluster: {len(points)} particles; one polyline per Horton-Strahler branch, stroke width "
        f"{STROKE:g} x order; lengths in particle diameters (1 mm) -->\n"
        '<g fill="none" stroke="black" stroke-linecap="round" stroke-linejoin="round" transform="scale(1,-1)">\n'
        .encode())
    exact = points.dtype.kind in "iu"
    current = 0
    for k, path in branch_polylines(cluster):
        if k != current:
            f.write((b"</g>\n" if current else b"") + f'<g stroke-width="{STROKE * k:g}" class="order-{k}">\n'
                     .encode())
            current = k
        xy = " ".join(f"{x},{y}" if exact else f"{x:.3f},{y:.3f}" for x, y in path.tolist())
        f.write(f'<polyline points="{xy}"/>\n'.encode())
    f.write((b"</g>\n" if current else b"") + b"</g>\n</svg>\n")
