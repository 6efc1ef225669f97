"""The benchmark's targets, and the fits a benchmark's runs are held to: the cost
exponent (its range over the runs and its parts, steps and the cost of a
step) and the table of each figure beside its target (``dlasweep bench --full``).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ..params import MODEL_KINDS

if TYPE_CHECKING:
    import xarray as xr

MODELS = MODEL_KINDS
"""The models ``dlasweep bench`` grows, by the names its targets, tables and ``--model`` use. This
module loads neither xarray nor numba: the CLI reads the names while it builds its options."""
PARENT_BYTES = 4
"""Each particle's parent (an int32), which the memory targets allow beside their own."""
TARGETS = {
    "lattice-2d": {"seconds": {10**7: 60, 10**8: 900}, "bytes": {10**7: 20 + PARENT_BYTES, 10**8: 20 + PARENT_BYTES},
                   "exponent": 1.06},
    "offlattice-2d": {"seconds": {10**7: 90, 10**8: 1200},
                      "bytes": {10**7: 28 + PARENT_BYTES, 10**8: 28 + PARENT_BYTES}, "exponent": 1.06},
    "lattice-3d": {"seconds": {10**7: 180}, "bytes": {10**7: 48 + PARENT_BYTES}, "exponent": 1.10},
    "offlattice-3d": {"seconds": {10**7: 300}, "bytes": {10**7: 48 + PARENT_BYTES}, "exponent": 1.10},
}
"""The targets on one core: seconds to grow (compile excluded) and
memory added by growth per particle (bytes) at each N, and the cost exponent
over ``SCALING``."""
COLD_COUNT = 1_000
"""Particles of the ``cold`` and ``installed`` rows' first grow (``benchmark.probe``)."""
COLD_TARGET = 10.0
"""Seconds a new user's first ``dlasweep grow`` of ``COLD_COUNT`` particles may take, where the kernels are
as the wheel installs them: the ``installed`` row (the ``cold`` row, compiling from an empty cache, is
shown beside it without a target)."""
SCALING = (10**5, 10**7)
"""The cost exponent is fitted from the first N to the second, and steps per particle compared between them."""
STEPS_GROWTH_TARGET = 1.40
"""Steps per particle may grow at most like log N: from 1e5 to 1e7 by at most 40%."""


def verdict(value, target):
    """``value`` beside its target: met, or over by how much."""
    if target is None:
        return ""
    if not np.isfinite(value):
        return f" (target {target:g})"
    over = value / target - 1
    # under 1%, one decimal: "0% over" would read as met
    return f" (<= {target:g}: met)" if over <= 0 else f" (<= {target:g}: {over:.{0 if over >= 0.01 else 1}%} over)"


def power_label(n: int) -> str:
    """``1e7`` for 10**7."""
    return f"1e{len(str(n)) - 1}"


