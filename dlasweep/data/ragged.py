"""One stored cluster of a dataset, read back from its CF ragged array: its points, parents, status, parameters.

Indexing of an open dataset (``netcdf.open_sweep``, or a sweep in memory),
no netCDF: the analysis and the pictures read clusters through here.
Only the cluster's range of the per-particle arrays is read.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from .. import params as _params
from .schema import AXES, BOOLEAN, STATUS_FLAGS, StoreError
from .selection import dataset_checked, selected_clusters


def cluster_points(ds: xr.Dataset, index=None, **where) -> np.ndarray:
    """Positions of one stored cluster, in attachment order.

    Parameters
    ----------
    ds : xarray.Dataset
        From ``open_sweep`` or ``run_sweep``, or a selection of one
        (``ds.sel(stickiness=0.5)``): ``where`` then looks among the clusters
        of the selection only (``selected_clusters``).
    index : int, optional
        Position along ``cluster`` (task order).
    **where
        Otherwise, the cluster's parameters, e.g. ``stickiness=0.5, seed=3``;
        names without the ``cluster_`` prefix. They must pick one cluster.

    Returns
    -------
    ndarray, (n, dim)
    """
    index = _index(ds, index, where)
    start, stop = _particles_of(ds, index)
    # With dim swept, 2D clusters sit in the z = 0 plane of a 3D ragged array.
    axes = AXES[:_cluster_value(ds, "dim", index)]
    points = np.empty((stop - start, len(axes)), ds[axes[0]].dtype)
    for a, name in enumerate(axes):  # a column at a time: 10^8 sites' columns are 4e8 bytes each
        points[:, a] = ds[name][start:stop].values
    return points


def cluster_parents(ds: xr.Dataset, index=None, **where) -> np.ndarray:
    """Parents of one stored cluster's particles, in attachment order (``Cluster.parents``).

    Parameters
    ----------
    ds : xarray.Dataset
        As for ``cluster_points``.
    index : int, optional
        As for ``cluster_points``.
    **where
        As for ``cluster_points``.

    Returns
    -------
    ndarray, (n,) int32
        Position in the cluster of the particle each one stuck to; -1 for
        the seed particles and those that stuck to a substrate.

    Raises
    ------
    StoreError
        When the file predates parents (no ``parent`` variable).
    """
    if "parent" not in ds.variables:
        raise StoreError("parent: this file holds no parents (written before dlasweep stored them)")
    index = _index(ds, index, where)
    start, stop = _particles_of(ds, index)
    return ds["parent"][start:stop].values.astype(np.int32)


def read_cluster(ds: xr.Dataset, index=None, **where):
    """One stored cluster, as ``grow`` returned it: points, diffusion times, status and parameters.

    Only that cluster's range of the per-particle arrays is read (with dask
    chunks, only the chunks that hold it).

    Parameters
    ----------
    ds : xarray.Dataset
        As for ``cluster_points``.
    index : int, optional
        As for ``cluster_points``.
    **where
        As for ``cluster_points``.

    Returns
    -------
    dlasweep.Cluster
        ``status`` is the growth's outcome at the largest count; no
        checkpoint times (a sweep keeps them in ``wall_time``).
    """
    from ..growth.cluster import Cluster

    index = _index(ds, index, where)
    start, stop = _particles_of(ds, index)
    # a parameter younger than the file takes its default, the behaviour of the code that wrote it
    params = {name: _cluster_value(ds, name, index) for name in _params.PARAMETERS
              if name in ds.coords or f"cluster_{name}" in ds.coords}
    return Cluster(cluster_points(ds, index), ds["diffusion_time"][start:stop].values, _status(ds, index),
                   _params.resolve(**params),
                   parents=cluster_parents(ds, index) if "parent" in ds.variables else None)


def _index(ds, index, where) -> int:
    """The position on ``cluster`` that ``index`` or ``where`` names (``cluster_points``), checked."""
    dataset_checked(ds)
    if (index is None) == (not where):
        raise TypeError("cluster: give either an index or parameter values")
    if index is None:
        return _find_cluster(ds, where)
    if not _params.is_integer(index):
        raise TypeError(f"cluster: index {index!r} is not an integer")
    count = ds.sizes.get("cluster", 0)
    if not -count <= index < count:
        raise IndexError(f"cluster: index {index} is outside 0..{count - 1}")
    return int(index) % count


def _particles_of(ds, index) -> tuple:
    """The range of ``particle`` that holds cluster ``index``."""
    counts = ds["cluster_particles"].values
    start = int(counts[:index].sum())
    return start, start + int(counts[index])


def _cluster_value(ds, name, index):
    """Model parameter ``name`` of cluster ``index``: its ``cluster_<name>`` value, else the dataset's scalar.

    A boolean comes back as bool also from a file opened without ``open_sweep`` (int8 flags there).
    """
    coord = f"cluster_{name}"
    var = ds[coord][index] if coord in ds.coords else ds[name]
    value = var.values.item()
    return bool(value) if var.attrs.get("flag_meanings") == BOOLEAN else value


def _status(ds, index) -> str:
    """Cluster ``index``'s growth outcome: at the largest count of a sweep, or its own in a grown cluster's file."""
    status = ds["status"]
    if status.dims == ("cluster",):
        return STATUS_FLAGS[int(status[index])]
    at = {d: ds[f"cluster_{d}"].values[index] for d in status.dims if d != "n_particles"}
    return STATUS_FLAGS[int(status.sel(at).isel(n_particles=-1))]


def _find_cluster(ds, where) -> int:
    """The position on ``cluster`` of the one cluster of ``ds``'s selection whose parameters are ``where``."""
    candidates = selected_clusters(ds)
    match = np.ones(len(candidates), bool)
    for name, value in where.items():
        coord = f"cluster_{name}"
        if coord not in ds.coords:
            known = [c[len("cluster_"):] for c in ds.coords if c.startswith("cluster_")]
            raise ValueError(f"{name}: not a cluster parameter (known: {', '.join(known)})")
        match &= ds[coord].values[candidates] == value
    found = candidates[match]
    if len(found) != 1:
        raise ValueError(f"{where}: matches {len(found)} clusters, not one")
    return int(found[0])


