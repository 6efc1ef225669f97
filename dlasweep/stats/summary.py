"""Ensemble analysis of a sweep: every number the report quotes, as one xarray Dataset.

The headline D of a configuration at a count N is the ensemble mass-radius
estimate: the seed-averaged radius of gyration <Rg>(n) over the growth
histories of every cluster that reached N, fitted as n ~ <Rg>**D over the
widest flat window between the end of the transient (5% of N) and N
(``fit.fit_mass_radius``). Its 95% CI comes from a bootstrap over seeds
with the window held fixed, scaled by Student's t (``fit.seed_interval``),
given from ``MIN_CI_SEEDS`` clusters on (every interval over seeds is;
below, ``D_ci_reason`` says why there is none).
Every cluster that reached N enters; none is dropped for its own fit.

Beside it: the local slope D_eff(n) of the same ensemble curve over each
octave of n with its bootstrap band; D_inf, the extrapolation
D_eff(n) = D_inf + a n**-w over independent octaves, given only where that
model describes the data (``extrapolation``); each variant against the
exact method (``exact``); and the box-counting D (the mean over every
cluster of its own fit), a finite-cluster estimate that reads low.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from functools import cached_property

import numpy as np
import xarray as xr

from ..data.ragged import cluster_points
from ..data.schema import config_dims, is_sweep, plain
from ..data.selection import dataset_checked, with_selected_clusters
from ..measures.shape import radius_of_gyration, time_depth_pairs
from ..params import STATUSES
from . import branches
from .constants import LEVEL, MIN_CI_SEEDS, MIN_COUNT, RESAMPLES
from .exact import against_exact
from .extrapolation import extrapolate
from .fit import (
    Fit,
    bootstrap_means,
    ensemble,
    fit_dimension,
    fit_mass_radius,
    growth_counts,
    history_counts,
    mass_radius_counts,
    seed_interval,
)

DEPTH_EDGES = np.linspace(0.0, 1.0, 11)
"""Bins of the depth at which a particle stuck: distance from the seed over the cluster's radius."""
_MERGE_AT = 1_000_000
"""Distinct (diffusion time, depth bin) pairs a configuration collects from its clusters before merging them."""

@dataclass(frozen=True)
class Summarised:
    """One variable of the summary: its dims beside the configuration's, its type and long name.

    Computed as floats, NaN where missing, and stored as ``dtype``, NaN then
    becoming ``missing``; ``str`` variables (the reasons) are empty where there
    is nothing to say.
    """

    dims: tuple
    long_name: str
    dtype: object = np.float64
    missing: object = np.nan

    def blank(self, shape) -> np.ndarray:
        """Its values while they are computed: NaN, or empty strings."""
        return np.full(shape, "", object) if self.dtype is str else np.full(shape, np.nan)


