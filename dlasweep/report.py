"""Report of a sweep: a summary table, plots and a short write-up.

Reads the dataset described in DESIGN.md, fits every cluster at every count
with both estimators (box counting on the stored curve, mass-radius on the
cluster's own growth history), summarises them over seeds and writes
``summary.csv``, ``summary.md``, PNG plots and ``report.md`` into one folder.
Plots the dataset has no data for are skipped, never drawn empty.
"""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np

from .fit import ensemble, fit_dimension, fit_mass_radius
from .measure import radius_of_gyration

REFERENCE_D = {2: 1.7100, 3: 2.50}
"""D of DLA: 2D off-lattice 1.7100(3); 3D about 2.50."""

EXACT_METHOD = {"kill_factor": 0.0, "jumps": True, "step": 0.0, "size": 0}
"""The exact variant of every approximation a sweep can switch on."""

FAILURE_AXES = ("kill_factor", "step", "size", "stickiness")
"""Parameters whose extremes are expected to break the model or the measurement."""

ESTIMATORS = (("mr", "mass-radius (Rg over growth)"), ("box", "box counting"))

_MAX_PANELS = 12


def report(ds, outdir) -> list:
    """Write the report of a sweep into ``outdir``.

    Parameters
    ----------
    ds : xarray.Dataset
        A sweep, as from ``run_sweep`` or ``open_sweep``.
    outdir : str or Path
        Created when missing.

    Returns
    -------
    list of Path
        Every file written: ``summary.csv``, ``summary.md``, the plots that
        the dataset has data for, and ``report.md``.
    """
    out = Path(outdir)
    out.mkdir(parents=True, exist_ok=True)
    sweep = _Sweep(ds)
    written = [_write_csv(sweep, out / "summary.csv"), _write_table(sweep, out / "summary.md")]
    figures = {}
    for name, draw in _PLOTS.items():
        caption = draw(sweep, out / f"{name}.png")
        if caption:
            figures[name] = caption
            written.append(out / f"{name}.png")
    written.append(_write_report(sweep, figures, out / "report.md"))
    return written


