"""The report's plots: one function per figure, each drawing what ``readout.Readout`` reads and returning its caption.

``PLOTS`` names them in the report's order; a plot the dataset has no data
for returns None and is not drawn.
"""

from __future__ import annotations

import numpy as np

from ..data.ragged import cluster_points
from ..params import EXACT_METHOD, text
from ..stats.constants import LEVEL, MIN_CI_SEEDS
from .branch_report import branching_figure
from .figures import MAX_PANELS, colour_of, log_x, mark_missing, new_figure, save_figure
from .harmonic_report import spectrum_figure
from .pictures import draw_points
from .readout import bias, error_bars, fitted_line, fitted_scales, visible_scales

ESTIMATORS = (("D", "mass-radius, ensemble (headline)"), ("D_box", "box counting, per cluster (reads low)"))


def _gallery(sweep, path):
    shown = [c for c in sweep.configs if sweep.cluster_of(c, 0) is not None][:MAX_PANELS]
    if not shown:
        return None
    fig, axes = new_figure(len(shown), 3.4, 3.4)
    last = len(sweep.counts) - 1
    for ax, config in zip(axes, shown):
        points = cluster_points(sweep.ds, sweep.cluster_of(config, 0))
        status = sweep.status_of(config, last, 0)
        ax.set_title(f"{sweep.label(config)}\nN={len(points)}, {status}", fontsize=8)
        if len(points):
            draw_points(ax, points, sweep.lattice, 3.0)
        else:
            ax.set_axis_off()
    # Two short lines: a one-panel gallery is only 3.4 inches wide.
    fig.suptitle("Seed 0 of each configuration\ncolour: attachment order (dark: early)"
                 + ("\nx-y view, paler: deeper" if sweep.dim == 3 else ""), fontsize=9)
    save_figure(fig, path)
    extra = f" (first {MAX_PANELS} of {len(sweep.configs)} configurations)" if len(sweep.configs) > MAX_PANELS else ""
    return f"One cluster per configuration at its largest count{extra}, coloured by attachment order."


def _box_counts(sweep, path):
    scales = sweep.ds["scale"].values
    last = len(sweep.counts) - 1
    shown = sweep.configs[:MAX_PANELS]
    fig, axes = new_figure(len(shown))
    # Past the largest cluster every count is 1: nothing to see there.
    visible = visible_scales(scales, sweep.ds["box_count"].values)
    for ax, config in zip(axes, shown):
        where = {**dict(zip(sweep.config_dims, config)), "n_particles": last}
        curves = sweep.ds["box_count"][where].values
        for seed in range(len(curves)):
            ax.loglog(scales[visible], curves[seed][visible], color="0.75", lw=0.7)
        ax.loglog(scales[visible], curves[0][visible], "o", ms=2.5, color="C0", label="seed 0")
        ax.minorticks_off()
        D = sweep.at("D_box_cluster", config, n_particles=last, seed=0)
        lo, hi = (sweep.at(f"D_box_range_{e}", config, n_particles=last, seed=0) for e in ("lo", "hi"))
        if np.isfinite(D):
            ok = bool(sweep.at("D_box_cluster_ok", config, n_particles=last, seed=0))
            span = (scales >= lo) & (scales <= hi)
            x = scales[span]
            ax.loglog(x, fitted_line(x, curves[0][span], -D), color="C3" if ok else "C1", lw=1.5,
                      label=f"seed 0: D={D:.3f}" + ("" if ok else " (not flat)"))
            ax.axvspan(lo, hi, color="C2", alpha=0.1, lw=0)
        ax.set_title(sweep.label(config), fontsize=8)
        ax.set_xlabel("box side s")
        ax.set_ylabel("boxes N(s)")
        ax.legend(fontsize=7)
    fig.suptitle(f"Box counts at N={sweep.counts[last]}\n(grey: all seeds; shaded: seed 0's fitted range)", fontsize=9)
    save_figure(fig, path)
    return ("Box counts N(s) at the largest count, every seed in grey, seed 0 with the fitted line over the "
            "range the fit chose (shaded; orange when its local slope is not flat). A finite-cluster estimate: "
            "it reads low.")