_N, _SEEDS = ("n_particles",), ("n_particles", "seed")
SUMMARY = {
    "D": Summarised(_N, "D, ensemble mass-radius: n ~ <Rg>**D over the seeds that reached N, widest flat window"),
    "D_ci_lo": Summarised(_N, f"lower end of the {LEVEL} CI of D (bootstrap over seeds, window fixed)"),
    "D_ci_hi": Summarised(_N, f"upper end of the {LEVEL} CI of D (bootstrap over seeds, window fixed)"),
    "D_range_lo": Summarised(_N, "smallest particle count of the fitted window"),
    "D_range_hi": Summarised(_N, "largest particle count of the fitted window"),
    "D_drift": Summarised(_N, "change of the local slope of the ensemble curve across the fitted window"),
    "D_ok": Summarised(_N, "the ensemble curve has a flat window of a decade (1) or not (0)", np.int8, 0),
    "D_seeds": Summarised(_N, "clusters that reached N and enter D", np.int64, 0),
    "D_seed_std": Summarised(_N, "standard deviation over seeds of the per-cluster mass-radius D"),
    "D_box": Summarised(_N, "box-counting D, mean of the per-cluster fits of every cluster that reached N (reads low)"),
    "D_box_ci_lo": Summarised(_N, f"lower end of the bootstrap {LEVEL} CI of D_box"),
    "D_box_ci_hi": Summarised(_N, f"upper end of the bootstrap {LEVEL} CI of D_box"),
    "D_box_ok_fraction": Summarised(_N, "fraction of those clusters whose own box-counting fit is flat"),
    "rg_mean": Summarised(_N, "mean radius of gyration over the seeds that reached N"),
    "rg_ci_lo": Summarised(_N, f"lower end of the bootstrap {LEVEL} CI of rg_mean"),
    "rg_ci_hi": Summarised(_N, f"upper end of the bootstrap {LEVEL} CI of rg_mean"),
    "rg_over_rmax": Summarised(_N, "mean of Rg / R_max over the seeds that reached N"),
    "rg_over_rmax_ci_lo": Summarised(_N, f"lower end of the bootstrap {LEVEL} CI of rg_over_rmax"),
    "rg_over_rmax_ci_hi": Summarised(_N, f"upper end of the bootstrap {LEVEL} CI of rg_over_rmax"),
    "anisotropy": Summarised(_N,
                             "mean over the seeds that reached N of the cubic anisotropy of the outer half of the "
                             "mass"),
    "anisotropy_ci_lo": Summarised(_N, f"lower end of the bootstrap {LEVEL} CI of anisotropy"),
    "anisotropy_ci_hi": Summarised(_N, f"upper end of the bootstrap {LEVEL} CI of anisotropy"),
    "seconds_per_particle": Summarised(_N, "mean wall time per particle to grow to N"),
    "steps_per_particle": Summarised(_N, "mean walk steps per particle to grow to N"),
    "pareto": Summarised(_N,
                         "on the Pareto front of cost per particle against the bound on |Rg/Rg(exact) - 1| (1) or not "
                         "(0)", np.int8, 0),
    "D_vs_exact": Summarised(_N, "D minus D of the exact method (other parameters equal) at equal N"),
    "D_vs_exact_half_width": Summarised(_N, f"{LEVEL} CI half-width of D_vs_exact (both CIs in quadrature)"),
    "rg_mean_vs_exact": Summarised(_N, "rg_mean over rg_mean of the exact method, minus 1, at equal N"),
    "rg_mean_vs_exact_half_width": Summarised(_N,
                                              f"{LEVEL} CI half-width of rg_mean_vs_exact (both CIs in quadrature)"),
    "rg_over_rmax_vs_exact": Summarised(_N, "rg_over_rmax minus that of the exact method at equal N"),
    "rg_over_rmax_vs_exact_half_width": Summarised(_N,
                                                   f"{LEVEL} CI half-width of rg_over_rmax_vs_exact (both CIs in "
                                                   "quadrature)"),
    "D_cluster": Summarised(_SEEDS, "mass-radius D of one cluster's own growth history up to N"),
    "D_cluster_ok": Summarised(_SEEDS, "whether that cluster's fit is flat (1) or not (0)", np.int8, 0),
    "D_box_cluster": Summarised(_SEEDS, "box-counting D of one cluster at N"),
    "D_box_cluster_ok": Summarised(_SEEDS, "whether that fit is flat (1) or not (0)", np.int8, 0),
    "D_box_range_lo": Summarised(_SEEDS, "smallest box side of that cluster's box-counting fit window"),
    "D_box_range_hi": Summarised(_SEEDS, "largest box side of that cluster's box-counting fit window"),
    "box_slope": Summarised(("scale_mid",),
                            "local box-counting slope -d ln N(s) / d ln s between adjacent sides, mean over seeds, "
                            "largest N"),
    "box_slope_std": Summarised(("scale_mid",), "standard deviation over seeds of box_slope"),
    "diffusion_density": Summarised(("diffusion_bin",),
                                    "probability density of diffusion times (walk steps or jumps to stick), pooled "
                                    "over the stored clusters"),
    "diffusion_median": Summarised(("depth_bin",),
                                   "median diffusion time of the particles that stuck at that depth, pooled over the "
                                   "stored clusters"),
    "D_local": Summarised(("n_local",), "local slope D_eff: d ln n / d ln <Rg> over one octave of n, ensemble curve"),
    "D_local_ci_lo": Summarised(("n_local",), f"lower end of the bootstrap {LEVEL} band of D_local"),
    "D_local_ci_hi": Summarised(("n_local",), f"upper end of the bootstrap {LEVEL} band of D_local"),
    "rg_history": Summarised(("n_history",),
                             "mean radius of gyration over the seeds that reached the largest count, along their "
                             "growth"),
    "D_inf": Summarised((), "D extrapolated to infinite N: D_eff(n) = D_inf + a n**-w over independent octaves"),
    "D_inf_ci_lo": Summarised((), f"lower end of the bootstrap {LEVEL} CI of D_inf"),
    "D_inf_ci_hi": Summarised((), f"upper end of the bootstrap {LEVEL} CI of D_inf"),
    "D_inf_exponent": Summarised((), "correction exponent w of the extrapolation"),
    "D_inf_range_lo": Summarised((), "smallest count of the octaves the extrapolation uses"),
    "status_count": Summarised(("n_particles", "status"), "clusters with each growth status at N", np.int64, 0),
    "cluster_index": Summarised(("seed",),
                                "position on the sweep's cluster dimension of this seed's stored cluster, -1 if "
                                "none", np.int64, -1),
    "D_reason": Summarised(_N, "why D_ok is 0; empty otherwise", str),
    "D_ci_reason": Summarised(_N, f"why D has no {LEVEL} CI (and no other interval over seeds is given); "
                                  "empty otherwise", str),
    "D_inf_reason": Summarised((), "why D_inf is not given; empty otherwise", str),
}
"""Every variable of ``summarise``'s dataset, in its order: the one place its dims, type and
long name are spelled (as ``schema.SCHEMA`` spells the stored ones)."""