def target_table(ds: xr.Dataset) -> list[str]:
    """The targets' table: seconds at 1e7 and 1e8, memory added per particle
    there, the cost exponent and the growth of steps per particle from 1e5
    to 1e7, each beside its target (markdown rows)."""
    from ..data.schema import plain

    counts = sorted({n for t in TARGETS.values() for n in t["seconds"]})
    sizes = sorted({n for t in TARGETS.values() for n in t["bytes"]})
    lo, hi = SCALING
    head = ["model", *(f"{power_label(n)} s" for n in counts),
            *(f"bytes/particle at {power_label(n)}" for n in sizes),
            f"cost exponent {power_label(lo)} to {power_label(hi)}",
            f"steps/particle {power_label(hi)} over {power_label(lo)}"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    benched = {str(plain(v)) for v in ds.model.values}
    for name, target in TARGETS.items():
        if name not in benched:
            continue
        exact = ds.where((ds.model == name) & (ds.method == "exact"), drop=True)
        row = [name]

        def at(n, exact=exact):
            pick = exact.where(exact.n == n, drop=True)
            return pick.isel(run=0) if pick.sizes["run"] else None

        def cell(value, goal):
            return f"{value:.1f}{verdict(value, goal)}"

        for n in counts:
            r = at(n)
            row.append("" if r is None else cell(float(r.seconds), target["seconds"].get(n)))
        for n in sizes:
            r = at(n)
            row.append("" if r is None else cell(float(r.added_memory) * 2**20 / n, target["bytes"].get(n)))
        first, last = at(lo), at(hi)
        if first is None or last is None:
            row += ["", ""]
        else:
            slope = cost_exponent(exact)[0]
            low, high = cost_exponent_range(exact)
            growth = (float(last.walk_steps) / float(last.n_grown)) / (float(first.walk_steps) / float(first.n_grown))
            row += [f"{slope:.2f} [{low:.2f}, {high:.2f}]{verdict(slope, target['exponent'])}",
                    f"{growth:.2f}{verdict(growth, STEPS_GROWTH_TARGET)}"]
        lines.append("| " + " | ".join(row) + " |")
    return lines


def cost_exponent(exact: xr.Dataset) -> tuple[float, int, int] | None:
    """The slope of log time against log N over one model's exact runs with N in ``SCALING``, and the
    smallest and largest N fitted; None with fewer than two such N.

    The runs below (1e4, and lattice 2D's 1e3 and 3e3 beside the naive walk) are left out: their
    grids fit the caches, and they would lower the slope that the targets are set on.
    """
    fit = _in_scaling(exact)
    n = fit.n.values.astype(float)
    if len(np.unique(n)) < 2:
        return None
    return _slope(fit, fit.seconds), int(n.min()), int(n.max())


def cost_exponent_range(exact: xr.Dataset) -> tuple[float, float]:
    """The lowest and highest slopes ``cost_exponent``'s fit takes with each N's fastest or slowest run.

    The least-squares slope is a weighted sum of the log times, with weights of the sign of log N
    less its mean: the lowest takes the slowest runs below the mean and the fastest above it; the
    highest the other way round. The host's noise over the bench, not an error of the law.
    """
    fit = _in_scaling(exact)
    log_n = np.log(fit.n.astype(float))
    above = log_n > log_n.mean()
    lowest = fit.seconds_low.where(above, fit.seconds_high)
    highest = fit.seconds_high.where(above, fit.seconds_low)
    return _slope(fit, lowest), _slope(fit, highest)


def exponent_parts(exact: xr.Dataset) -> dict[str, float]:
    """The cost exponent split as time = N x steps a particle x seconds a step: the slopes of the last
    two over the same runs as ``cost_exponent``, which add up to its slope less one (least squares
    is linear in the logs). Steps grow like log N with any walk-on-spheres walk; the cost of a step
    grows as the grids outgrow the caches."""
    fit = _in_scaling(exact)
    return {"steps": _slope(fit, fit.walk_steps / fit.n_grown), "step_cost": _slope(fit, fit.seconds / fit.walk_steps)}


def _in_scaling(exact: xr.Dataset) -> xr.Dataset:
    """The runs with N in ``SCALING``."""
    lo, hi = SCALING
    return exact.where((exact.n >= lo) & (exact.n <= hi), drop=True)


def _slope(fit: xr.Dataset, values: xr.DataArray) -> float:
    """The least-squares slope of log ``values`` against log N."""
    return float(np.polyfit(np.log(fit.n.values.astype(float)), np.log(values.values.astype(float)), 1)[0])


def exponent_attribute(model: str, part: str = "") -> str:
    """The global attribute holding ``model``'s cost exponent, ``cost_exponent_lattice_2d`` (CF: no
    hyphens), one of its ``exponent_parts``, ``cost_exponent_steps_lattice_2d``, or an end of its range
    (``cost_exponent_range``), ``cost_exponent_low_lattice_2d``."""
    return f"cost_exponent_{part + '_' if part else ''}{model.replace('-', '_')}"
