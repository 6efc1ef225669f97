"""The report's harmonic measure: the figure of D(q) against q with its intervals over seeds, and the lines of
report.md on it (``stats.multifractal``'s ``seed_spectrum`` and ``size_scaling``, drawn; nothing else computed
here).

Present only for a sweep with ``[measure] harmonic_walkers``. Two estimates of D(q) are shown: by cluster
size (the Renyi entropies' growth between the two largest counts, ``size_scaling``), the scaling that
Makarov's and Halsey's relations are about, and by box partition sums within each cluster at the largest
count (``seed_spectrum``). In 2D the figure marks Makarov's D(1) = 1 and Halsey's D(3) = D/2, and the text
says whether each holds within the intervals of the size estimate. Halsey's D is the dimension of the
measure's support, the cluster: the mass dimension between the same counts from the same seeds, not the
harmonic D(0), which a finite number of walkers cannot resolve (the fjords they never reach count in D(0)
as much as the tips).
"""

from __future__ import annotations

import numpy as np

from ..stats.constants import LEVEL, MIN_CI_SEEDS
from ..stats.multifractal import seed_spectrum, size_scaling
from .figures import colour_of, new_figure, save_figure

_MAX_LINES = 10


def _spectra(sweep) -> list:
    """(config, SeedSpectrum) of the first configurations of a sweep with the harmonic measurement."""
    ds = sweep.ds
    if "harmonic_D" not in ds:
        return []
    out = []
    for config in sweep.configs[:_MAX_LINES]:
        where = dict(zip(sweep.config_dims, config))
        D = ds["harmonic_D"][where].transpose("seed", "q").values
        ok = ds["harmonic_D_ok"][where].transpose("seed", "q").values
        out.append((config, seed_spectrum(ds["q"].values, D, ok)))
    return out


def _scalings(sweep) -> list:
    """(config, SizeScaling) of the first configurations, between the sweep's counts; [] with one count."""
    ds = sweep.ds
    if "harmonic_entropy" not in ds or len(sweep.counts) < 2:
        return []
    out = []
    for config in sweep.configs[:_MAX_LINES]:
        where = dict(zip(sweep.config_dims, config))
        entropy, half = (ds[name][where].transpose("seed", "n_particles", "q").values
                         for name in ("harmonic_entropy", "harmonic_entropy_half"))
        rg = ds["radius_gyration"][where].transpose("seed", "n_particles").values
        out.append((config, size_scaling(ds["q"].values, sweep.counts, rg, entropy, half)))
    return out


def _raw_mean(sweep, config) -> np.ndarray:
    """Each q's mean of every seed's D(q), trusted or not: drawn hollow where none is trusted, so that no q
    silently vanishes from the figure."""
    values = sweep.ds["harmonic_D"][dict(zip(sweep.config_dims, config))].transpose("seed", "q").values
    finite = np.isfinite(values)
    return np.where(finite.any(axis=0), np.nansum(values, axis=0) / np.maximum(finite.sum(axis=0), 1), np.nan)


def spectrum_figure(sweep, path):
    """D(q) against q, each configuration's mean over seeds with its 95% interval; None without the measurement."""
    spectra = _spectra(sweep)
    raw = [_raw_mean(sweep, config) for config, _ in spectra]
    if not any(np.isfinite(r).any() for r in raw):
        return None
    fig, (ax,) = new_figure(1, 6.5, 4.4)
    shift = 0.04
    scalings = dict(_scalings(sweep))
    for i, (config, s) in enumerate(spectra):
        x = s.q + shift * (i - (len(spectra) - 1) / 2)
        if config in scalings:
            z = scalings[config]
            ok = z.ok[-1]
            lo, hi = z.D[-1] - z.ci_lo[-1], z.ci_hi[-1] - z.D[-1]
            ax.errorbar(x[ok], z.D[-1][ok], yerr=[lo[ok], hi[ok]], color=colour_of(i), marker="s", ms=4, capsize=2,
                        lw=0, elinewidth=1, mfc="white",
                        label=(f"by cluster size, N = {sweep.counts[-2]:g} to {sweep.counts[-1]:g}"
                               + (f": {sweep.label(config)}" if sweep.label(config) else "")))
        lo, hi = s.mean - s.ci_lo, s.ci_hi - s.mean
        bars = np.where(np.isfinite(lo), [lo, hi], 0.0)
        ax.errorbar(x, s.mean, yerr=bars, color=colour_of(i), marker="o", ms=3, capsize=2, lw=1,
                    label=f"box sums at N = {sweep.counts[-1]:g}"
                          + (f": {sweep.label(config)}" if sweep.label(config) else ""))
        untrusted = ~np.isfinite(s.mean) & np.isfinite(raw[i])
        ax.scatter(x[untrusted], raw[i][untrusted], s=18, facecolors="none", edgecolors=colour_of(i),
                   label="no seed's fit trusted: mean of the untrusted fits" if i == 0 and untrusted.any() else None)
        half = scalings[config].mass[-1] / 2 if config in scalings else np.nan
        if sweep.dim == 2 and np.isfinite(half):
            ax.plot([2.6, 3.4], [half, half], color=colour_of(i), ls="--", lw=1.2,
                    label="Halsey: D(3) = D/2, D the mass dimension between the same counts" if i == 0 else None)
    if sweep.dim == 2:
        ax.plot([0.6, 1.4], [1.0, 1.0], color="k", ls=":", lw=1.5, label="Makarov: D(1) = 1")
        for q in (1.0, 3.0):
            ax.axvline(q, color="0.85", lw=0.8, zorder=0)
    ax.set_xlabel("moment q")
    ax.set_ylabel(f"D(q), mean over seeds ({LEVEL} CI)")
    ax.set_title("Generalised dimensions of the harmonic measure", fontsize=9)
    ax.legend(fontsize=7, loc="upper right")
    save_figure(fig, path)
    return (f"The generalised dimensions D(q) of the harmonic measure (where the next particle lands), sampled by "
            f"the walkers fired at each cluster. Squares: by cluster size, the growth of the measure's Renyi "
            f"entropies between the two largest counts over that of log Rg, with its {LEVEL} CI over seeds (only "
            f"the q whose correction for the walkers' number is within the interval). Dots: by box partition sums "
            f"within each cluster at its largest count, mean over the seeds whose fit is trusted with its {LEVEL} "
            f"CI (no bar: fewer than {MIN_CI_SEEDS} trusted seeds; hollow: no seed's fit is trusted, the mean of "
            f"the untrusted fits, not to be quoted)"
            + ("; dotted, Makarov's D(1) = 1; dashed, Halsey's D(3) = D/2 with D the mass dimension between the "
               "same counts, the dimension of the measure's support."
               if sweep.dim == 2 else "."))


