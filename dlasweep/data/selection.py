"""Which stored clusters a selection on a sweep's grid holds (xarray only: no netCDF, no dask).

A sweep keeps its clusters on their own dims, ``cluster`` and ``particle``
(a CF ragged array), which a selection on the grid, ``ds.sel(stickiness=0.5)``,
leaves whole. Each cluster names its configuration in its ``cluster_<name>``
coordinates, and these say which clusters belong to the selection.
"""

from __future__ import annotations

import numpy as np
import xarray as xr


def dataset_checked(ds) -> xr.Dataset:
    """``ds`` when it is an xarray Dataset, else a TypeError naming it (a file is opened with ``open_sweep``)."""
    if not isinstance(ds, xr.Dataset):
        raise TypeError(f"ds: expected an xarray.Dataset (open_sweep, run_sweep), got {type(ds).__name__}")
    return ds


def selected_clusters(ds: xr.Dataset) -> np.ndarray:
    """Positions on ``cluster`` of the clusters that a selection on the grid keeps, in order.

    ``ds.sel(stickiness=0.5)`` leaves the ``cluster`` dim whole (xarray does
    not know that a cluster belongs to a configuration); a cluster belongs
    to the selection when each of its ``cluster_<name>`` values is among the
    dataset's values of ``<name>``, a scalar or a sweep axis. Unselected:
    every cluster.
    """
    keep = np.ones(ds.sizes.get("cluster", 0), bool)
    for name in ds.coords:
        grid = str(name).removeprefix("cluster_")
        if grid != name and grid in ds.coords:
            keep &= np.isin(ds[name].values, np.atleast_1d(ds[grid].values))
    return np.flatnonzero(keep)


def with_selected_clusters(ds: xr.Dataset) -> xr.Dataset:
    """``ds`` holding only the clusters of its selection (``selected_clusters``) and their particles.

    The ``cluster`` and ``particle`` dims are subset alike, so positions on
    ``cluster`` and the offsets the counts give stay consistent; lazy and
    dask arrays stay lazy. Returns ``ds`` itself when every cluster is kept.
    """
    keep = selected_clusters(ds)
    if len(keep) == ds.sizes.get("cluster", 0):
        return ds
    offsets = np.r_[0, np.cumsum(ds["cluster_particles"].values)]
    ranges = [(offsets[i], offsets[i + 1]) for i in keep]
    if len(keep) and all(a[1] == b[0] for a, b in zip(ranges, ranges[1:])):
        particles = slice(ranges[0][0], ranges[-1][1])  # one block: a slice reads no index array
    else:
        particles = np.concatenate([np.arange(a, b) for a, b in ranges] or [np.zeros(0, np.int64)])
    return ds.isel(cluster=keep, particle=particles) if "particle" in ds.dims else ds.isel(cluster=keep)