def _box_local_slopes(sweep, path):
    slope = sweep.s["box_slope"].values
    if slope.shape[-1] == 0 or not np.isfinite(slope).any():
        return None
    mid = sweep.s["scale_mid"].values
    keep = fitted_scales(sweep.s)
    fig, (ax,) = new_figure(1, 6.5, 4.2)
    for c, config in enumerate(sweep.configs[:10]):
        mean, spread = sweep.at("box_slope", config)[keep], sweep.at("box_slope_std", config)[keep]
        ax.plot(mid[keep], mean, color=colour_of(c), label=sweep.label(config))
        ax.fill_between(mid[keep], mean - spread, mean + spread, color=colour_of(c), alpha=0.12, lw=0)
    log_x(ax)
    if sweep.reference:
        ax.axhline(sweep.reference, color="k", ls="--", lw=1, label=f"off-lattice reference {sweep.reference}")
    ax.set_xlabel("box side s")
    ax.set_ylabel("box-counting slope -d ln N / d ln s\n(mean ± std over seeds)")
    ax.set_title(f"Box-counting local slope at N={sweep.counts[-1]}", fontsize=9)
    fig.legend(*ax.get_legend_handles_labels(), loc="outside lower center", fontsize=6, ncols=3)
    save_figure(fig, path)
    extra = f" (first 10 of {len(sweep.configs)} configurations)" if len(sweep.configs) > 10 else ""
    return ("Box counting's local slope -d ln N / d ln s between adjacent box sides, mean ± std over seeds, up to "
            "the largest fitted window" + extra + ": where it is not flat, box counting's D depends on the window "
            "fitted. The headline's (mass-radius) local slope D_eff(n) is in `dimension_vs_n`.")


def _dimension_vs_n(sweep, path):
    if not np.isfinite(sweep.s["D"].values).any():
        return None
    shown = sweep.configs[:MAX_PANELS]
    # Whether any interval is drawn: below MIN_CI_SEEDS clusters there is none, and the words say so.
    bars = bool(np.isfinite(sweep.s["D_ci_lo"].values).any())
    band = bool(np.isfinite(sweep.s["D_local_ci_lo"].values).any())
    inf = [c for c in shown if np.isfinite(sweep.at("D_inf", c))]
    # One y-axis: panels compare by eye.
    fig, axes = new_figure(len(shown), 4.2, 3.4, sharey=True)
    n_local = sweep.s["n_local"].values
    for ax, config in zip(axes, shown):
        if len(n_local):
            ax.fill_between(n_local, sweep.at("D_local_ci_lo", config), sweep.at("D_local_ci_hi", config),
                            color="C0", alpha=0.15, lw=0)
            ax.plot(n_local, sweep.at("D_local", config), color="C0", lw=0.8,
                    label="local slope D_eff(n)" + (f", {LEVEL} band" if band else ""))
        for e, (name, title) in enumerate(ESTIMATORS):
            mean, err = sweep.bars(name, config)
            ax.errorbar(sweep.counts * (1.06 if e else 1.0), mean, yerr=err, color=f"C{3 * e}", marker="os"[e],
                        mfc="none" if e else f"C{3 * e}", ls="none", capsize=2, label=title)
        for n, d, seeds in zip(sweep.counts, sweep.at("D", config), sweep.at("D_seeds", config)):
            if np.isfinite(d):
                ax.annotate(f"{seeds}", (n, d), fontsize=6, xytext=(0, 6), textcoords="offset points", ha="center")
        if config in inf:
            ax.axhspan(sweep.at("D_inf_ci_lo", config), sweep.at("D_inf_ci_hi", config), color="C2", alpha=0.2,
                       lw=0, label=f"D_inf, {LEVEL} CI")
        if sweep.reference:
            ax.axhline(sweep.reference, color="k", ls="--", lw=1, label=f"reference {sweep.reference}")
        log_x(ax)
        ax.set_title(sweep.label(config), fontsize=8)
        ax.set_xlabel("particles N")
        ax.set_ylabel("D")
    fig.legend(*_legend(axes), loc="outside lower center", fontsize=6, ncols=3)
    fig.suptitle("D against cluster size (" + (f"bars: {LEVEL} CI; " if bars else f"no CI: fewer than {MIN_CI_SEEDS} "
                 "clusters; ") + "numbers: clusters in the ensemble)", fontsize=9)
    save_figure(fig, path)
    said = ["the headline ensemble mass-radius D at each N (filled) with the number of clusters in it",
            "the mean box-counting D (open squares, reads low)",
            "the local slope D_eff(n)" + (f" with its {LEVEL} band" if band else "")]
    if inf:
        said.append(f"D_inf with its {LEVEL} CI (green) where the extrapolation holds")
    said.append(f"the dashed line is the {sweep.dim}D off-lattice reference" if sweep.reference
                else "no reference line: the off-lattice value is not the lattice model's")
    ci = (f"Bars are {LEVEL} CIs" if bars else
          f"No interval is drawn: fewer than {MIN_CI_SEEDS} clusters per configuration (see `Intervals`)")
    return "One panel per configuration, on one y-axis: " + "; ".join(said) + ". " + ci + "."