def summarise(ds, *, resamples: int = RESAMPLES) -> xr.Dataset:
    """Headline D, its 95% CI, local slopes, D_inf and box-counting D of every configuration.

    Parameters
    ----------
    ds : xarray.Dataset
        A sweep, as from ``run_sweep`` or ``open_sweep``.
    resamples : int
        Bootstrap resamples over seeds.

    Returns
    -------
    xarray.Dataset
        On the sweep's configuration dims (swept parameters, ``size``) and
        ``n_particles``; per-cluster fits also on ``seed``; the local slopes
        on ``n_local`` (the geometric centre of each octave); D_inf per
        configuration. Every variable has a ``long_name``; the module
        docstring says how each is estimated. With stored clusters that
        have parents, their branch statistics too (``branches.summary``).
    """
    sweep = _Sweep(ds)
    out = {name: var.blank(sweep.shape + tuple(sweep.extra[d] for d in var.dims)) for name, var in SUMMARY.items()}
    for config in np.ndindex(*sweep.shape):
        _config(sweep, config, out, resamples)
    against_exact(sweep.ds, out)
    return sweep.dataset(out, resamples).merge(branches.summary(sweep.ds, sweep.config_dims, sweep.clusters,
                                                                 MIN_CI_SEEDS))


def sweep_checked(ds):
    """``ds`` when it is a sweep's Dataset, else one line naming it: a TypeError (not a Dataset) or a ValueError."""
    if not is_sweep(dataset_checked(ds)):
        raise ValueError("ds: holds no sweep (no box_count or n_grown): one cluster from grow, or another dataset")
    return ds