class _Sweep:
    """The dataset with every cluster fitted and every configuration summarised."""

    def __init__(self, ds):
        self.ds = ds
        dims = ds["n_grown"].dims
        self.params = [d for d in dims if d not in ("size", "n_particles", "seed")]
        self.config_dims = [*self.params, "size"]
        self.counts = ds["n_particles"].values
        self.n_grown = ds["n_grown"].values
        self.status = ds["status"].values
        self.status_names = str(ds["status"].attrs.get("flag_meanings", "ok boundary step_limit exhausted error")).split()
        self.dim = int(ds["dim"].max()) if "dim" in ds else 2
        self.lattice = bool((ds["model"] == "lattice").all()) if "model" in ds else True
        self.configs = list(np.ndindex(*(ds.sizes[d] for d in self.config_dims)))
        self._fit_box()
        self._fit_mass_radius()
        self.summary = {(c, k): self._summarise(c, k) for c in self.configs for k in range(len(self.counts))}

    def label(self, config, dims=None) -> str:
        """``name=value`` for the swept parameters and the box size of a configuration."""
        parts = []
        for name, i in zip(self.config_dims, config):
            if dims is not None and name not in dims:
                continue
            value = self.ds[name].values[i]
            if name == "size":
                if self.ds.sizes["size"] > 1 or value:
                    parts.append("unbounded" if value == 0 else f"L={value}")
            else:
                parts.append(f"{name}={_plain(value)}")
        return ", ".join(parts) or "all clusters"

    def _fit_box(self):
        scales = self.ds["scale"].values
        box = self.ds["box_count"].values
        shape = self.n_grown.shape
        self.box = {key: np.full(shape, np.nan) for key in ("D", "stderr", "lo", "hi")}
        self.box["ok"] = np.zeros(shape, bool)
        self.fits = {}
        for index in np.ndindex(*shape):
            if self.n_grown[index] < 1:
                continue
            fit = fit_dimension(scales, box[index])
            self.fits[index] = fit
            for key in ("D", "stderr", "lo", "hi"):
                self.box[key][index] = getattr(fit, key)
            self.box["ok"][index] = fit.ok

    def _fit_mass_radius(self):
        """Fit each stored cluster's Rg history up to every count."""
        ds = self.ds
        shape = self.n_grown.shape
        self.mr = {"D": np.full(shape, np.nan), "ok": np.zeros(shape, bool)}
        lookup = {d: {_key(v): i for i, v in enumerate(ds[d].values)} for d in (*self.config_dims, "seed")}
        self.cluster_of = {}
        offsets = np.r_[0, np.cumsum(ds["cluster_particles"].values)]
        self.depth, self.times = {}, {}
        for i in range(ds.sizes["cluster"]):
            where = tuple(lookup[d][_key(ds[f"cluster_{d}"].values[i])] for d in (*self.config_dims, "seed"))
            config, seed = where[:-1], where[-1]
            self.cluster_of[config, seed] = i
            if ds["cluster_particles"].values[i] < 1:
                continue
            points = _cluster_points(ds, i)
            rg = radius_of_gyration(points)
            for k in range(len(self.counts)):
                index = (*config, k, seed)
                m = int(self.n_grown[index])
                if m >= 1:
                    fit = fit_mass_radius(np.arange(1, m + 1), rg[:m])
                    self.mr["D"][index], self.mr["ok"][index] = fit.D, fit.ok
            distance = np.sqrt(((points - points[0]) ** 2).sum(axis=1))
            self.depth[config, seed] = distance / max(distance.max(), 1.0)
            self.times[config, seed] = ds["diffusion_time"].values[offsets[i]:offsets[i + 1]]

    def _summarise(self, config, k) -> dict:
        at = (*config, k)
        statuses = self.status[at]
        codes, tally = np.unique(statuses, return_counts=True)
        row = {name: _plain(self.ds[name].values[i]) for name, i in zip(self.config_dims, config)}
        grown = self.n_grown[at]
        alive = grown > 0
        row.update(
            n_particles=int(self.counts[k]),
            seeds=len(statuses),
            status=" ".join(f"{self.status_names[c]}:{t}" for c, t in zip(codes, tally)),
            flagged=bool((statuses != 0).any()),
            n_grown_mean=float(grown.mean()),
        )
        for prefix, fits in (("D_mr", self.mr), ("D_box", self.box)):
            stats = ensemble(np.where(fits["ok"][at], fits["D"][at], np.nan))
            row.update({f"{prefix}_{key}": getattr(stats, key) for key in ("mean", "std", "stderr", "ci_lo", "ci_hi")})
            row[f"{prefix}_ok"] = int(stats.n)
        for name in ("radius_gyration", "max_radius"):
            stats = ensemble(self.ds[name].values[at][alive])
            row[f"{name}_mean"], row[f"{name}_stderr"] = stats.mean, stats.stderr
        with np.errstate(invalid="ignore", divide="ignore"):
            row["seconds_per_particle"] = float(np.nanmean(self.ds["wall_time"].values[at][alive] / grown[alive])) if alive.any() else np.nan
            row["steps_per_particle"] = float(np.mean(self.ds["walk_steps"].values[at][alive] / grown[alive])) if alive.any() else np.nan
        return row


def _cluster_points(ds, i):
    from .store import cluster_points  # here, so `import dlasweep` skips xarray until a sweep is read

    return cluster_points(ds, i)


def _key(value):
    """A hashable, type-stable form of a coordinate value (bools and numpy scalars)."""
    return value.item() if hasattr(value, "item") else value


def _plain(value):
    value = _key(value)
    return value.decode() if isinstance(value, bytes) else value


# Tables -------------------------------------------------------------------