def _legend(axes):
    """Handles and labels of every panel, each label once: a figure-wide legend."""
    seen = {}
    for ax in axes:
        for handle, label in zip(*ax.get_legend_handles_labels()):
            seen.setdefault(label, handle)
    return list(seen.values()), list(seen)


def _mass_radius(sweep, path):
    history = sweep.s["n_history"].values
    shown = [c for c in sweep.configs[:MAX_PANELS] if np.isfinite(sweep.at("rg_history", c)).any()]
    if not shown:
        return None
    fig, axes = new_figure(len(shown), 4.2, 3.4)
    last = len(sweep.counts) - 1
    for ax, config in zip(axes, shown):
        rg = sweep.at("rg_history", config)
        ax.loglog(rg, history, "o", ms=2, color="C0", label="<Rg> over seeds")
        D, lo, hi = (float(sweep.at(name, config, n_particles=last)) for name in ("D", "D_range_lo", "D_range_hi"))
        if np.isfinite(D):
            window = (history >= lo) & (history <= hi)
            ax.loglog(rg[window], fitted_line(rg[window], history[window], D), color="C3", lw=1.5,
                      label=f"N ~ <Rg>^{D:.3f}, fitted window")
            ax.axhspan(lo, hi, color="C3", alpha=0.08, lw=0)
        ax.minorticks_off()
        ax.set_title(sweep.label(config), fontsize=8)
        ax.set_xlabel("mean radius of gyration <Rg>")
        ax.set_ylabel("particles n")
        ax.legend(fontsize=6, loc="upper left")
    fig.suptitle(f"Mass against radius, the headline estimator, at N={sweep.counts[last]}", fontsize=9)
    save_figure(fig, path)
    return ("The estimator the report quotes: n against the seed-averaged radius of gyration along the growth, "
            "log-log, with the line fitted over the window chosen from the data (shaded).")


