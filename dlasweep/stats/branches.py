"""Branch statistics of a sweep's stored clusters, over seeds: what ``summarise`` adds of the trees.

Each stored cluster (grown to the sweep's largest count) is read as a
tree (``tree.branching``); per configuration, the bifurcation ratio and the
chemical-distance dimension are the means over its clusters with the 95%
CI of the mean (Student's t, ``fit.ensemble``), and the branch counts per
Horton-Strahler order are averaged over them.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from ..data.ragged import cluster_parents
from ..measures.tree import MIN_BRANCHES, branching
from .constants import LEVEL
from .fit import ensemble

ATTRS = {
    "bifurcation_ratio": "Horton-Strahler bifurcation ratio R_b = N_k / N_(k+1), mean over the stored clusters of "
                         f"each cluster's fit of ln N_k against k over the orders with at least {MIN_BRANCHES} "
                         "branches, largest count",
    "bifurcation_ratio_ci_lo": f"lower end of the {LEVEL} CI of bifurcation_ratio (Student's t over clusters)",
    "bifurcation_ratio_ci_hi": f"upper end of the {LEVEL} CI of bifurcation_ratio (Student's t over clusters)",
    "bifurcation_ratio_cluster": "bifurcation ratio of one stored cluster",
    "chemical_dimension": "chemical-distance dimension d_l: particles within l bonds of the seed ~ l**d_l, "
                          "mean over the stored clusters",
    "chemical_dimension_ci_lo": f"lower end of the {LEVEL} CI of chemical_dimension (Student's t over clusters)",
    "chemical_dimension_ci_hi": f"upper end of the {LEVEL} CI of chemical_dimension (Student's t over clusters)",
    "branch_count": "number of branches of each Horton-Strahler order, mean over the stored clusters (0 where a "
                    "cluster has no branch of that order)",
    "branch_clusters": "stored clusters with parents that enter the branch statistics",
}


def summary(ds, config_dims, clusters, min_seeds) -> xr.Dataset:
    """The branch statistics of every configuration (``ATTRS``), empty when no stored cluster has parents.

    Parameters
    ----------
    ds : xarray.Dataset
        The sweep (a selection's clusters only: ``selection.with_selected_clusters``).
    config_dims : list of str
        The configuration dims (``schema.config_dims``).
    clusters : dict
        (configuration index tuple, seed index) -> position on ``cluster``.
    min_seeds : int
        Fewest clusters a CI is given from (``summary.MIN_CI_SEEDS``).
    """
    if "parent" not in ds.variables or not clusters:
        return xr.Dataset()
    shape = tuple(ds.sizes[d] for d in config_dims)
    n_seeds = ds.sizes["seed"]
    ratio = np.full((*shape, n_seeds), np.nan)
    chem = np.full((*shape, n_seeds), np.nan)
    counts = {}
    for (config, seed), i in sorted(clusters.items(), key=lambda item: item[1]):
        parents = cluster_parents(ds, i)
        if len(parents) < 2:
            continue
        b = branching(parents)
        ratio[(*config, seed)], chem[(*config, seed)] = b["bifurcation_ratio"], b["chemical_dimension"]
        counts[config, seed] = b["branch_counts"]
    top = max((len(c) for c in counts.values()), default=0)
    mean_counts = np.full((*shape, top), np.nan)
    out = {name: np.full(shape, np.nan) for name in ATTRS if name not in ("bifurcation_ratio_cluster",
                                                                          "branch_count")}
    for config in np.ndindex(*shape):
        found = [np.pad(c, (0, top - len(c))) for (cfg, _), c in counts.items() if cfg == config]
        if found:
            mean_counts[config] = np.mean(found, axis=0)
        out["branch_clusters"][config] = len(found)
        for name, values in (("bifurcation_ratio", ratio[config]), ("chemical_dimension", chem[config])):
            e = ensemble(values)
            out[name][config] = e.mean
            if e.n >= min_seeds:
                out[f"{name}_ci_lo"][config], out[f"{name}_ci_hi"][config] = e.ci_lo, e.ci_hi
    data = {name: (config_dims, values, {"long_name": ATTRS[name]}) for name, values in out.items()}
    data["branch_clusters"] = (config_dims, out["branch_clusters"].astype(np.int64),
                               {"long_name": ATTRS["branch_clusters"]})
    data["bifurcation_ratio_cluster"] = ((*config_dims, "seed"), ratio,
                                         {"long_name": ATTRS["bifurcation_ratio_cluster"]})
    data["branch_count"] = ((*config_dims, "order"), mean_counts, {"long_name": ATTRS["branch_count"]})
    coords = {d: ds[d].values for d in (*config_dims, "seed")}
    coords["order"] = ("order", np.arange(1, top + 1), {"long_name": "Horton-Strahler order"})
    return xr.Dataset(data, coords=coords)


def ratio_line(counts, ratio) -> np.ndarray:
    """Branch counts falling by ``ratio`` an order, N_k = A ratio**-k, at every order; A fitted (least squares
    in ln N, ratio fixed) to the ``counts`` (order 1 first) of the orders that enter R_b (``tree.MIN_BRANCHES``)."""
    counts = np.asarray(counts, np.float64)
    k = np.arange(1, len(counts) + 1)
    fitted = np.isfinite(counts) & (counts >= MIN_BRANCHES)
    anchor = np.exp(np.mean(np.log(counts[fitted]) + k[fitted] * np.log(ratio)))
    return anchor * ratio ** -k.astype(np.float64)