def _write_csv(sweep, path) -> Path:
    rows = list(sweep.summary.values())
    with open(path, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    return path


def _estimate(row, prefix) -> str:
    if row[f"{prefix}_ok"] == 0:
        return f"no ok fit (0/{row['seeds']})"
    text = f"{row[f'{prefix}_mean']:.3f}"
    if row[f"{prefix}_ok"] > 1:
        text += f" ± {row[f'{prefix}_stderr']:.3f} [{row[f'{prefix}_ci_lo']:.3f}, {row[f'{prefix}_ci_hi']:.3f}]"
    return f"{text} ({row[f'{prefix}_ok']}/{row['seeds']})"


def _markdown_table(sweep) -> str:
    head = [*sweep.config_dims, "N", "status", "D mass-radius", "D box counting", "std (mr, box)", "Rg", "s/particle"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for row in sweep.summary.values():
        cells = [str(row[d]) for d in sweep.config_dims] + [
            str(row["n_particles"]),
            row["status"] + (" ⚠" if row["flagged"] else ""),
            _estimate(row, "D_mr"),
            _estimate(row, "D_box"),
            f"{row['D_mr_std']:.3f}, {row['D_box_std']:.3f}",
            f"{row['radius_gyration_mean']:.1f}",
            f"{row['seconds_per_particle']:.2e}",
        ]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def _write_table(sweep, path) -> Path:
    path.write_text(
        "D: mean ± standard error over seeds [bootstrap 95% CI] (fits that passed / seeds).\n"
        "Only fits that passed their checks enter the statistics; ⚠: some cluster stopped early.\n\n"
        + _markdown_table(sweep)
    )
    return path


# Plots --------------------------------------------------------------------

def _figure(n_panels=1, width=4.0, height=3.4):
    """A grid of panels on a Figure of its own (no pyplot state, no backend switch)."""
    from matplotlib.figure import Figure  # here, so `import dlasweep` (and dask workers) skip matplotlib

    cols = min(n_panels, 4)
    rows = -(-n_panels // cols)
    fig = Figure(figsize=(width * cols, height * rows), layout="constrained")
    axes = fig.subplots(rows, cols, squeeze=False).ravel()
    for ax in axes[n_panels:]:
        ax.set_visible(False)
    return fig, axes[:n_panels]


def _save(fig, path):
    fig.savefig(path, dpi=110)


def _colour(i):
    from matplotlib import colormaps

    return colormaps["tab10"](i % 10)


def _mark_missing(ax, xs, ys):
    """A red cross on the bottom edge for every x whose y is missing: nothing silently vanishes."""
    xs, lost = np.asarray(xs, float), ~np.isfinite(np.asarray(ys, float))
    if lost.any():
        ax.scatter(xs[lost], np.full(lost.sum(), 0.03), transform=ax.get_xaxis_transform(),
                   marker="x", color="C3", s=40, zorder=3)
        ax.dataLim.update_from_data_x(xs[lost], ignore=False)
        ax.autoscale_view()


def _log_x(ax):
    ax.set_xscale("log")
    # A narrow log range otherwise labels its minor ticks on top of each other.
    ax.tick_params(axis="x", which="minor", labelbottom=False)


def _draw_points(ax, points, lattice, inches, rasterized=True):
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
    fig, (ax,) = _figure(1, 6.0, 6.0)
    _draw_points(ax, np.asarray(points, float), params.get("model", "lattice") == "lattice", 5.6,
                 rasterized=path.suffix.lower() != ".svg")
    projected = ", projected on x-y" if params.get("dim", 2) == 3 else ""
    ax.set_title(f"{params.get('model', 'lattice')} DLA, N={len(points)}{projected}", fontsize=9)
    _save(fig, path)
    return path


def _gallery(sweep, path):
    shown = [c for c in sweep.configs if (c, 0) in sweep.cluster_of][:_MAX_PANELS]
    if not shown:
        return None
    fig, axes = _figure(len(shown), 3.4, 3.4)
    for ax, config in zip(axes, shown):
        points = _cluster_points(sweep.ds, sweep.cluster_of[config, 0])
        status = sweep.status_names[sweep.status[(*config, len(sweep.counts) - 1, 0)]]
        ax.set_title(f"{sweep.label(config)}\nN={len(points)}, {status}", fontsize=8)
        if len(points):
            _draw_points(ax, points.astype(float), sweep.lattice, 3.0)
        else:
            ax.set_axis_off()
    fig.suptitle("Clusters (seed 0), coloured by attachment order (dark: early)"
                 + (", projected on x-y" if sweep.dim == 3 else ""))
    _save(fig, path)
    extra = f" (first {_MAX_PANELS} of {len(sweep.configs)} configurations)" if len(sweep.configs) > _MAX_PANELS else ""
    return f"One cluster per configuration at its largest count{extra}, coloured by attachment order."


def _box_counts(sweep, path):
    scales = sweep.ds["scale"].values
    box = sweep.ds["box_count"].values
    last = len(sweep.counts) - 1
    shown = sweep.configs[:_MAX_PANELS]
    fig, axes = _figure(len(shown))
    # Past the largest cluster every count is 1: nothing to see there.
    visible = scales <= 2 * scales[min(np.argmax(box.max(axis=tuple(range(box.ndim - 1))) <= 1), len(scales) - 1)]
    for ax, config in zip(axes, shown):
        index = (*config, last, 0)
        for seed in range(sweep.ds.sizes["seed"]):
            ax.loglog(scales[visible], box[(*config, last, seed)][visible], color="0.75", lw=0.7)
        fit = sweep.fits.get(index)
        ax.loglog(scales[visible], box[index][visible], "o", ms=2.5, color="C0", label="seed 0")
        ax.minorticks_off()
        if fit is not None and np.isfinite(fit.D):
            span = (scales >= fit.lo) & (scales <= fit.hi)
            x = scales[span]
            anchor = np.exp(np.mean(np.log(box[index][span]) + fit.D * np.log(x)))
            ax.loglog(x, anchor * x ** -fit.D, color="C3" if fit.ok else "C1", lw=1.5,
                      label=f"D={fit.D:.3f}±{fit.stderr:.3f}" + ("" if fit.ok else " (not ok)"))
            ax.axvspan(fit.lo, fit.hi, color="C2", alpha=0.1, lw=0)
        ax.set_title(sweep.label(config), fontsize=8)
        ax.set_xlabel("box side s")
        ax.set_ylabel("boxes N(s)")
        ax.legend(fontsize=7)
    fig.suptitle(f"Box counts at N={sweep.counts[last]} (grey: all seeds; shaded: fitted range)")
    _save(fig, path)
    return ("Box counts N(s) at the largest count, every seed in grey, seed 0 with the fitted line over the "
            "range the fit chose (shaded; orange when the fit did not pass its checks).")


def _local_slopes(sweep, path):
    scales = sweep.ds["scale"].values
    if len(scales) < 3:
        return None
    box = sweep.ds["box_count"].values.astype(float)
    last = len(sweep.counts) - 1
    mid = np.sqrt(scales[1:] * scales[:-1])
    fig, (ax,) = _figure(1, 6.5, 4.2)
    for c, config in enumerate(sweep.configs[:10]):
        curves = box[(*config, last)]
        with np.errstate(divide="ignore", invalid="ignore"):
            slopes = -np.diff(np.log(curves), axis=-1) / np.diff(np.log(scales))
        below = np.nanmax(sweep.box["hi"][(*config, last)]) if np.isfinite(sweep.box["hi"][(*config, last)]).any() else scales[-1]
        keep = mid <= 2 * below
        mean, spread = np.nanmean(slopes, axis=0)[keep], np.nanstd(slopes, axis=0)[keep]
        ax.semilogx(mid[keep], mean, color=_colour(c), label=sweep.label(config))
        ax.fill_between(mid[keep], mean - spread, mean + spread, color=_colour(c), alpha=0.15, lw=0)
    ax.axhline(REFERENCE_D.get(sweep.dim, np.nan), color="k", ls="--", lw=1, label=f"reference {REFERENCE_D.get(sweep.dim)}")
    ax.axvline(2, color="0.5", ls=":", lw=1)
    ax.set_xlabel("box side s")
    ax.set_ylabel("local slope  -d ln N / d ln s")
    ax.set_title(f"Local box-counting slopes at N={sweep.counts[last]} (mean ± std over seeds)")
    ax.legend(fontsize=7)
    _save(fig, path)
    return ("Local slopes of the box counts against scale: a plateau would be a clean power law. Below s=2 "
            "(dotted) the particle shape dominates; towards the cluster size the slope falls.")


def _dimension_vs_n(sweep, path):
    means = [sweep.summary[config, k][f"D_{prefix}_mean"] for config in sweep.configs[:10]
             for k in range(len(sweep.counts)) for prefix, _ in ESTIMATORS]
    if not np.isfinite(means).any():
        return None  # no fit passed its checks: nothing to draw
    fig, (ax,) = _figure(1, 6.5, 4.2)
    for c, config in enumerate(sweep.configs[:10]):
        for e, (prefix, name) in enumerate(ESTIMATORS):
            rows = [sweep.summary[config, k] for k in range(len(sweep.counts))]
            mean = np.array([r[f"D_{prefix}_mean"] for r in rows])
            low = mean - np.array([r[f"D_{prefix}_ci_lo"] for r in rows])
            high = np.array([r[f"D_{prefix}_ci_hi"] for r in rows]) - mean
            x = sweep.counts * (1.04 if e else 1.0)
            ax.errorbar(x, mean, yerr=[np.nan_to_num(low), np.nan_to_num(high)], color=_colour(c),
                        marker="os"[e], mfc="none" if e else _colour(c), ls="-:"[e], capsize=2,
                        label=f"{name}, {sweep.label(config)}")
    ax.axhline(REFERENCE_D.get(sweep.dim, np.nan), color="k", ls="--", lw=1, label="reference")
    _log_x(ax)
    ax.set_xlabel("particles N")
    ax.set_ylabel("D (mean over seeds, 95% CI)")
    ax.set_title("Fractal dimension against cluster size")
    ax.legend(fontsize=6)
    _save(fig, path)
    return ("D against N for both estimators (filled/solid: mass-radius; open/dotted: box counting), mean over "
            "seeds with bootstrap 95% intervals; the dashed line is the reference value.")


def _dimension_spread(sweep, path):
    last = len(sweep.counts) - 1
    shown = sweep.configs[:20]
    fig, (ax,) = _figure(1, max(5.0, 0.6 * len(shown) + 2), 4.2)
    for c, config in enumerate(shown):
        for e, (prefix, name) in enumerate(ESTIMATORS):
            fits = sweep.mr if prefix == "mr" else sweep.box
            values, ok = fits["D"][(*config, last)], fits["ok"][(*config, last)]
            x = c + (0.2 if e else -0.2) + np.linspace(-0.06, 0.06, len(values))
            ax.scatter(x[ok], values[ok], s=12, marker="os"[e], color=f"C{e}", label=name if c == 0 else None)
            ax.scatter(x[~ok], values[~ok], s=14, marker="x", color="C3", label="fit not ok" if c == 0 and e == 0 else None)
            row = sweep.summary[config, last]
            ax.errorbar(c + (0.2 if e else -0.2), row[f"D_{prefix}_mean"], yerr=row[f"D_{prefix}_std"], color="k", capsize=3)
    ax.axhline(REFERENCE_D.get(sweep.dim, np.nan), color="k", ls="--", lw=1)
    ax.set_xticks(range(len(shown)), [sweep.label(c) for c in shown], rotation=30, ha="right", fontsize=7)
    ax.set_ylabel("D per seed (bars: mean ± std)")
    ax.set_title(f"Spread of D over seeds at N={sweep.counts[last]}")
    ax.legend(fontsize=7)
    _save(fig, path)
    return "D of every seed at the largest count, both estimators; red crosses are fits that did not pass their checks."


def _diffusion_times(sweep, path):
    if not sweep.times:
        return None
    fig, (hist, depth) = _figure(2, 5.0, 3.8)
    bins = np.linspace(0, 1, 11)
    for c, config in enumerate(sweep.configs[:10]):
        seeds = [s for s in range(sweep.ds.sizes["seed"]) if (config, s) in sweep.times]
        if not seeds:
            continue
        times = np.concatenate([sweep.times[config, s][1:] for s in seeds]).astype(float)
        where = np.concatenate([sweep.depth[config, s][1:] for s in seeds])
        if len(times) == 0:
            continue
        # Half-integer edges: times are whole steps, and log bins narrower than one step alias.
        edges = np.unique(np.round(np.logspace(0, np.log10(max(times.max(), 10.0)), 40))) + 0.5
        hist.hist(times, bins=np.r_[0.5, edges], histtype="step", density=True, color=_colour(c), label=sweep.label(config))
        slot = np.clip(np.digitize(where, bins) - 1, 0, len(bins) - 2)
        median = [np.median(times[slot == b]) if (slot == b).any() else np.nan for b in range(len(bins) - 1)]
        depth.semilogy(0.5 * (bins[1:] + bins[:-1]), median, "o-", ms=3, color=_colour(c))
    hist.set_xscale("log")
    hist.set_yscale("log")
    hist.set_xlabel("diffusion time (walk steps or jumps to stick)")
    hist.set_ylabel("density")
    hist.legend(fontsize=6)
    depth.set_xlabel("distance from seed / cluster radius")
    depth.set_ylabel("median diffusion time")
    fig.suptitle("Diffusion times, pooled over seeds")
    _save(fig, path)
    return ("Distribution of diffusion times (left) and their median against the depth at which the particle "
            "stuck, as a fraction of the cluster's radius (right).")


def _method_axes(sweep):
    return [a for a in EXACT_METHOD if a in sweep.config_dims and sweep.ds.sizes[a] > 1]


def _reference_of(sweep, config, methods):
    """The configuration with every method axis at its exact value, or None when not swept."""
    reference = list(config)
    for name in methods:
        exact = [i for i, v in enumerate(sweep.ds[name].values) if _key(v) == EXACT_METHOD[name]]
        if not exact:
            return None
        reference[sweep.config_dims.index(name)] = exact[0]
    return tuple(reference)


def _speed_accuracy(sweep, path):
    methods = _method_axes(sweep)
    last = len(sweep.counts) - 1
    pairs = [(c, _reference_of(sweep, c, methods)) for c in sweep.configs]
    pairs = [(c, r) for c, r in pairs if r is not None]
    if not methods or all(c == r for c, r in pairs):
        return None
    fig, (dev_d, dev_rg) = _figure(2, 5.5, 4.2)
    groups = {r: g for g, r in enumerate(dict.fromkeys(r for _, r in pairs))}
    for config, ref in pairs:
        row, base = sweep.summary[config, last], sweep.summary[ref, last]
        cost = row["seconds_per_particle"]
        delta = row["D_mr_mean"] - base["D_mr_mean"]
        delta_err = np.hypot(row["D_mr_stderr"], base["D_mr_stderr"])
        ratio = row["radius_gyration_mean"] / base["radius_gyration_mean"] - 1
        ratio_err = (1 + ratio) * np.hypot(row["radius_gyration_stderr"] / row["radius_gyration_mean"],
                                          base["radius_gyration_stderr"] / base["radius_gyration_mean"])
        style = dict(color=_colour(groups[ref]), marker="*" if config == ref else "o", ms=9 if config == ref else 5,
                     mec="C3" if row["flagged"] else None, capsize=2)
        text = sweep.label(config, methods)
        for ax, y, err in ((dev_d, delta, delta_err), (dev_rg, ratio, ratio_err)):
            if np.isfinite(y):
                ax.errorbar(cost, y, yerr=np.nan_to_num(err), **style)
                ax.annotate(text, (cost, y), fontsize=6, xytext=(3, 3), textcoords="offset points")
            else:
                _mark_missing(ax, [cost], [y])
    for ax, label in ((dev_d, "D(variant) - D(exact), mass-radius"), (dev_rg, "Rg(variant) / Rg(exact) - 1 at equal N")):
        ax.axhline(0, color="k", lw=0.8)
        _log_x(ax)
        ax.set_xlabel("wall time per particle (s)")
        ax.set_ylabel(label)
    fig.suptitle(f"Speed against accuracy at N={sweep.counts[last]} "
                 "(stars: exact method; red edge: flagged; red x: no value)")
    _save(fig, path)
    return ("Cost per particle against the deviation from the exact method (" + ", ".join(
        f"{m}={EXACT_METHOD[m]}" for m in methods) + ") with the other parameters equal, at the largest count; "
        "error bars combine the standard errors of both ensembles.")


def _failure(sweep, path):
    axes_present = [a for a in FAILURE_AXES if a in sweep.config_dims and sweep.ds.sizes[a] > 1]
    if not axes_present:
        return None
    last = len(sweep.counts) - 1
    fig, panels = _figure(2 * len(axes_present), 4.2, 3.4)
    for p, axis in enumerate(axes_present):
        top, bottom = panels[2 * p], panels[2 * p + 1]
        others = [d for d in sweep.config_dims if d != axis]
        series = {}
        for config in sweep.configs:
            series.setdefault(tuple(config[sweep.config_dims.index(d)] for d in others), []).append(config)
        for s, members in enumerate(series.values()):
            xs, rows = [], []
            for config in members:
                row = sweep.summary[config, last]
                x = float(row[axis])
                if axis == "size":
                    if x == 0:
                        top.axhline(row["D_mr_mean"], color=_colour(s), ls=":", lw=1)
                        continue
                    x /= max(row["max_radius_mean"], 1e-9)
                xs.append(x)
                rows.append(row)
            if not rows:
                continue
            xs = np.array(xs)
            order = np.argsort(xs)
            xs, rows = xs[order], [rows[i] for i in order]
            label = sweep.label(members[0], others) if others else None
            for ax, key, marker in ((top, "D_mr", "o"), (top, "D_box", "s"), (bottom, None, "o")):
                if key:
                    y = np.array([r[f"{key}_mean"] for r in rows])
                    err = np.array([r[f"{key}_stderr"] for r in rows])
                else:
                    y = np.array([r["radius_gyration_mean"] / r["max_radius_mean"] for r in rows])
                    err = np.zeros_like(y)
                ax.errorbar(xs, y, yerr=np.nan_to_num(err), color=_colour(s), marker=marker,
                            mfc="none" if key == "D_box" else _colour(s), capsize=2,
                            label=(f"{'box' if key == 'D_box' else 'mass-radius'}, {label}" if key else label))
                flagged = np.array([r["flagged"] or (key and r[f"{key}_ok"] < r["seeds"]) for r in rows], bool)
                ax.scatter(xs[flagged], y[flagged], s=80, facecolors="none", edgecolors="C3", lw=1.2, zorder=3)
                _mark_missing(ax, xs, y)
        xlabel = "box side / cluster radius" if axis == "size" else axis
        for ax in (top, bottom):
            ax.set_xlabel(xlabel)
            # kill_factor and step keep a linear axis: their exact value is 0
            if axis == "size" and (np.asarray(sweep.ds[axis].values, float) > 0).sum() > 1:
                _log_x(ax)
        top.axhline(REFERENCE_D.get(sweep.dim, np.nan), color="k", ls="--", lw=1)
        top.set_ylabel("D (mean ± stderr)")
        top.legend(fontsize=6)
        bottom.set_ylabel("Rg / R_max")
    fig.suptitle(f"Where methods fail, at N={sweep.counts[last]} (red rings: flagged; red x: no value)")
    _save(fig, path)
    return ("D and Rg/R_max against the parameters that break the model or its measurement ("
            + ", ".join(axes_present) + "). Red rings mark configurations where a cluster stopped early or a fit "
            "did not pass; red crosses at the bottom mark configurations with no value at all.")


_PLOTS = {
    "gallery": _gallery,
    "box_counts": _box_counts,
    "local_slopes": _local_slopes,
    "dimension_vs_n": _dimension_vs_n,
    "dimension_spread": _dimension_spread,
    "diffusion_times": _diffusion_times,
    "speed_accuracy": _speed_accuracy,
    "failure": _failure,
}
"""Every plot: name -> function(sweep, path) returning a caption, or None when skipped."""


# The write-up -------------------------------------------------------------

def _write_report(sweep, figures, path) -> Path:
    ds = sweep.ds
    last = len(sweep.counts) - 1
    reference = REFERENCE_D.get(sweep.dim)
    best = [(sweep.label(c), sweep.summary[c, last]) for c in sweep.configs]
    lines = [
        f"# {ds.attrs.get('title', 'dlasweep sweep')}",
        "",
        f"{ds.sizes['cluster']} clusters; counts {', '.join(map(str, sweep.counts))}; "
        f"{ds.sizes['seed']} seeds per configuration; root seed {ds.attrs.get('root_seed')}; "
        f"{ds.attrs.get('source', 'dlasweep')}.",
        "",
        "## Result",
        "",
        f"D from the radius of gyration over each cluster's growth history, mean over seeds at N = {sweep.counts[last]} "
        "(± standard error, bootstrap 95% interval, fits that passed / seeds):",
        "",
        *[f"- {label}: {_estimate(row, 'D_mr')}; box counting {_estimate(row, 'D_box')}" for label, row in best],
        "",
        f"Reference: 2D off-lattice DLA D = 1.7100(3); 3D DLA about 2.50 (this sweep: {sweep.dim}D, "
        f"reference {reference}).",
        "",
        "## How D is measured, and how far to trust it",
        "",
        "- **Mass-radius** (the estimator to quote): N ~ Rg^D fitted over the cluster's own growth history, "
        "leaving out the first 5% of the particles (and at least 50), on the longest straight window of at "
        "least one decade of N. Averaged over seeds it is the better estimator: its spread over seeds is the "
        "honest error bar, and the standard error of the mean shrinks as 1/sqrt(seeds).",
        "- **Box counting** on one finite cluster reads low: boxes at the edge of the cluster are partly empty, "
        "and between the particle size (s >= 2 used) and a quarter of the cluster's extent there is little "
        "more than a decade. The fit picks the longest straight window and says when there is none.",
        "- A fit's own standard error measures the scatter about its line, not the spread over seeds; the "
        "table's errors are over seeds. Fits that do not pass their checks (too short a range, curvature, poor "
        "line) are left out of the statistics and counted in the table.",
        "",
        "## Summary table",
        "",
        "(Also in `summary.csv` with every column; ⚠ marks a configuration where a cluster stopped early.)",
        "",
        _markdown_table(sweep),
        "## Figures",
        "",
    ]
    for name, caption in figures.items():
        lines += [f"### {name.replace('_', ' ').capitalize()}", "", f"![{name}]({name}.png)", "", caption, ""]
    lines += ["## Spec", "", "```toml", str(ds.attrs.get("spec", "")).strip(), "```", ""]
    source = ds.encoding.get("source")
    if source:
        lines += ["Reproduce this report with", "", f"    dlasweep report {source} -o {path.parent}", ""]
    path.write_text("\n".join(lines))
    return path


# Benchmark ----------------------------------------------------------------

def plot_bench(ds, outdir) -> Path:
    """Draw kernel time against N, log-log, one line per model, to ``bench.png``.

    Parameters
    ----------
    ds : xarray.Dataset
        As from ``dlasweep.bench.run_bench``: dimension ``run``, coordinates
        ``model``, ``method`` (``exact`` or ``naive``) and ``n``, variable
        ``seconds``, attributes ``cost_exponent_<model>``.
    outdir : str or Path
        Created when missing.

    Returns
    -------
    Path
        The PNG written.
    """
    out = Path(outdir)
    out.mkdir(parents=True, exist_ok=True)
    model = np.array([str(_plain(v)) for v in ds["model"].values])
    method = np.array([str(_plain(v)) for v in ds["method"].values])
    n, seconds = ds["n"].values.astype(float), ds["seconds"].values.astype(float)
    fig, (ax,) = _figure(1, 6.5, 4.5)
    for c, name in enumerate(dict.fromkeys(model)):
        exponent = ds.attrs.get(f"cost_exponent_{name}")
        fitted = f", time $\\propto N^{{{exponent:.2f}}}$" if exponent is not None else ""
        for kind, style, label in (
            ("exact", dict(marker="o", ls="-"), name + fitted),
            ("naive", dict(marker="x", ls=":", ms=8), f"{name}, naive walk (single steps, kill circle)"),
        ):
            pick = (model == name) & (method == kind)
            if pick.any():
                order = np.argsort(n[pick])
                ax.loglog(n[pick][order], seconds[pick][order], color=_colour(c), label=label, **style)
    ax.set_xlabel("particles N")
    ax.set_ylabel("wall time to grow (s), one core")
    ax.set_title("Kernel time against cluster size")
    ax.legend(fontsize=7)
    path = out / "bench.png"
    _save(fig, path)
    return path