class _Sweep:
    """The parts of a sweep dataset that the analysis reads, indexed by configuration."""

    def __init__(self, ds):
        # a selection on the grid (ds.sel) keeps its own clusters only
        self.ds = ds = with_selected_clusters(sweep_checked(ds))
        self.config_dims = config_dims(ds)
        self.shape = tuple(ds.sizes[d] for d in self.config_dims)
        self.counts = ds["n_particles"].values.astype(np.int64)
        self.scales = ds["scale"].values
        self.n_counts, self.n_seeds = len(self.counts), ds.sizes["seed"]
        self.history = history_counts(int(self.counts[-1]))
        octave = [np.flatnonzero((self.history >= h) & (self.history <= 2 * h)) for h in self.history]
        self.octaves = [o for o in octave if len(o) >= 2 and self.history[o[-1]] >= 1.9 * self.history[o[0]]]
        self.centres = np.array([np.exp(np.log(self.history[o]).mean()) for o in self.octaves])
        self.clusters = self._cluster_index() if "cluster_particles" in ds else {}
        self.offsets = np.r_[0, np.cumsum(ds["cluster_particles"].values)] if self.clusters else None
        # Files written before the growth history was recorded: the stored clusters give it.
        self.growth = ds["history"].values if "radius_gyration_history" in ds else growth_counts(self.counts)

    def curves(self, config):
        """Rg of every seed's cluster at the ``growth`` counts, NaN where not grown (or, in older files, not stored)."""
        if "radius_gyration_history" in self.ds:
            return self.ds["radius_gyration_history"][dict(zip(self.config_dims, config))].values
        curves = np.full((self.n_seeds, len(self.growth)), np.nan)
        for s in range(self.n_seeds):
            points = self.points(config, s)
            if points is not None:
                rg = radius_of_gyration(points)
                reach = self.growth <= len(rg)
                curves[s, reach] = rg[self.growth[reach] - 1]
        return curves

    @cached_property
    def diffusion(self):
        """Per configuration, the diffusion times of its stored clusters' particles by depth bin, as counts.

        ``(times, depth bins, counts)`` of the distinct pairs, sorted by
        time: exact histograms and medians without holding every particle.
        The clusters are read once, in file order. The seed particle is
        left out. Also returns the longest time stored.
        """
        bins = len(DEPTH_EDGES) - 1
        pending, top = {}, 0
        for (config, seed), i in sorted(self.clusters.items(), key=lambda item: item[1]):
            if self.ds["cluster_particles"].values[i] < 1:
                continue
            times = self.times(config, seed)
            top = max(top, int(times.max()))
            pending.setdefault(config, []).append(time_depth_pairs(cluster_points(self.ds, i), times, DEPTH_EDGES))
            if sum(len(keys) for keys, _ in pending[config]) > _MERGE_AT:
                pending[config] = [_merge(pending[config])]
        tables = {}
        for config, found in pending.items():
            keys, counts = _merge(found)
            tables[config] = keys // bins, keys % bins, counts
        return tables, top

    @cached_property
    def time_edges(self):
        """Edges of the diffusion-time histogram, from one step to the longest time stored."""
        top = self.diffusion[1] if self.ds.sizes.get("particle", 0) else 1
        # Half-integer edges: times are whole steps, and log bins narrower than one step alias.
        return np.r_[0.5, np.unique(np.round(np.logspace(0, np.log10(max(top, 10)), 40))) + 0.5]

    @cached_property
    def extra(self):
        """Sizes of the dims a summary has beside the configuration's."""
        return {"n_particles": self.n_counts, "seed": self.n_seeds, "n_local": len(self.octaves),
                "n_history": len(self.history), "scale_mid": len(self.scales) - 1,
                "diffusion_bin": len(self.time_edges) - 1, "depth_bin": len(DEPTH_EDGES) - 1,
                "status": len(STATUSES)}

    def _cluster_index(self):
        """(configuration, seed index) -> position on ``cluster``."""
        ds = self.ds
        lookup = {d: {plain(v): i for i, v in enumerate(ds[d].values)} for d in (*self.config_dims, "seed")}
        where = {}
        for i in range(ds.sizes["cluster"]):
            at = tuple(lookup[d][plain(ds[f"cluster_{d}"].values[i])] for d in (*self.config_dims, "seed"))
            where[at[:-1], at[-1]] = i
        return where

    def points(self, config, seed):
        """The stored cluster's positions, or None."""
        i = self.clusters.get((config, seed))
        if i is None or self.ds["cluster_particles"].values[i] < 1:
            return None
        return cluster_points(self.ds, i).astype(np.float64)

    def times(self, config, seed):
        """The stored cluster's diffusion times."""
        i = self.clusters[config, seed]
        return self.ds["diffusion_time"][self.offsets[i]:self.offsets[i + 1]].values

    def dataset(self, out, resamples) -> xr.Dataset:
        ds = self.ds
        data = {}
        for name, values in out.items():
            var = SUMMARY[name]
            if var.dtype not in (str, np.float64):
                values = np.nan_to_num(values, nan=var.missing).astype(var.dtype)
            data[name] = ((*self.config_dims, *var.dims), values, {"long_name": var.long_name})
        coords = {d: ds[d].values for d in (*self.config_dims, "n_particles", "seed")}
        coords["n_history"] = self.history
        coords["n_local"] = self.centres
        coords["status"] = np.array(STATUSES, object)
        coords["scale_mid"] = np.sqrt(self.scales[1:] * self.scales[:-1])
        coords["diffusion_bin"] = np.sqrt(self.time_edges[1:] * self.time_edges[:-1])
        coords["depth_bin"] = (DEPTH_EDGES[1:] + DEPTH_EDGES[:-1]) / 2
        return xr.Dataset(data, coords=coords, attrs={
            "title": "dlasweep summary: fractal dimension of every configuration",
            "interval": f"every interval is a {LEVEL} confidence interval over seeds (Student's t: of the mean, or "
                        f"on a bootstrap's spread), given where at least {MIN_CI_SEEDS} clusters enter",
            "headline": "D: ensemble mass-radius (n ~ <Rg>**D), window chosen from the data (D_range_lo..hi)",
            "bootstrap_resamples": resamples,
        })