def _anisotropy(sweep, path):
    if not np.isfinite(sweep.s["anisotropy"].values).any():
        return None
    fig, (ax,) = new_figure(1, 6.5, 4.2)
    for c, config in enumerate(sweep.configs[:10]):
        mean, err = sweep.bars("anisotropy", config)
        ax.errorbar(sweep.counts * 1.02 ** c, mean, yerr=err, color=colour_of(c), marker="o", capsize=2,
                    label=sweep.label(config))
    ax.axhline(0, color="k", lw=0.8)
    log_x(ax)
    ax.set_xlabel("particles N")
    ci = _any_ci(sweep, "anisotropy")
    ax.set_ylabel("anisotropy of the outer mass" + (f" ({LEVEL} CI)" if ci else ""))
    drifted = any(sweep.param("drift", config) > 0 for config in sweep.configs)
    ax.set_title("Growth along the lattice axes: <cos 4 theta> (2D), cubic harmonic (3D)"
                 + ("\nnot the elongation along a drift" if drifted else ""), fontsize=9)
    fig.legend(*ax.get_legend_handles_labels(), loc="outside lower center", fontsize=6, ncols=3)
    save_figure(fig, path)
    return ("The cubic anisotropy of the outer half of the mass about the seed, mean over seeds"
            + (f" with its {LEVEL} CI" if ci else f" (no CI: fewer than {MIN_CI_SEEDS} seeds)") + ": 1 if the mass lay "
            "along the axes, 0 for an isotropic cluster (square-lattice arms are expected to raise it with N)."
            + (" Under a drift it is not the cluster's elongation along the drift: it weighs the directions of the "
               "outer mass by how near they lie to any lattice axis, so a cone growing up into a drift along an "
               "axis raises it, and one growing along a diagonal lowers it, however narrow the cone; the cone's "
               "elongation shows in the pictures and in the summary's Rg/Rmax, which falls as it narrows."
               if drifted else ""))


def _any_ci(sweep, stem) -> bool:
    """Whether the summary has any 95% CI of ``stem`` to draw (none below ``MIN_CI_SEEDS`` clusters)."""
    return bool(np.isfinite(sweep.s[f"{stem}_ci_lo"].values).any())


def _dimension_spread(sweep, path):
    last = len(sweep.counts) - 1
    shown = sweep.configs[:20]
    ci = _any_ci(sweep, "D")
    fig, (ax,) = new_figure(1, max(5.0, 0.6 * len(shown) + 2), 4.2)
    for c, config in enumerate(shown):
        for e, (name, prefix) in enumerate((("mass-radius, per cluster", "D_cluster"),
                                            ("box counting, per cluster", "D_box_cluster"))):
            values = sweep.at(prefix, config, n_particles=last)
            ok = sweep.at(f"{prefix}_ok", config, n_particles=last).astype(bool)
            x = c + (0.2 if e else -0.2) + np.linspace(-0.06, 0.06, len(values))
            ax.scatter(x[ok], values[ok], s=12, marker="os"[e], color=f"C{e}", label=name if c == 0 else None)
            ax.scatter(x[~ok], values[~ok], s=14, marker="x", color="C3",
                       label="fit not flat" if c == 0 and e == 0 else None)
        row = sweep.row(config, last)
        ax.errorbar([c - 0.2], [row["D"]], yerr=np.reshape(error_bars(row["D"], row["D_ci_lo"], row["D_ci_hi"]),
                                                          (2, 1)), color="k",
                    capsize=3, marker="_", ms=14,
                    label=("ensemble D" + (f", {LEVEL} CI" if ci else "")) if c == 0 else None)
    if sweep.reference:
        ax.axhline(sweep.reference, color="k", ls="--", lw=1)
    ax.set_xticks(range(len(shown)), [sweep.label(c) for c in shown], rotation=30, ha="right", fontsize=7)
    ax.set_ylabel("D")
    ax.set_title(f"Spread of D over seeds at N={sweep.counts[last]}")
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    save_figure(fig, path)
    return ("D of every seed's own fit at the largest count, both estimators (red crosses: the fit's local slope "
            "is not flat), and the ensemble headline (black)" + (f" with its {LEVEL} CI." if ci else
                                                                  f", no CI: fewer than {MIN_CI_SEEDS} seeds."))