def _value(s, q) -> str:
    k = s.at(q)
    if not np.isfinite(s.mean[k]):
        return f"D({q:g}): no trusted fit"
    if not np.isfinite(s.ci_lo[k]):
        return f"D({q:g}) = {s.mean[k]:.3f} (no CI: {s.n[k]} trusted seeds)"
    return f"D({q:g}) = {s.mean[k]:.3f} [{s.ci_lo[k]:.3f}, {s.ci_hi[k]:.3f}]"


def _holds(lo, hi, value) -> str:
    if not (np.isfinite(lo) and np.isfinite(hi)):
        return "cannot be judged (no interval)"
    return "holds within it" if lo <= value <= hi else "does not hold within it"


def _sized(z, q) -> str:
    k = z.at(q)
    value = f"D({q:g}) = {z.D[-1, k]:.3f}"
    if not np.isfinite(z.ci_lo[-1, k]):
        return f"{value} (no CI: {z.seeds} seeds)"
    value += f" [{z.ci_lo[-1, k]:.3f}, {z.ci_hi[-1, k]:.3f}]"
    return value if z.ok[-1, k] else f"{value} (untrusted: the correction for the walkers' number, " \
                                     f"{z.correction[-1, k]:+.3f}, exceeds the interval's half-width)"


def _size_line(sweep, z) -> str:
    """What the size estimate says at the two largest counts, and whether Makarov and Halsey hold in 2D."""
    line = (f"by cluster size (N = {sweep.counts[-2]:g} to {sweep.counts[-1]:g}, {z.seeds} seeds): "
            f"{_sized(z, 1.0)}; {_sized(z, 3.0)}; mass dimension D = {z.mass[-1]:.3f} "
            f"[{z.mass_ci_lo[-1]:.3f}, {z.mass_ci_hi[-1]:.3f}]")
    if sweep.dim != 2:
        return line
    one, three = z.at(1.0), z.at(3.0)
    makarov = _holds(z.ci_lo[-1, one], z.ci_hi[-1, one], 1.0) if z.ok[-1, one] else "cannot be judged (untrusted)"
    halsey = (_holds(z.halsey_ci_lo[-1], z.halsey_ci_hi[-1], 0.0) if z.ok[-1, three]
              else "cannot be judged (D(3) untrusted)")
    return (f"{line}. Makarov (D(1) = 1) {makarov}; Halsey (2 D(3) = D): 2 D(3) - D = {z.halsey[-1]:.3f} "
            f"[{z.halsey_ci_lo[-1]:.3f}, {z.halsey_ci_hi[-1]:.3f}], {halsey}")


def harmonic_lines(sweep) -> list:
    """The section of report.md on the harmonic measure (none without it)."""
    spectra = _spectra(sweep)
    if not spectra:
        return []
    ds = sweep.ds
    scalings = dict(_scalings(sweep))
    lines = ["## Harmonic measure", "",
             "Walkers fired at each cluster as it was at every count, moved and stuck exactly as in growth but not "
             "attached (`[measure] harmonic_walkers`). D(q) by cluster size: the growth of the Renyi entropies of "
             "the measure at the particles over that of log Rg between the two largest counts, each entropy "
             "corrected for the walkers' number (Richardson, from half of them), with its "
             f"{LEVEL} CI over seeds; Makarov's D(1) = 1 and Halsey's 2 D(3) = D are judged on it. D(q) by box "
             "partition sums within each cluster at the largest count, each seed's fit trusted only when flat and "
             f"resolved by the walkers, mean over the trusted seeds with its {LEVEL} CI (docs/harmonic.md).", ""]
    for config, s in spectra:
        where = dict(zip(sweep.config_dims, config))
        depth = ds["harmonic_depth"][where].values
        depth = depth[np.isfinite(depth)]
        label = sweep.label(config) or "all"
        if config in scalings:
            lines.append(f"- {label}, {_size_line(sweep, scalings[config])}.")
        else:
            lines.append(f"- {label}, by cluster size: not measured (one count, or no entropies in the file).")
        line = (f"- {label}, by box sums at N = {sweep.counts[-1]:g}: "
                + "; ".join(_value(s, q) for q in (0.0, 1.0, 3.0)))
        if len(depth):
            line += f"; deposition depth {depth.mean():.3f} of the radius"
        lines.append(line + ".")
    return [*lines, ""]
