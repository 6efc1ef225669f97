"""The report's branching: the figure of branch counts against Horton-Strahler order, and the table of
bifurcation ratios (``stats.branches.summary``'s numbers, drawn; nothing computed here)."""

from __future__ import annotations

import numpy as np

from ..measures.tree import MIN_BRANCHES
from ..stats.branches import ratio_line
from ..stats.constants import LEVEL
from .figures import colour_of, new_figure, save_figure

LITERATURE = {2: "5.2 in simulations and 4.9 from the branched-growth model (both quoted by Halsey 1997)"}
"""Published bifurcation ratios of DLA, by dimension (falling towards 3.1 in high dimension)."""
_MAX_LINES = 10


def _shown(sweep) -> list:
    if "branch_count" not in sweep.s:
        return []
    return [c for c in sweep.configs if np.isfinite(sweep.at("bifurcation_ratio", c))][:_MAX_LINES]


def _ratio(sweep, config, name="bifurcation_ratio") -> str:
    value, lo, hi = (float(sweep.at(f"{name}{end}", config)) for end in ("", "_ci_lo", "_ci_hi"))
    if not np.isfinite(value):
        return "-"
    return f"{value:.2f} [{lo:.2f}, {hi:.2f}]" if np.isfinite(lo) else f"{value:.2f} (no CI)"


def branching_figure(sweep, path):
    """Mean branch counts per order, log scale, each configuration with its fitted ratio; None without parents."""
    shown = _shown(sweep)
    if not shown:
        return None
    fig, (ax,) = new_figure(1, 6.5, 4.2)
    orders = sweep.s["order"].values
    for i, config in enumerate(shown):
        counts = sweep.at("branch_count", config)
        keep = np.isfinite(counts) & (counts > 0)
        ratio = float(sweep.at("bifurcation_ratio", config))
        ax.semilogy(orders[keep], counts[keep], "o", color=colour_of(i),
                    label=f"{sweep.label(config)}: R_b = {_ratio(sweep, config)}, "
                          f"{int(sweep.at('branch_clusters', config))} clusters")
        ax.semilogy(orders[keep], ratio_line(counts[keep], ratio), "-", color=colour_of(i), lw=1)
    ax.set_xlabel("Horton-Strahler order k")
    ax.set_ylabel("branches of order k, mean over clusters")
    ax.set_xticks(orders)
    ax.legend(fontsize=7)
    ax.set_title(f"Branching of the stored clusters at N={sweep.counts[-1]}", fontsize=9)
    save_figure(fig, path)
    literature = LITERATURE.get(sweep.dim)
    return ("Branches of each Horton-Strahler order (points: mean over the stored clusters) and the line "
            "falling by the bifurcation ratio R_b an order (R_b: mean over clusters of each one's fit over "
            f"the orders with at least {MIN_BRANCHES} branches, with its {LEVEL} CI; the highest orders of a finite "
            "cluster are cut short)."
            + (f" 2D DLA: R_b is {literature}." if literature else ""))


def branching_lines(sweep) -> list:
    """The report's section on branching: a row per configuration; empty without parents."""
    shown = [c for c in sweep.configs if "branch_count" in sweep.s and int(sweep.at("branch_clusters", c))]
    if not shown:
        return []
    literature = LITERATURE.get(sweep.dim)
    lines = ["## Branching", "",
             f"The stored clusters as trees (each particle's parent: the one it stuck to), at N = "
             f"{sweep.counts[-1]}. R_b: Horton-Strahler bifurcation ratio; d_l: chemical-distance dimension "
             f"(particles within l bonds of the seed ~ l^d_l); means over clusters with {LEVEL} CIs."
             + (f" Published for 2D DLA: R_b = {literature}." if literature else ""), "",
             "| configuration | clusters | highest order | R_b | d_l |", "|---|---|---|---|---|"]
    orders = sweep.s["order"].values
    for config in shown:
        counts = sweep.at("branch_count", config)
        top = int(orders[np.isfinite(counts) & (counts > 0)].max())
        lines.append(f"| {sweep.label(config)} | {int(sweep.at('branch_clusters', config))} | {top} | "
                     f"{_ratio(sweep, config)} | {_ratio(sweep, config, 'chemical_dimension')} |")
    return [*lines, ""]