def _diffusion_times(sweep, path):
    if not np.isfinite(sweep.s["diffusion_density"].values).any():
        return None
    fig, (hist, depth) = new_figure(2, 5.0, 3.8)
    bins, depths = sweep.s["diffusion_bin"].values, sweep.s["depth_bin"].values
    jumps = {c: bool(sweep.param("jumps", c)) for c in sweep.configs[:10]}
    for c, config in enumerate(jumps):
        # Times with and without jumps count different moves: the line style keeps them apart.
        style = dict(color=colour_of(c), ls="-" if jumps[config] else "--")
        density = sweep.at("diffusion_density", config)
        hist.step(bins, np.where(density > 0, density, np.nan), where="mid", label=sweep.label(config), **style)
        depth.semilogy(depths, sweep.at("diffusion_median", config), marker="o", ms=3, **style)
    hist.set_xscale("log")
    hist.set_yscale("log")
    hist.set_xlabel("diffusion time: moves to stick\n(one per walk step or first-passage jump)")
    hist.set_ylabel("density")
    fig.legend(*hist.get_legend_handles_labels(), loc="outside lower center", fontsize=6, ncols=3)
    depth.set_xlabel("distance from seed / cluster radius")
    depth.set_ylabel("median diffusion time (moves)")
    low, high = depth.get_ylim()
    if high < 10 * low:
        # within one decade matplotlib labels minor ticks as 2.8x10^1: plain numbers read better
        from matplotlib.ticker import ScalarFormatter

        depth.yaxis.set_major_formatter(ScalarFormatter())
        depth.yaxis.set_minor_formatter(ScalarFormatter())
    fig.suptitle("Diffusion times, pooled over the stored clusters")
    save_figure(fig, path)
    unit = {frozenset([False]): " Every walk here takes single steps (jumps off): a move is one step.",
            frozenset([True]): " Walkers here jump far from the cluster: a first-passage jump counts as one move "
                               "however far it goes, so the time counts moves, not walk steps.",
            frozenset([True, False]): " Walkers with jumps on count a first-passage jump as one move however far "
                                      "it goes, those with jumps off (dashed) one move per step: the two are not "
                                      "on one time scale."}[frozenset(jumps.values())]
    return ("Distribution of diffusion times, in moves from release to sticking (left), and their median against "
            "the depth at which the particle stuck, as a fraction of the cluster's radius (right)." + unit)


_MARKERS = "*osD^vP<>Xph"
_FILLS = ("full", "none", "left", "bottom")


def _speed_accuracy(sweep, path):
    methods = sweep.methods
    last = len(sweep.counts) - 1
    pairs = [(c, sweep.exact(c)) for c in sweep.configs]
    pairs = [(c, r) for c, r in pairs if r is not None]
    if not methods or all(c == r for c, r in pairs):
        return None
    others = [d for d in sweep.config_dims if d not in methods and sweep.ds.sizes[d] > 1]
    families = list(dict.fromkeys(["exact", *(sweep.family(c) for c, _ in pairs)]))
    members = {}
    fig, (dev_d, dev_rg) = new_figure(2, 5.0, 4.4)
    for config, ref in pairs:
        row = sweep.row(config, last)
        family = sweep.family(config)
        f = families.index(family)
        # Variants of one family share colour and marker and differ in fill.
        fill = _FILLS[members.setdefault(family, []).__len__() % len(_FILLS)]
        members[family].append(config)
        label = sweep.variant(config) + (f" ({sweep.label(config, others)})" if others else "")
        style = dict(color=colour_of(f), marker=_MARKERS[f % len(_MARKERS)], ms=10 if f == 0 else 6, capsize=2,
                     ls="none", fillstyle=fill, mec="k" if row["pareto"] else colour_of(f))
        for ax, name in ((dev_d, "D"), (dev_rg, "rg_mean")):
            y, err = row[f"{name}_vs_exact"], row[f"{name}_vs_exact_half_width"]
            if np.isfinite(y):
                ax.errorbar(row["seconds_per_particle"], y, yerr=np.nan_to_num(err), label=label, **style)
            else:
                mark_missing(ax, [row["seconds_per_particle"]], [y])
    front = sweep.pareto_front([c for c, _ in pairs], last)
    if len(front) > 1:
        dev_rg.plot([r["seconds_per_particle"] for r in front], [r["rg_mean_vs_exact"] for r in front],
                    color="k", lw=0.8, ls=":", label="Pareto front (cheapest for its accuracy)")
    ci = f", {LEVEL} CI" if _any_ci(sweep, "D") else ""
    for ax, label in ((dev_d, f"D(variant) - D(exact){ci}"), (dev_rg, f"Rg(variant) / Rg(exact) - 1{ci}")):
        ax.axhline(0, color="k", lw=0.8)
        log_x(ax)
        ax.set_xlabel("wall time per particle (s)")
        ax.set_ylabel(label)
    handles, labels = dev_rg.get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", fontsize=6, ncols=3,
               title="variant (colour and marker: the shortcuts taken; fill: which of them)", title_fontsize=7)
    fig.suptitle(f"Speed against accuracy at N={sweep.counts[last]}")
    save_figure(fig, path)
    return ("Cost per particle against the departure from the exact method (" + ", ".join(
        f"{m}={text(EXACT_METHOD[m])}" for m in methods) + ") with the other parameters equal, at the largest count: "
        "D (left) and Rg at equal N (right, the sharper test). One colour and marker per set of shortcuts taken; "
        "black edges and the dotted line mark the Pareto front (no variant is both cheaper and closer)."
        + (f" Bars combine both {LEVEL} CIs." if _any_ci(sweep, "D") else
           f" No bars and no Pareto front: fewer than {MIN_CI_SEEDS} seeds give no CI."))