def _merge(tables):
    """One table of distinct keys and their summed counts from several."""
    keys, where = np.unique(np.concatenate([k for k, _ in tables]), return_inverse=True)
    return keys, np.bincount(where, weights=np.concatenate([c for _, c in tables])).astype(np.int64)



def _config(sweep, config, out, resamples):
    """Fill ``out`` at one configuration."""
    ds = sweep.ds
    at = {d: i for d, i in zip(sweep.config_dims, config)}
    cell = {name: ds[name][at].values for name in (
        "n_grown", "status", "radius_gyration", "max_radius", "wall_time", "walk_steps", "box_count")}
    # Files written before the anisotropy variable existed have none.
    cell["anisotropy"] = (ds["anisotropy"][at].values if "anisotropy" in ds
                          else np.full_like(cell["max_radius"], np.nan))
    needed = [mass_radius_counts(int(n)) for n in sweep.counts]
    grid = sweep.growth
    curves = sweep.curves(config)
    _per_cluster(sweep, config, cell, curves, out)
    _diffusion(sweep, config, out)
    for k, n in enumerate(sweep.counts):
        reached = cell["n_grown"][k] == n
        _count(sweep, config, k, n, reached, cell, curves[:, np.searchsorted(grid, needed[k])], needed[k], out,
               resamples)
    with np.errstate(divide="ignore", invalid="ignore"):
        slopes = -np.diff(np.log(cell["box_count"][-1].astype(float)), axis=-1) / np.diff(np.log(sweep.scales))
    grown = cell["n_grown"][-1] > 0
    if grown.any():
        out["box_slope"][config], out["box_slope_std"][config] = slopes[grown].mean(0), slopes[grown].std(0)
    alive = (cell["n_grown"][-1] == sweep.counts[-1]) & np.isfinite(curves[:, -1])
    _local(sweep, config, curves[alive][:, np.searchsorted(grid, sweep.history)], out, resamples)


def _per_cluster(sweep, config, cell, curves, out):
    """Each cluster's own fits at every count, from its Rg along the growth (``curves``) and its box counts.

    A cluster that stopped early, at m particles between the ``growth``
    counts, is fitted on the counts below m and m itself.
    """
    grid = sweep.growth
    for s in range(sweep.n_seeds):
        out["cluster_index"][config][s] = sweep.clusters.get((config, s), -1)
        for k in range(sweep.n_counts):
            m = int(cell["n_grown"][k, s])
            if m < 1:
                continue
            below = grid <= m
            if np.isfinite(curves[s, below]).all():
                n, rg = grid[below], curves[s, below]
                if not len(n) or n[-1] != m:
                    n, rg = np.r_[n, m], np.r_[rg, cell["radius_gyration"][k, s]]
                fit = fit_mass_radius(rg, n)
                out["D_cluster"][config][k, s], out["D_cluster_ok"][config][k, s] = fit.D, fit.ok
            fit = fit_dimension(sweep.scales, cell["box_count"][k, s])
            out["D_box_cluster"][config][k, s], out["D_box_cluster_ok"][config][k, s] = fit.D, fit.ok
            out["D_box_range_lo"][config][k, s], out["D_box_range_hi"][config][k, s] = fit.range_lo, fit.range_hi


