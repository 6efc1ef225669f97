"""The report's words: ``summary.csv``, ``summary.md`` and ``report.md`` (results, method, comparisons, figures).

Writes what ``readout.Readout`` reads, and the captions the plots returned; computes nothing.
"""

from __future__ import annotations

import csv
import os
from pathlib import Path

import numpy as np

from ..params import EXACT_METHOD, text
from ..stats.constants import LEVEL, MIN_CI_SEEDS, MIN_DECADES, START_FRACTION
from .branch_report import branching_lines
from .figures import MAX_PANELS
from .harmonic_report import harmonic_lines
from .readout import REFERENCE_D, resolved


def _stored(sweep) -> str:
    """How many clusters keep their positions, and what the report draws from them."""
    if sweep.n_stored == 0:
        return "none stored with its positions (no gallery, no diffusion times; every curve is measured)"
    if sweep.n_stored < sweep.n_clusters:
        return f"{sweep.n_stored} stored with their positions (the gallery and the diffusion times are of those)"
    return "every one stored with its positions"


def write_csv(sweep, path) -> Path:
    rows = sweep.rows()
    with open(path, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    return path


def _interval(row, name) -> str:
    """``value [lo, hi]`` (95% CI), or the value alone when there is no interval."""
    value = row[name]
    if not np.isfinite(value):
        return "-"
    lo, hi = row[f"{name}_ci_lo"], row[f"{name}_ci_hi"]
    return f"{value:.3f} [{lo:.3f}, {hi:.3f}]" if np.isfinite(lo) else f"{value:.3f} (no CI)"


def _against_reference(sweep, rows) -> list:
    """Whether each configuration's 95% intervals of D and D_inf contain the published D of its model.

    Parameters
    ----------
    sweep : Readout
        The sweep; ``sweep.reference`` is the published D of off-lattice DLA in its dimension, None on a
        lattice (whose clusters have no published asymptote to hold them to).
    rows : list of (str, dict)
        Each configuration's label and summary row at the largest count.

    Returns
    -------
    list of str
        Markdown lines: one sentence a configuration and a blank line, or none without a reference.
    """
    if sweep.reference is None:
        return []

    def verdict(row, name):
        lo, hi = row[f"{name}_ci_lo"], row[f"{name}_ci_hi"]
        if not (np.isfinite(lo) and np.isfinite(hi)):
            return f"{name}: no interval"
        inside = lo <= sweep.reference <= hi
        return f"{name} [{lo:.4f}, {hi:.4f}] {'contains' if inside else 'does not contain'} it"

    published = f"{sweep.reference:.4f}(3)" if sweep.dim == 2 else f"about {sweep.reference:.2f}"
    return [f"Against the published D of {sweep.dim}D off-lattice DLA, {published}: "
            + "; ".join(f"{label}: {verdict(row, 'D')}, {verdict(row, 'D_inf')}" for label, row in rows) + ".", ""]


def _headline(row) -> str:
    shown = _interval(row, "D")
    if shown != "-":
        if row["D_ci_reason"] and np.isfinite(row["D"]):
            shown = shown.replace("(no CI)", f"(no CI: {row['D_seeds']} < {MIN_CI_SEEDS} clusters)")
        shown += f" over N {row['D_range_lo']:.0f}-{row['D_range_hi']:.0f}"
        if not row["D_ok"]:
            shown += " (local slope not flat)"
    return f"{shown}, {row['D_seeds']} clusters"


def _markdown_table(sweep) -> str:
    head = [*sweep.config_dims, "N", "status", "D mass-radius (ensemble)", "D box counting (share of flat fits)",
            "D per-seed std", "Rg", "Rg/Rmax", "s/particle"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for row in sweep.rows():
        cells = [str(row[d]) for d in sweep.config_dims] + [
            str(row["n_particles"]),
            row["status"] + (" ⚠" if row["flagged"] else ""),
            _headline(row),
            f"{_interval(row, 'D_box')} ({row['D_box_ok_fraction']:.0%})",
            f"{row['D_seed_std']:.3f}",
            f"{row['rg_mean']:.1f}",
            _interval(row, "rg_over_rmax"),
            f"{row['seconds_per_particle']:.2e}",
        ]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def write_table(sweep, path) -> Path:
    path.write_text(
        f"Every interval is a {LEVEL} confidence interval (bootstrap over seeds), given from {MIN_CI_SEEDS} "
        "clusters on. D mass-radius: one fit of "
        "n ~ <Rg>^D to the seed-averaged growth histories of every cluster that reached N, over the window "
        "given. Box counting: mean of every cluster's own fit (in brackets: the share of fits whose local "
        "slope is flat). ⚠: some cluster stopped early.\n\n"
        + _markdown_table(sweep)
    )
    return path


def _verdict(value, half) -> str:
    """``+0.012 ± 0.004 (resolved)`` or ``+0.001 ± 0.004 (|dev| < 0.005)``."""
    if not np.isfinite(value):
        return "-"
    if not np.isfinite(half):
        return f"{value:+.4f} (no CI: cannot say whether resolved)"
    shown = f"{value:+.4f} ± {half:.4f}"
    return shown + (" (resolved)" if resolved(value, half) else f" (|dev| < {abs(value) + half:.4f})")


def _differences(sweep) -> list:
    """Markdown lines: whether the CIs resolve the difference in D between neighbouring scenes."""
    last = len(sweep.counts) - 1
    pairs = sweep.differences(last)
    if not pairs:
        return []
    lines = [f"D between configurations one value apart, at N = {sweep.counts[last]}: the difference ± its {LEVEL} CI "
             "half-width (both CIs in quadrature); resolved when that interval excludes zero, otherwise the "
             "difference is only bounded.", ""]
    for config, other, value, half in pairs[:MAX_PANELS]:
        lines.append(f"- {sweep.label(other)} against {sweep.label(config)}: {_verdict(value, half)}")
    if len(pairs) > MAX_PANELS:
        lines.append(f"- ... and {len(pairs) - MAX_PANELS} more pairs (every D and CI is in `summary.csv`)")
    return lines + [""]


def _deviation_table(sweep) -> list:
    """Markdown lines: every variant against the exact method at the largest N."""
    methods = sweep.methods
    last = len(sweep.counts) - 1
    rows = [sweep.row(c, last) for c in sweep.configs]
    if not methods or not any(np.isfinite(r["rg_mean_vs_exact"]) for r in rows):
        return []
    lines = [f"Each variant against the exact method ({', '.join(f'{m}={text(EXACT_METHOD[m])}' for m in methods)}) "
             f"with the other parameters equal, at N = {sweep.counts[last]}: the difference ± its {LEVEL} CI "
             "half-width; resolved when the interval excludes zero, otherwise bounded.", "",
             "| " + " | ".join([*sweep.config_dims, "D - D(exact)", "Rg / Rg(exact) - 1",
                                "Rg/Rmax - exact"]) + " |", "|" + "---|" * (len(sweep.config_dims) + 3)]
    for config, r in zip(sweep.configs, rows):
        exact = sweep.exact(config) == config
        cells = [str(r[d]) for d in sweep.config_dims] + [
            "exact (reference)" if exact else _verdict(r[f"{name}_vs_exact"], r[f"{name}_vs_exact_half_width"])
            for name in ("D", "rg_mean", "rg_over_rmax")]
        lines.append("| " + " | ".join(cells) + " |")
    return lines + [""]


def _decades(n) -> str:
    """``a decade``, ``1.5 decades``."""
    return "a decade" if n == 1 else f"{n:g} decades"


def write_report(sweep, figures, path) -> Path:
    ds = sweep.ds
    last = len(sweep.counts) - 1
    rows = [(sweep.label(c), sweep.row(c, last)) for c in sweep.configs]
    deviations, differences = _deviation_table(sweep), _differences(sweep)
    attrs = sweep.s.attrs
    lines = [
        f"# {ds.attrs.get('title', 'dlasweep sweep')}",
        "",
        f"{sweep.n_clusters} clusters, {_stored(sweep)}; counts "
        f"{', '.join(map(str, sweep.counts))}; {ds.sizes['seed']} seeds per configuration; root seed "
        f"{ds.attrs.get('root_seed')}; {ds.attrs.get('source', 'dlasweep')}.",
        "",
        f"Intervals: {attrs['interval']}.",
        "",
        "## Result",
        "",
        f"Headline D at N = {sweep.counts[last]}: the ensemble mass-radius estimate (n ~ <Rg>^D fitted to the "
        "seed-averaged growth histories of every cluster that reached N, over the window of n stated), and "
        "D_inf, its extrapolation to infinite N where the data allow it:",
        "",
    ]
    for label, row in rows:
        inf = (f"D_inf = {_interval(row, 'D_inf')}" if np.isfinite(row["D_inf"])
               else f"no D_inf ({row['D_inf_reason']})")
        lines.append(f"- {label}: D = {_headline(row)}; {inf}.")
    lines += [
        "",
        "Box counting, a finite-cluster estimate that reads low (not an equal of the above): "
        + "; ".join(f"{label}: {_interval(row, 'D_box')}" for label, row in rows) + ".",
        "",
        f"Reference: 2D off-lattice DLA D = {REFERENCE_D[2]:.4f}(3) (Menshutin et al. 2008), 1.715(4) (Tolman and "
        f"Meakin 1989); 3D DLA about {REFERENCE_D[3]:.2f}. "
        f"This sweep: {sweep.dim}D {'lattice' if sweep.lattice else 'off-lattice'}.",
        "",
        *_against_reference(sweep, rows),
        "## How D is measured, and how far to trust it",
        "",
        "- **Mass-radius, ensemble** (the estimator to quote): <Rg>(n) averaged over seeds, from the end of "
        f"the transient ({START_FRACTION:.0%} of N) to N; the fit takes the widest window of at least "
        f"{_decades(MIN_DECADES)} whose local slope "
        "is flat within its own uncertainty. The CI is a bootstrap over seeds with that window fixed; no "
        "cluster is left out for its own fit. A window whose local slope is not flat is marked.",
        "- **Local slope and D_inf**: D_eff(n) over each octave of n with its bootstrap band (figure "
        "`dimension_vs_n`); D_inf fits D_eff = D_inf + a n^-w over independent octaves and is given only when "
        "that model describes the data and pins D_inf down.",
        "- **Box counting** on one finite cluster reads low: boxes at the cluster's edge are partly empty. "
        "Each cluster's fit gives a standard error that includes the drift of its local slope; the table "
        "gives the mean over every cluster and the share of fits that are flat.",
        "",
        *(["## Between configurations", "", *differences] if differences else []),
        *(["## Against the exact method", "", *deviations] if deviations else []),
        *branching_lines(sweep),
        *harmonic_lines(sweep),
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
        lines += ["Reproduce this report with", "",
                  f"    dlasweep report {os.path.relpath(source)} -o {os.path.relpath(path.parent)}", ""]
    path.write_text("\n".join(lines))
    return path