def _failure(sweep, path):
    methods = sweep.methods
    if not methods:
        return None
    last = len(sweep.counts) - 1
    every = sweep.scenes()
    scenes = every[:10]
    fig, panels = new_figure(2 * len(methods), 4.0, 3.3)
    drawn = set()
    for p, axis in enumerate(methods):
        for panel, name, label in ((panels[2 * p], "D", "D, mass-radius"), (panels[2 * p + 1], "rg_over_rmax",
                                                                              "Rg / R_max")):
            for c, base in enumerate(scenes):
                # Scenes side by side, 6 points apart: their points share x.
                drawn |= _failure_series(sweep, panel, axis, name, base, colour_of(c) if len(scenes) > 1 else "C0",
                                         sweep.scene_label(base), last, 6 * (c - (len(scenes) - 1) / 2))
            if name == "D" and sweep.reference:
                panel.axhline(sweep.reference, color="k", ls="--", lw=1, label=f"reference {sweep.reference}")
            panel.set_xlabel(f"{axis} (exact: {text(EXACT_METHOD[axis])})")
            panel.set_ylabel(f"{label}" + (f" ({LEVEL} CI)" if "ci" in drawn else ""))
            panel.legend(fontsize=6, loc="best")
    numbers = f"\n(numbers: bias in units of the combined {LEVEL} CI half-width)" if "bias" in drawn else ""
    fig.suptitle(f"Shortcuts against the exact method at N={sweep.counts[last]}, the model's parameters equal"
                 + numbers, fontsize=9)
    save_figure(fig, path)
    return _failure_caption(methods, scenes, len(every), drawn)


