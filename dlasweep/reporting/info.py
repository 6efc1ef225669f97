"""What ``dlasweep info`` says of a file: a sweep, one grown cluster or a benchmark, in the project's words.

Reads an opened dataset (``netcdf.open_dataset``) and returns lines of text;
the command line prints them under the file's history.
"""

from __future__ import annotations

import numpy as np

from .. import params
from ..bench.host import latency_line
from ..bench.targets import exponent_attribute
from ..data import ragged, schema
from ..measures.shape import radius_of_gyration
from ..stats.constants import LEVEL
from ..stats.fit import fit_mass_radius
from ..stats.summary import summarise


def lines(ds) -> list:
    """What ``info`` says of a dataset, by kind: a benchmark (dimension ``run``), a sweep, or one cluster."""
    return _bench(ds) if "run" in ds.dims else _sweep(ds) if schema.is_sweep(ds) else _cluster(ds)


def _sweep(ds) -> list:
    """What ``info`` says of a sweep: spec, axes, counts, statuses, failures, headline D."""
    fixed = [name for name in params.PARAMETERS if name in ds.coords and ds[name].ndim == 0]
    lines = ["spec:", *(f"  {line}" for line in ds.attrs["spec"].rstrip().splitlines()),
             "axes:", *(f"  {name:<12} {ds.sizes[name]:>4}: {_values(ds[name].values)}"
                        for name in ds["box_count"].dims),
             "fixed: " + " ".join(f"{name}={params.text(ds[name].values)}" for name in fixed),
             f"clusters: {ds.sizes['cluster']} stored, {ds.sizes['particle']} particles",
             "status (clusters at each count):"]
    full = summarise(ds)
    tally = full["status_count"].sum([d for d in full["status_count"].dims if d not in ("n_particles", "status")])
    for n in ds["n_particles"].values:
        counts = tally.sel(n_particles=n).values
        lines.append(f"  {n:>10}: " + ", ".join(f"{flag} {k}" for flag, k in zip(schema.STATUS_FLAGS, counts) if k))
    failed = [task for task in ds.attrs.get("failed_tasks", "").split("; ") if task]
    lines += [f"failed tasks: {len(failed) or 'none'}", *(f"  {task}" for task in failed)]
    if "stop_reason" in ds.attrs:
        lines.append(f"stopped: {ds.attrs['stop_reason']} (target_ci {ds.attrs['target_ci']}, "
                     f"max_seeds {ds.attrs['max_seeds']})")

    summary = full.isel(n_particles=-1)
    config = list(summary["D_inf"].dims)
    header = [*config, "N", "seeds", "D", f"{LEVEL} CI", "D_inf"]
    rows = []
    for index in np.ndindex(summary["D_inf"].shape):
        at = summary.isel(dict(zip(config, index)))
        d_inf = (f"{_number(at['D_inf'])} [{_number(at['D_inf_ci_lo'])}, {_number(at['D_inf_ci_hi'])}]"
                 if np.isfinite(at["D_inf"]) else f"none: {at['D_inf_reason'].item()}")
        rows.append([*(params.text(at[name].values) for name in config), str(int(at["n_particles"])),
                     str(int(at["D_seeds"])), _number(at["D"]),
                     f"[{_number(at['D_ci_lo'])}, {_number(at['D_ci_hi'])}]", d_inf])
    return [*lines, f"headline D at the largest N (ensemble mass-radius, {LEVEL} CI over seeds):",
            *_table(header, rows)]


def _cluster(ds) -> list:
    """What ``info`` says of one grown cluster: parameters, particles, status, its own D."""
    points = ragged.cluster_points(ds, 0)
    fit = fit_mass_radius(radius_of_gyration(points))
    window = f"n in [{fit.range_lo:g}, {fit.range_hi:g}]" if fit.ok else f"not flat: {fit.reason}"
    return [f"seed: {ds.attrs['seed']}",
            "parameters: " + " ".join(f"{name}={params.text(ds[name].values)}" for name in params.PARAMETERS),
            f"particles: {len(points)}, status {schema.STATUS_FLAGS[int(ds['status'][0])]}",
            f"D of this cluster (mass-radius, {LEVEL} CI): {_number(fit.D)} "
            f"[{_number(fit.ci_lo)}, {_number(fit.ci_hi)}], {window}"]


def _bench(ds) -> list:
    """What ``info`` says of a benchmark: its runs, each model's largest exact run and cost exponent."""
    model, method, n = ds["model"].values.astype(str), ds["method"].values.astype(str), ds["n"].values
    lines = [f"runs: {ds.sizes['run']} (" + ", ".join(f"{k} {int((method == k).sum())}"
                                                      for k in dict.fromkeys(method)) + ")"]
    rows = []
    for name in dict.fromkeys(model):
        exact = np.flatnonzero((model == name) & (method == "exact"))
        top = exact[np.argmax(n[exact])]
        exponent = ds.attrs.get(exponent_attribute(name))
        rows.append([name, _values(np.sort(n[exact])), f"{n[top]}", f"{float(ds['seconds'][top]):.3g}",
                     f"{float(ds['peak_memory'][top]):.0f}", "" if exponent is None else f"{exponent:.2f}"])
    ratios = {k.removeprefix("naive_over_exact_"): v for k, v in ds.attrs.items() if k.startswith("naive_over_exact_")}
    host = ([latency_line(dict(zip(np.atleast_1d(ds.attrs["host_read_mib"]), np.atleast_1d(ds.attrs["host_read_ns"]))))]
            if "host_read_ns" in ds.attrs else [])
    return [*lines, *_table(["model", "N (exact)", "largest", "seconds", "peak MiB", "time ~ N^"], rows),
            "naive walk / exact jumps, time: " + (", ".join(f"N={k} {v:.1f}x" for k, v in ratios.items()) or "none"),
            *host]


def _table(header, rows) -> list:
    """Rows of text cells as aligned lines, indented under a header."""
    widths = [max(map(len, column)) for column in zip(header, *rows)]
    return ["  " + "  ".join(cell.ljust(w) for cell, w in zip(row, widths)).rstrip() for row in (header, *rows)]


def _values(values) -> str:
    """An axis's values; consecutive integers as ``first..last``, a long list as a sketch of it."""
    if values.dtype.kind in "iu" and len(values) > 3 and (np.diff(values) == 1).all():
        return f"{values[0]}..{values[-1]}"
    long = len(values) > 8
    shown = [f"{v:.4g}" if long and values.dtype.kind == "f" else params.text(v) for v in values]
    return ", ".join([*shown[:4], "...", shown[-1]] if long else shown)


def _number(value) -> str:
    return f"{float(value):.3f}" if np.isfinite(value) else "n/a"