def _diffusion(sweep, config, out):
    """Density of the diffusion times and their median by depth, pooled over the stored clusters."""
    if config not in sweep.diffusion[0]:
        return
    times, slot, counts = sweep.diffusion[0][config]
    n = np.histogram(times.astype(float), sweep.time_edges, weights=counts)[0]
    # As np.histogram(..., density=True) computes it from the pooled times.
    out["diffusion_density"][config] = n / np.diff(sweep.time_edges) / n.sum()
    for b in range(len(DEPTH_EDGES) - 1):
        here = slot == b
        if here.any():
            ends = np.cumsum(counts[here])
            middle = times[here][np.searchsorted(ends, [(ends[-1] - 1) // 2, ends[-1] // 2], side="right")]
            out["diffusion_median"][config][b] = middle.astype(float).mean()


def _count(sweep, config, k, n, reached, cell, curves, counts, out, resamples):
    """Statistics at one count: headline D, box-counting D, Rg, costs, statuses."""
    o = {name: values[(*config, ...)] for name, values in out.items()}
    o["status_count"][k] = np.bincount(cell["status"][k].astype(np.int64), minlength=len(STATUSES))
    grown = cell["n_grown"][k]
    alive = grown > 0
    if alive.any():
        o["seconds_per_particle"][k] = np.nanmean(cell["wall_time"][k][alive] / grown[alive])
        o["steps_per_particle"][k] = np.mean(cell["walk_steps"][k][alive] / grown[alive])
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = cell["radius_gyration"][k] / cell["max_radius"][k]
    for stem, mean, values in (("rg", "rg_mean", cell["radius_gyration"][k]), ("rg_over_rmax", "rg_over_rmax", ratio),
                               ("anisotropy", "anisotropy", cell["anisotropy"][k])):
        stats = _ensemble(np.where(reached, values, np.nan))
        o[mean][k], o[f"{stem}_ci_lo"][k], o[f"{stem}_ci_hi"][k] = stats.mean, stats.ci_lo, stats.ci_hi
    box = _ensemble(np.where(reached, o["D_box_cluster"][k], np.nan))
    o["D_box"][k], o["D_box_ci_lo"][k], o["D_box_ci_hi"][k] = box.mean, box.ci_lo, box.ci_hi
    if reached.any():
        o["D_box_ok_fraction"][k] = o["D_box_cluster_ok"][k][reached].mean()
    o["D_seed_std"][k] = ensemble(np.where(reached, o["D_cluster"][k], np.nan)).std
    use = reached & np.isfinite(curves).all(axis=1)
    o["D_seeds"][k] = use.sum()
    fit, o["D_ci_lo"][k], o["D_ci_hi"][k], o["D_ci_reason"][k] = _headline(curves[use], counts, _stream("D", n),
                                                                          resamples)
    o["D"][k], o["D_drift"][k], o["D_ok"][k], o["D_reason"][k] = fit.D, fit.drift, fit.ok, fit.reason
    o["D_range_lo"][k], o["D_range_hi"][k] = fit.range_lo, fit.range_hi


def _headline(curves, counts, rng, resamples):
    """The ensemble fit of ``counts`` against the mean of ``curves`` (a row per cluster), its 95% CI, and why none."""
    if len(curves) == 0:
        reason = "no stored cluster reached this count"
        return Fit(*[np.nan] * 6, 0, np.nan, False, reason), np.nan, np.nan, reason
    fit = fit_mass_radius(curves.mean(axis=0), counts)
    if not np.isfinite(fit.D):
        return fit, np.nan, np.nan, "no D to give an interval to"
    if len(curves) < MIN_CI_SEEDS:
        return fit, np.nan, np.nan, too_few(len(curves))
    window = (counts >= fit.range_lo) & (counts <= fit.range_hi)
    slopes = _slopes(np.log(bootstrap_means(curves[:, window], rng, resamples)), np.log(counts[window]))
    ci_lo, ci_hi = seed_interval(fit.D, slopes, len(curves))
    return fit, ci_lo, ci_hi, ""


def too_few(n) -> str:
    """Why a statistic over ``n`` clusters has no interval (``MIN_CI_SEEDS``)."""
    return (f"{n} cluster{'s' * (n != 1)} reached N, fewer than the {MIN_CI_SEEDS} a {LEVEL} CI needs "
            "(over fewer, the spread over seeds is too poorly known)")


def _ensemble(values):
    """``fit.ensemble`` of the finite values, its interval NaN below ``MIN_CI_SEEDS`` of them."""
    stats = ensemble(values)
    return stats if stats.n >= MIN_CI_SEEDS else replace(stats, ci_lo=np.nan, ci_hi=np.nan)


def headline(ds, *, resamples: int = RESAMPLES) -> xr.Dataset:
    """The headline D at the largest count and its 95% CI, per configuration: what a precision target watches.

    The same numbers as ``summarise(ds)`` at the largest count, without the
    per-cluster fits and the rest of the summary.

    Returns
    -------
    xarray.Dataset
        ``D``, ``D_ci_lo``, ``D_ci_hi`` on the configuration dims; the CI is
        NaN below ``MIN_CI_SEEDS`` clusters.
    """
    sweep = _Sweep(ds)
    n = int(sweep.counts[-1])
    counts = mass_radius_counts(n)
    out = {name: np.full(sweep.shape, np.nan) for name in ("D", "D_ci_lo", "D_ci_hi")}
    for config in np.ndindex(*sweep.shape):
        reached = ds["n_grown"][{**dict(zip(sweep.config_dims, config)), "n_particles": -1}].values == n
        curves = sweep.curves(config)[reached][:, np.searchsorted(sweep.growth, counts)]
        fit, out["D_ci_lo"][config], out["D_ci_hi"][config], _ = _headline(
            curves[np.isfinite(curves).all(axis=1)], counts, _stream("D", n), resamples)
        out["D"][config] = fit.D
    coords = {d: ds[d].values for d in sweep.config_dims}
    return xr.Dataset({name: (sweep.config_dims, values, {"long_name": SUMMARY[name].long_name})
                       for name, values in out.items()},
                      coords=coords)


def _stream(statistic, n):
    """The bootstrap stream of one statistic at count ``n``."""
    return np.random.default_rng([sum(map(ord, statistic)), int(n)])


def _local(sweep, config, curves, out, resamples):
    """Local slopes of the ensemble curve with their band, and the extrapolation D_inf."""
    o = {name: values[(*config, ...)] for name, values in out.items()}
    if len(curves) == 0 or len(sweep.octaves) == 0:
        o["D_inf_reason"][()] = (f"the largest count spans no octave above {MIN_COUNT}" if len(curves)
                                 else "no cluster reached the largest count")
        return
    o["rg_history"][:] = curves.mean(axis=0)
    log_n = np.log(sweep.history)
    mean = np.log(curves.mean(axis=0))
    local = np.array([_slopes(mean[None, w], log_n[w])[0] for w in sweep.octaves])
    o["D_local"][:] = local
    if len(curves) < MIN_CI_SEEDS:
        o["D_inf_reason"][()] = too_few(len(curves))
        return
    boot = np.log(bootstrap_means(curves, _stream("D_local", sweep.counts[-1]), resamples))
    band = np.array([_slopes(boot[:, w], log_n[w]) for w in sweep.octaves])
    o["D_local_ci_lo"][:], o["D_local_ci_hi"][:] = seed_interval(local, band, len(curves), axis=1)
    for name, value in extrapolate(sweep.centres, local, band, len(curves)).items():
        o[name][()] = value


def _slopes(log_rg, log_n):
    """Least-squares slope of log_n on each row of log_rg."""
    x = log_rg - log_rg.mean(axis=-1, keepdims=True)
    return (x * (log_n - log_n.mean())).sum(axis=-1) / (x * x).sum(axis=-1)
