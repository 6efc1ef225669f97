"""``ds.dla``: a sweep's clusters, summary and report from the Dataset itself (xarray's accessor convention).

Registered by ``import dlasweep`` (see ``dlasweep/__init__.py``). A
selection on the grid, ``ds.sel(stickiness=0.5).dla``, has the clusters of
that selection (``selection.selected_clusters``). Nothing here reads the
per-particle arrays whole: a cluster is read as its own range of them.
"""

from __future__ import annotations

import xarray as xr

from .selection import with_selected_clusters


@xr.register_dataset_accessor("dla")
class DlaAccessor:
    """dlasweep's view of a Dataset it wrote (``open_sweep``, ``run_sweep``, ``xr.open_dataset``).

    Examples
    --------
    >>> ds = xr.open_dataset("results/quick.nc", chunks={})  # doctest: +SKIP
    >>> ds.sel(stickiness=0.5).dla.cluster(seed=3)            # doctest: +SKIP
    >>> for c in ds.dla.clusters(): ...                       # doctest: +SKIP
    """

    def __init__(self, ds: xr.Dataset):
        self._ds = ds
        self._own = None

    @property
    def ds(self) -> xr.Dataset:
        """The dataset with only the clusters of its selection, and their particles (lazy as it was)."""
        if self._own is None:
            self._own = with_selected_clusters(self._ds)
        return self._own

    def __len__(self) -> int:
        return self.ds.sizes.get("cluster", 0)

    def cluster(self, k=None, **where):
        """One stored cluster with its diffusion times, status and parameters.

        Parameters
        ----------
        k : int, optional
            Position among the clusters of the selection (task order).
        **where
            Otherwise, the cluster's parameters, e.g. ``seed=3`` or
            ``stickiness=0.5, seed=3``; they must pick one cluster.

        Returns
        -------
        dlasweep.Cluster
            Shown as its picture in a notebook.
        """
        from .ragged import read_cluster

        return read_cluster(self.ds, k, **where)

    def clusters(self):
        """Every stored cluster of the selection, in order, read one at a time.

        Yields
        ------
        dlasweep.Cluster
        """
        for k in range(len(self)):
            yield self.cluster(k)

    def __iter__(self):
        return self.clusters()

    def summarise(self, **kwargs) -> xr.Dataset:
        """``dlasweep.summarise`` of the selection (keywords passed on)."""
        from ..stats.summary import summarise

        return summarise(self.ds, **kwargs)

    def report(self, outdir, **kwargs) -> list:
        """``dlasweep.report`` of the selection into ``outdir``; returns the files written."""
        from ..reporting.folder import report

        return report(self.ds, outdir, **kwargs)
