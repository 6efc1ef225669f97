"""The report's harmonic measure: the figure of D(q) against q with its intervals over seeds, and the lines of
report.md on it (``stats.multifractal.seed_spectrum``'s numbers, drawn; nothing else computed here).

Present only for a sweep with ``[measure] harmonic_walkers``. In 2D the figure marks Makarov's D(1) = 1 and
Halsey's D(3) = D(0)/2, and the text says whether each holds within the intervals. Halsey's D(0) is the
dimension of the measure's support, the cluster: the report's headline D (mass-radius, ensemble) with its
interval, not the harmonic D(0), whose box sums a finite number of walkers cannot resolve (the fjords they
never reach count in D(0) as much as the tips).
"""

from __future__ import annotations

import numpy as np

from ..stats.constants import LEVEL, MIN_CI_SEEDS
from ..stats.multifractal import seed_spectrum
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
    for i, (config, s) in enumerate(spectra):
        x = s.q + shift * (i - (len(spectra) - 1) / 2)
        lo, hi = s.mean - s.ci_lo, s.ci_hi - s.mean
        bars = np.where(np.isfinite(lo), [lo, hi], 0.0)
        ax.errorbar(x, s.mean, yerr=bars, color=colour_of(i), marker="o", ms=3, capsize=2, lw=1,
                    label=sweep.label(config) or "D(q)")
        untrusted = ~np.isfinite(s.mean) & np.isfinite(raw[i])
        ax.scatter(x[untrusted], raw[i][untrusted], s=18, facecolors="none", edgecolors=colour_of(i),
                   label="no seed's fit trusted: mean of the untrusted fits" if i == 0 and untrusted.any() else None)
        half = sweep.row(config, len(sweep.counts) - 1)["D"] / 2
        if sweep.dim == 2 and np.isfinite(half):
            ax.plot([2.6, 3.4], [half, half], color=colour_of(i), ls="--", lw=1.2,
                    label="Halsey: D(3) = D(0)/2, D(0) the headline D" if i == 0 else None)
    if sweep.dim == 2:
        ax.plot([0.6, 1.4], [1.0, 1.0], color="k", ls=":", lw=1.5, label="Makarov: D(1) = 1")
        for q in (1.0, 3.0):
            ax.axvline(q, color="0.85", lw=0.8, zorder=0)
    ax.set_xlabel("moment q")
    ax.set_ylabel(f"D(q), mean over seeds ({LEVEL} CI)")
    ax.set_title(f"Generalised dimensions of the harmonic measure at N={sweep.counts[-1]}", fontsize=9)
    ax.legend(fontsize=7, loc="upper right")
    save_figure(fig, path)
    return (f"The generalised dimensions D(q) of the harmonic measure (where the next particle lands), sampled by "
            f"the walkers fired at each cluster at its largest count, mean over the seeds whose fit is trusted with "
            f"its {LEVEL} CI (no bar: fewer than {MIN_CI_SEEDS} trusted seeds; hollow: no seed's fit is trusted, the "
            f"mean of the untrusted fits, not to be quoted)"
            + ("; dotted, Makarov's D(1) = 1; dashed, Halsey's D(3) = D(0)/2 with D(0) the configuration's "
               "headline D (mass-radius, ensemble), the dimension of the measure's support."
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


def harmonic_lines(sweep) -> list:
    """The section of report.md on the harmonic measure (none without it)."""
    spectra = _spectra(sweep)
    if not spectra:
        return []
    ds = sweep.ds
    lines = ["## Harmonic measure", "",
             "Walkers fired at each cluster as grown to its largest count, moved and stuck exactly as in growth "
             "but not attached (`[measure] harmonic_walkers`); D(q) by box partition sums over a fitted window, "
             f"each seed's fit trusted only when flat and resolved by the walkers; values are means over the "
             f"trusted seeds with {LEVEL} CIs (docs/harmonic.md).", ""]
    for config, s in spectra:
        where = dict(zip(sweep.config_dims, config))
        depth = ds["harmonic_depth"][where].values
        depth = depth[np.isfinite(depth)]
        parts = [_value(s, q) for q in (0.0, 1.0, 3.0)]
        line = f"- {sweep.label(config) or 'all'}: " + "; ".join(parts)
        if len(depth):
            line += f"; deposition depth {depth.mean():.3f} of the radius"
        if sweep.dim == 2:
            k = s.at(1.0)
            line += f". Makarov (D(1) = 1) {_holds(s.ci_lo[k], s.ci_hi[k], 1.0)}"
            row, k = sweep.row(config, len(sweep.counts) - 1), s.at(3.0)
            # the two intervals' half-widths in quadrature: D(3) and D(0)/2 come from independent estimates
            diff = s.mean[k] - row["D"] / 2
            half = np.hypot(s.ci_hi[k] - s.mean[k], (row["D_ci_hi"] - row["D"]) / 2)
            if np.isfinite(half):
                line += (f"; Halsey (D(3) = D(0)/2, D(0) = the headline D {row['D']:.3f}): D(3) - D(0)/2 = "
                         f"{diff:.3f} [{diff - half:.3f}, {diff + half:.3f}], {_holds(diff - half, diff + half, 0.0)}")
            else:
                line += "; Halsey (D(3) = D(0)/2) cannot be judged (no interval of D(3) or of the headline D)"
        lines.append(line + ".")
    return [*lines, ""]