def _failure_series(sweep, panel, axis, name, base, colour, scene, last, shift) -> set:
    """One scene's values along one method axis (``shift`` points to the right), and its exact method.

    Returns what it drew.
    """
    from matplotlib.transforms import ScaledTranslation

    moved = panel.transData + ScaledTranslation(shift / 72, 0, panel.figure.dpi_scale_trans)
    exact, varied = sweep.one_factor(axis, base)
    rows = [sweep.row(c, last) for c in varied]
    xs = np.array([float(r[axis]) for r in rows])
    y = np.array([r[name] for r in rows])
    lo, hi = np.array([r[f"{name}_ci_lo"] for r in rows]), np.array([r[f"{name}_ci_hi"] for r in rows])
    drawn = {"ci"} if np.isfinite(lo).any() else set()
    panel.errorbar(xs, y, yerr=error_bars(y, lo, hi), color=colour, marker="o", capsize=2, ls="-",
                   label=scene or f"{axis} varied", transform=moved)
    # A shifted transform keeps matplotlib from seeing the points: tell it where they are.
    seen = np.c_[np.r_[xs, xs, xs], np.r_[y, lo, hi]]
    panel.update_datalim(seen[np.isfinite(seen).all(axis=1)])
    panel.autoscale_view()
    mark_missing(panel, xs, y)
    if not np.isfinite(y).all():
        drawn.add("missing")
    if sweep.ds[axis].dtype == bool:
        panel.set_xticks(xs, [text(bool(x)) for x in xs])
        panel.set_xlim(-0.5, 1.5)
    flagged = np.array([r["flagged"] for r in rows], bool) & np.isfinite(y)
    if flagged.any():
        panel.scatter(xs[flagged], y[flagged], s=80, facecolors="none", edgecolors="C3", lw=1.2, zorder=3,
                      transform=moved,
                      label=None if "flagged" in panel.get_legend_handles_labels()[1] else "flagged")
        drawn.add("flagged")
    if not exact:
        return drawn | {"no exact"}
    ref = sweep.row(exact[0], last)
    if np.isfinite(ref[f"{name}_ci_lo"]):
        panel.axhspan(ref[f"{name}_ci_lo"], ref[f"{name}_ci_hi"], color=colour, alpha=0.15, lw=0,
                      label=None if scene else f"exact method, {LEVEL} CI")
        drawn.add("band")
    panel.axhline(ref[name], color=colour, lw=1, ls=":", label=None if scene else "exact method")
    for x, r in zip(xs, rows):
        units = bias(r, ref, name)
        if np.isfinite(units):
            panel.annotate(f"{units:+.1f}", (x, r[name]), fontsize=6, xytext=(4 + shift, -9),
                           textcoords="offset points", color=colour, annotation_clip=False,
                           bbox={"boxstyle": "square,pad=0.1", "fc": "white", "ec": "none", "alpha": 0.8})
            drawn.add("bias")
    if sweep.ds[axis].dtype != bool:
        panel.margins(x=0.12)  # room for the rightmost point's number inside the axes
    return drawn | {"exact"}


def _failure_caption(methods, scenes, every, drawn) -> str:
    """What the failure map drew, and only that."""
    parts = [f"D and Rg/R_max as each shortcut ({', '.join(methods)}) departs from the exact method "
             f"({', '.join(f'{m}={text(EXACT_METHOD[m])}' for m in methods)}), the other parameters equal"]
    if len(scenes) > 1:
        parts.append(f"one colour per scene, a setting of the model's swept parameters ({every} scenes"
                     + (f", the first {len(scenes)} drawn)" if every > len(scenes) else ")"))
    if "exact" in drawn:
        parts.append("the dotted line is the exact method's value" + (
            f" and the shaded band its {LEVEL} CI, drawn across the panel (an infinite kill radius or an exact "
            "contact has no place on the axis)" if "band" in drawn else f" (no CI: fewer than {MIN_CI_SEEDS} seeds)"))
    if "no exact" in drawn:
        parts.append("some scenes have no exact-method configuration in the sweep, so nothing to compare with")
    if "bias" in drawn:
        parts.append(f"each point is labelled with its bias in units of the combined {LEVEL} CI half-width: beyond "
                     "+-1 the bias is resolved")
    if "ci" in drawn:
        parts.append(f"bars are {LEVEL} CIs")
    if "flagged" in drawn:
        parts.append("red rings: a cluster stopped early")
    if "missing" in drawn:
        parts.append("a red cross on the bottom edge: a variant with no value at this N (no cluster reached it)")
    return "; ".join(parts) + "."


PLOTS = {
    "gallery": _gallery,
    "box_counts": _box_counts,
    "box_local_slopes": _box_local_slopes,
    "dimension_vs_n": _dimension_vs_n,
    "mass_radius": _mass_radius,
    "anisotropy": _anisotropy,
    "dimension_spread": _dimension_spread,
    "diffusion_times": _diffusion_times,
    "speed_accuracy": _speed_accuracy,
    "failure": _failure,
    "branching": branching_figure,
    "harmonic_spectrum": spectrum_figure,
}
"""Every plot: name -> function(sweep, path) returning a caption, or None when skipped."""
