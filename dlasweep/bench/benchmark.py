"""Kernel benchmarks: speed, memory and cost scaling, side by side in one run.

Each (model, N) runs in a fresh interpreter so that its peak memory is its
own, ``REPEATS`` times below ``HUGE_COUNT`` (the median kept); numba
compilation is excluded by growing a small cluster first (the kernels are
cached on disk), but in two rows of each model: ``cold``, a first grow of ``targets.COLD_COUNT``
particles on an empty numba cache, compiling included (what an editable install waits), and ``installed``,
the same first grow where the kernels were compiled ahead as the wheel's build compiles them
(``sweep.precompile``: what a user of the wheel built on the same machine waits). The naive
baseline (single steps everywhere, a kill circle at twice the launch radius) runs at small N
beside the exact method, so the gain is a ratio taken on the same machine at the same time.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
import xarray as xr

from ..data import netcdf
from ..data.schema import Variable
from .host import MEMORY_SET, READS, RUN_SET, latency_line, read_latency, shared_cache
from .targets import (
    COLD_COUNT,
    COLD_TARGET,
    MODELS,
    SCALING,
    cost_exponent,
    cost_exponent_range,
    exponent_attribute,
    exponent_parts,
    power_label,
    target_table,
    verdict,
)

MIB = "2^20 byte"
"""The units of memory sizes (MiB, which udunits does not know)."""

BESIDE_A_RUN = {"host_read": RUN_SET, "memory_read": MEMORY_SET}
"""The host's reads just before and after each run (``_beside_the_host``): the MiB each reads, by the
name of its variables (``host_read_before``, ``host_read_after``, ...) and of its column (``host ns``)."""
BENCH_SCHEMA = {
    "seconds": Variable(("run",), np.float64, "s",
                        "wall time to grow the cluster, compilation excluded but in the cold and installed rows"),
    "seconds_low": Variable(("run",), np.float64, "s", "fastest of the repeated runs of this model, method and N"),
    "seconds_high": Variable(("run",), np.float64, "s", "slowest of the repeated runs of this model, method and N"),
    "n_grown": Variable(("run",), np.int64, "1", "particles attached"),
    "walk_steps": Variable(("run",), np.int64, "1", "walk steps and jumps in all"),
    # MiB, in words udunits reads
    "peak_memory": Variable(("run",), np.float64, MIB, "peak resident memory of the process"),
    "added_memory": Variable(("run",), np.float64, MIB, "peak resident memory added by growing the cluster"),
    **{f"{reads}_{when}": Variable(("run",), np.float64, "ns", f"time of a read waiting on the last within {mib:g} "
                                   f"MiB, just {when} the run kept (dlasweep.bench.host.shared_cache)")
       for reads, mib in BESIDE_A_RUN.items() for when in ("before", "after")},
    "n": Variable(("run",), np.int64, "1", "target particle count"),
    "model": Variable(("run",), str, None, "model and dimension"),
    "method": Variable(("run",), str, None,
                       "exact jumps, the naive single-step walk with a kill circle, a growth law's parameter=value, "
                       "cold: the exact method's first grow on an empty numba cache, compiling included, or "
                       "installed: that first grow where the wheel's build compiled the kernels ahead"),
}
"""The variables of ``dlasweep bench``'s dataset (one ``run`` per measurement). A table of
its own: ``n_grown`` and ``walk_steps`` there count one cluster, not a sweep's prefixes."""


FIRST_GROWS = {"cold": "on a cold cache", "installed": "as the wheel installs it"}
"""The rows that time a fresh interpreter's first grow, compiling included (``probe``), and what each says."""

NAIVE = {"jumps": False, "kill_factor": 2.0}
COUNTS = {
    "lattice-2d": [10_000, 100_000, 1_000_000],
    "offlattice-2d": [10_000, 100_000, 1_000_000],
    "lattice-3d": [10_000, 100_000, 1_000_000],
    "offlattice-3d": [10_000, 100_000, 1_000_000],
}
FULL_COUNT = 10_000_000
"""``--full`` adds this N for every model."""
HUGE_COUNT = 100_000_000
"""``--huge`` adds this N for the 2D models (tens of minutes each)."""
REPEATS = 3
"""Fresh runs of each N below ``HUGE_COUNT``, of which the bench keeps the median time: the runs of
one cluster spread by more than a cost exponent's margin, as the host's other tenants take its cache
and memory (docs/performance.md, "Benchmark and host"). With ``FULL_COUNT``, the first N of
``SCALING`` runs as often again after it, so that its runs bracket the long one, since the host's
speed drifts over the minutes between a model's first runs and its last. The cost exponent is
given with the range its fit takes from the fastest and slowest runs of each N
(``cost_exponent_range``)."""
DRIFT = {"drift=0.01": {"drift": 0.01, "kill_factor": 2.0}}
"""Drift's row: a crossover length of 100 sites (diameters), inside a cluster of ``LAW_COUNT``; a point
seed under a drift needs a kill circle (``params``), here at twice the launch radius."""
LAWS = {
    "lattice-2d": {"noise_reduction=4": {"noise_reduction": 4}, "neighbour_alpha=0.2": {"neighbour_alpha": 0.2},
                   **DRIFT},
    "lattice-3d": {"noise_reduction=4": {"noise_reduction": 4}, "neighbour_alpha=0.5": {"neighbour_alpha": 0.5},
                   **DRIFT},
    "offlattice-2d": {"contact_distance=0.5": {"contact_distance": 0.5}, **DRIFT},
    "offlattice-3d": {"contact_distance=0.5": {"contact_distance": 0.5}, **DRIFT},
}
"""The growth laws each model runs at ``LAW_COUNT`` beside its exact method, named ``parameter=value``
as ``method`` (drift's with the kill circle it needs, ``DRIFT``): their cost beside plain DLA's at the
same N."""
LAW_COUNT = 1_000_000
NAIVE_COUNTS = [1_000, 3_000]
QUICK_COUNT = 2_000

_PROBE = """
import json, resource, sys, time
import dlasweep as dla

def peak_mb():
    # the process's own high-water mark: ru_maxrss would also count the
    # parent's, which a child inherits across fork and exec
    try:
        with open("/proc/self/status") as f:
            return next(int(line.split()[1]) for line in f if line.startswith("VmHWM")) / 1024
    except OSError:
        return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024

params = json.loads(sys.argv[1]); n = int(sys.argv[2]); seed = int(sys.argv[3])
if sys.argv[4:] != ["cold"]:
    dla.grow(50, seed=0, **params)  # load the compiled kernels
# (where numba's cache is cold it compiles them here, and the process keeps about 245 MB of that:
# 3D lattice 1e4 peaked at 410 MB, then 163 with the cache filled)
base = peak_mb()
t = time.perf_counter(); c = dla.grow(n, seed=seed, **params); dt = time.perf_counter() - t
peak = peak_mb()
print(json.dumps(dict(seconds=dt, n_grown=c.n, status=c.status, steps=int(c.steps.sum()),
                      peak_mb=peak, added_mb=peak - base)))
"""


def probe(params: dict, n: int, seed: int = 1, cold: bool = False, ahead: str | None = None) -> dict:
    """Grow one cluster of ``n`` with ``params`` from ``seed`` in a fresh interpreter.

    Returns its seconds (compile excluded), status, steps and peak memory;
    e.g. ``probe({"model": "lattice"}, 10_000_000)`` for the 1e7 figures. With
    ``cold``, the interpreter's numba cache is an empty folder and the seconds
    are those of its first grow, compiling included: what a new user waits. With ``ahead`` as well (a key
    of ``MODELS``), another interpreter first compiles that model's kernels into the empty folder as the
    wheel's build does (``sweep.precompile``): the first grow is then what a user of the wheel waits.
    """
    with tempfile.TemporaryDirectory() as cache:
        env = {**os.environ, "NUMBA_CACHE_DIR": cache} if cold else None
        if ahead is not None:
            subprocess.run([sys.executable, "-c", "import sys; from dlasweep.sweep.precompile import precompile; "
                            "precompile(sys.argv[1])", ahead], capture_output=True, text=True, check=True, env=env)
        out = subprocess.run(
            [sys.executable, "-c", _PROBE, json.dumps(params), str(n), str(seed), *(["cold"] if cold else [])],
            capture_output=True, text=True, check=True, env=env,
        )
    return json.loads(out.stdout.strip().splitlines()[-1])


def run_bench(full: bool = False, quick: bool = False, huge: bool = False, models=None, echo=print) -> xr.Dataset:
    """Time every model at several N; return the measurements as a Dataset.

    Parameters
    ----------
    full : bool
        Add ``FULL_COUNT`` for every model and end with the targets table
        (``target_table``).
    quick : bool
        Only the smallest N of each model (a smoke test), without the ``cold`` rows (each compiles
        its model's kernels).
    huge : bool
        Also add ``HUGE_COUNT`` for the 2D models (implies ``full``).
    models : list of str, optional
        Only these of ``MODELS`` (default: all); the naive walk runs beside lattice-2d.
    echo : callable
        Receives one line per measurement as it finishes.
    """
    full = full or huge
    models = list(MODELS) if models is None else list(dict.fromkeys(models))
    plan = []
    for name in models:
        params = MODELS[name]
        counts = [QUICK_COUNT] if quick else COUNTS[name] + ([FULL_COUNT] if full else [])
        counts += [HUGE_COUNT] if huge and "2d" in name else []
        counts += [SCALING[0]] if full and SCALING[0] in counts else []  # again, after the long runs
        plan += [] if quick else [(name, "cold", params, COLD_COUNT), (name, "installed", params, COLD_COUNT)]
        plan += [(name, "exact", params, n) for n in counts]
        plan += [(name, method, {**params, **law}, QUICK_COUNT if quick else LAW_COUNT)
                 for method, law in LAWS.get(name, {}).items()]
    naive_counts = ([QUICK_COUNT // 4] if quick else NAIVE_COUNTS) if "lattice-2d" in models else []
    for n in naive_counts:
        plan.append(("lattice-2d", "exact", MODELS["lattice-2d"], n))
        plan.append(("lattice-2d", "naive", {**MODELS["lattice-2d"], **NAIVE}, n))
    # ns/step: the cost of one walk step (or exact jump), which rises as the
    # grids near the walker outgrow the processor's caches.
    echo(f"{'model':<15}{'method':<7}{'N':>10}{'seconds':>10}{'particles/s':>13}{'steps/particle':>16}{'ns/step':>9}"
         f"{'peak MB':>9}{'added MB':>10}" + "".join(f"{reads.replace('_read', ' ns'):>11}" for reads in BESIDE_A_RUN))
    ends = {}
    runs = {}  # (model, method, N) -> its runs, in the order of the plan
    for name, method, params, n in plan:
        again = (name, method, n) in runs
        first = method in FIRST_GROWS  # once: a compile takes a minute, and spreads as the host's load does
        repeats = 1 if quick or first or n >= HUGE_COUNT else REPEATS
        runs.setdefault((name, method, n), []).extend(_beside_the_host(params, n, method, name) for _ in range(repeats))
        r = _median_run(runs[name, method, n])
        if first:
            echo(f"{name}: first grow of {n} {FIRST_GROWS[method]} {r['seconds']:.1f} s"
                 f"{verdict(r['seconds'], COLD_TARGET) if method == 'installed' else ''}")
            continue
        if again:
            echo(f"{name}: {n} again after the rest, {len(runs[name, method, n])} runs from "
                 f"{r['seconds_low']:.3f} to {r['seconds_high']:.3f} s, median {r['seconds']:.3f} s")
            continue
        echo(
            f"{name:<15}{method:<7}{n:>10}{r['seconds']:>10.3f}{r['n_grown'] / r['seconds']:>13.0f}"
            f"{r['steps'] / r['n_grown']:>16.1f}{r['seconds'] / r['steps'] * 1e9:>9.1f}{r['peak_mb']:>9.0f}"
            f"{r['added_mb']:>10.0f}" + "".join(f"{_host_cell(r, reads):>11}" for reads in BESIDE_A_RUN)
        )
        if n == HUGE_COUNT:
            with tempfile.TemporaryDirectory() as scratch:
                ends[name] = end_to_end(params, n, r["peak_mb"], scratch)
            echo(_end_to_end_line(name, n, ends[name]))
    rows = [{**_median_run(each), "model": name, "method": method, "n": n} for (name, method, n), each in runs.items()]
    ds = _to_dataset(rows)
    for name, figures in ends.items():
        ds.attrs.update({f"end_to_end_{name.replace('-', '_')}_{key}": value for key, value in figures.items()})
    for name in models:
        exact = ds.where((ds.model == name) & (ds.method == "exact"), drop=True)
        fitted = cost_exponent(exact)
        if fitted is not None:
            slope, lo, hi = fitted
            parts = exponent_parts(exact)
            ranged = dict(zip(("low", "high"), cost_exponent_range(exact)))
            ds.attrs[exponent_attribute(name)] = slope
            ds.attrs.update({exponent_attribute(name, part): value for part, value in {**parts, **ranged}.items()})
            echo(_exponent_line(name, slope, lo, hi, parts, ranged))
    for n in naive_counts:
        sel = ds.where(ds.n == n, drop=True)
        t = {str(m): float(s) for m, s in zip(sel.method.values, sel.seconds.values)}
        ratio = t["naive"] / t["exact"]
        ds.attrs[f"naive_over_exact_{n}"] = ratio
        echo(f"lattice-2d N={n}: naive walk takes {ratio:.1f}x the time of the exact-jump kernel")
    if "offlattice-2d" in models:
        ds.attrs.update(harmonic_bench(full=full, quick=quick, echo=echo, grown=runs))
    latency = read_latency(reads=READS // 10 if quick else READS)  # after the runs, on the same quiet host
    ds.attrs.update(host_read_mib=list(latency), host_read_ns=list(latency.values()))
    echo(latency_line(latency))
    if full:
        for line in target_table(ds):
            echo(line)
    return ds


HARMONIC_COUNTS = {"quick": (QUICK_COUNT, 10_000), "default": (100_000, 100_000), "full": (1_000_000, 1_000_000)}
"""(cluster size, walkers) of the harmonic-measure row: a small frozen cluster in the quick bench, 1e5 by
default, 1e6 under ``--full`` (walkers per second against a frozen cluster of 1e6)."""

_HARMONIC_PROBE = """
import json, sys, time
import dlasweep as dla

params = json.loads(sys.argv[1]); n = int(sys.argv[2]); walkers = int(sys.argv[3]); seed = int(sys.argv[4])
dla.harmonic_measure(dla.grow(50, seed=0, **params), 100, seed=0)  # load the compiled kernels
t = time.perf_counter(); c = dla.grow(n, seed=seed, **params); grown = time.perf_counter() - t
h = dla.harmonic_measure(c, walkers, seed=seed)
print(json.dumps(dict(n_grown=c.n, growth_seconds=grown, walkers=h.walkers, seconds=h.seconds, status=h.status)))
"""


def harmonic_probe(params: dict, n: int, walkers: int, seed: int = 1) -> dict:
    """Grow one cluster of ``n`` with ``params`` from ``seed`` and fire ``walkers`` at it, in a fresh interpreter.

    Returns the particles grown and the growth's seconds, and the walkers that stuck and their seconds
    (``HarmonicMeasure.seconds``), compilation excluded (a small cluster is grown and its walkers fired first), as
    ``probe`` does for growth alone.
    """
    out = subprocess.run([sys.executable, "-c", _HARMONIC_PROBE, json.dumps(params), str(n), str(walkers), str(seed)],
                         capture_output=True, text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def harmonic_bench(full: bool = False, quick: bool = False, echo=print, grown=None) -> dict:
    """Walkers per second of ``harmonic_measure`` against a frozen 2D off-lattice cluster, beside its growth.

    The cluster (``HARMONIC_COUNTS``) grows from seed 1, as ``probe``'s do, and the walkers are fired at
    it (``harmonic_probe``). The growth's particles per second at the same N is the median run's in
    ``grown`` (the bench's runs by (model, method, N)) when the bench grew that N, else this cluster's own.

    Parameters
    ----------
    full, quick : bool
        Which size (``HARMONIC_COUNTS``).
    echo : callable
        Receives the one line of the row.
    grown : dict, optional
        The bench's runs, by (model, method, N).

    Returns
    -------
    dict
        The dataset's attributes: ``harmonic_cluster``, ``harmonic_walkers``, ``harmonic_seconds``,
        ``harmonic_walkers_per_second`` and ``harmonic_growth_particles_per_second``.
    """
    n, walkers = HARMONIC_COUNTS["full" if full else "quick" if quick else "default"]
    run = harmonic_probe(MODELS["offlattice-2d"], n, walkers)
    growth = run["n_grown"] / run["growth_seconds"]
    runs = (grown or {}).get(("offlattice-2d", "exact", n))
    if runs:
        median = _median_run(runs)
        growth = median["n_grown"] / median["seconds"]
    rate = run["walkers"] / run["seconds"]
    echo(f"offlattice-2d harmonic measure: {run['walkers']:,} walkers against a frozen cluster of "
         f"{run['n_grown']:,} in {run['seconds']:.2f} s: {rate:,.0f} walkers/s (its growth: {growth:,.0f} "
         "particles/s)")
    return {"harmonic_cluster": run["n_grown"], "harmonic_walkers": run["walkers"], "harmonic_seconds": run["seconds"],
            "harmonic_walkers_per_second": rate, "harmonic_growth_particles_per_second": growth}


def _beside_the_host(params: dict, n: int, method: str = "exact", name: str | None = None) -> dict:
    """``probe``'s figures, with the host's read times (``BESIDE_A_RUN``) just before and after the run:
    ``method`` ``cold`` grows on an empty numba cache, ``installed`` where model ``name``'s kernels were
    compiled ahead (``FIRST_GROWS``), any other with the kernels loaded first."""
    before = _host_reads("before")
    if method in FIRST_GROWS:
        run = probe(params, n, cold=True, ahead=name if method == "installed" else None)
    else:
        run = probe(params, n)
    return {**run, **before, **_host_reads("after")}


def _host_reads(when: str) -> dict:
    """The host's reads (``BESIDE_A_RUN``) now, by their variables' names ending in ``when``."""
    return {f"{reads}_{when}": shared_cache(mib) for reads, mib in BESIDE_A_RUN.items()}


def _host_cell(run: dict, reads: str) -> str:
    """One of the host's read times about a run (``BESIDE_A_RUN``), before>after, in ns: a read slower after
    than before names a run the host's neighbours slowed."""
    return f"{run[reads + '_before']:.0f}>{run[reads + '_after']:.0f}"


def _median_run(runs) -> dict:
    """The run of median time among ``runs``, with the fastest and slowest times of them all."""
    ordered = sorted(runs, key=lambda run: run["seconds"])
    return {**ordered[len(ordered) // 2], "seconds_low": ordered[0]["seconds"], "seconds_high": ordered[-1]["seconds"]}


def _exponent_line(name, slope, lo, hi, parts, ranged) -> str:
    """One line: the cost exponent, its range (``cost_exponent_range``) and its parts (``exponent_parts``)."""
    return (f"{name}: time grows as N^{slope:.2f} [{ranged['low']:.2f}, {ranged['high']:.2f}] from "
            f"{power_label(lo)} to {power_label(hi)}: N particles "
            f"x N^{parts['steps']:.3f} steps a particle x N^{parts['step_cost']:.3f} ns a step")


def _end_to_end_line(name, n, figures) -> str:
    """One line: the sweep's and the report's peaks beside the growth's, each against ``END_TO_END_TARGET``."""
    return (f"{name} {power_label(n)} end to end: one-cluster sweep peak {figures['sweep_peak_mb']:.0f} MB, "
            f"{figures['sweep_ratio']:.2f}x the growth's{verdict(figures['sweep_ratio'], END_TO_END_TARGET)}; "
            f"its report {figures['report_peak_mb']:.0f} MB, "
            f"{figures['report_ratio']:.2f}x{verdict(figures['report_ratio'], END_TO_END_TARGET)}")


def _to_dataset(rows) -> xr.Dataset:
    """The measurements as a Dataset on ``run``, laid out and described by ``BENCH_SCHEMA``."""
    keys = {"walk_steps": "steps", "peak_memory": "peak_mb", "added_memory": "added_mb"}
    # a row of one run: its time is the fastest and the slowest; a row made up, not run: the host unread
    unread = {f"{reads}_{when}": np.nan for reads in BESIDE_A_RUN for when in ("before", "after")}
    rows = [{"seconds_low": r["seconds"], "seconds_high": r["seconds"], **unread, **r} for r in rows]
    columns = {name: (var.dims, np.array([r[keys.get(name, name)] for r in rows], dtype=var.dtype))
               for name, var in BENCH_SCHEMA.items()}
    coords = ("model", "method", "n")
    ds = xr.Dataset({name: column for name, column in columns.items() if name not in coords},
                    coords={name: columns[name] for name in coords},
                    attrs={"title": "dlasweep kernel benchmark",
                           "history": netcdf.provenance("dlasweep.bench.benchmark.run_bench")})
    return netcdf.describe(ds, BENCH_SCHEMA)


END_TO_END_TARGET = 1.3
"""A one-cluster sweep writing its file, and its report, may peak at most this many times the growth's own
(``probe``'s peak) at ``HUGE_COUNT``."""

_PEAK_OF = """
import resource, subprocess, sys
done = subprocess.run(sys.argv[1:], capture_output=True, text=True)
if done.returncode:
    sys.exit(done.stderr)
print(resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024)
"""
"""Runs a command and prints its peak resident memory (MiB): its largest process's, the sweep's own (one
cluster grows in the sweep's process), in a fresh parent so that no earlier child's counts."""


def _peak_of(argv) -> float:
    """The peak resident memory (MiB) of running ``argv`` (``_PEAK_OF``)."""
    done = subprocess.run([sys.executable, "-c", _PEAK_OF, *map(str, argv)], capture_output=True, text=True,
                          check=True)
    return float(done.stdout.strip().splitlines()[-1])


def end_to_end(params: dict, n: int, grown_peak: float, folder) -> dict:
    """A one-cluster sweep of ``n`` (``params``) and its report, as a user runs them, against the growth.

    Each runs as ``dlasweep sweep`` and ``dlasweep report`` in a fresh process, into ``folder``.

    Returns
    -------
    dict
        ``sweep_peak_mb`` and ``report_peak_mb``, and each over ``grown_peak`` (the growth's own peak,
        MiB, from ``probe``): ``sweep_ratio``, ``report_ratio``.
    """
    folder = Path(folder)
    spec = folder / f"end_to_end_{n}.toml"
    model = "".join(f"{key} = {json.dumps(value)}\n" for key, value in params.items())
    spec.write_text(f'name = "end-to-end"\n[grid]\nn_particles = [{n}]\nseeds = 1\n[model]\n{model}')
    out = folder / f"end_to_end_{n}.nc"
    sweep = _peak_of([sys.executable, "-m", "dlasweep", "sweep", spec, "-o", out])
    report = _peak_of([sys.executable, "-m", "dlasweep", "report", out, "-o", folder / f"end_to_end_{n}"])
    return {"sweep_peak_mb": sweep, "report_peak_mb": report, "sweep_ratio": sweep / grown_peak,
            "report_ratio": report / grown_peak}


REPORT_SPEC = """\
name = "report-bench"
[grid]
n_particles = [1000, 3000, 10000]
seeds = 64
[model]
model = "lattice"
dim = 2
[run]
root_seed = 1
"""
"""The sweep ``analysis_bench`` times, then reports: 64 lattice clusters of 1e4 particles."""
SWEEP_THREADS = 2
SWEEPS = [(1000, [100, 1000]), (64, [1000, 10_000]), (32, [10_000, 100_000]), (10_000, [1000])]
"""Sweeps of 2D lattice clusters whose whole-process time ``sweep_ratios`` sets
against their kernels': seeds and particle counts."""
RATIO_TARGET = (1.25, 2.0)
"""A sweep process should take at most 1.25 x ideal + 2 s (interpreter, imports, embedded cluster)."""


def sweep_spec(seeds: int, counts) -> str:
    """The spec (TOML text) of a 2D lattice sweep of ``seeds`` clusters, each recorded at ``counts``."""
    return (f'name = "bench"\n[grid]\nn_particles = {list(counts)}\nseeds = {seeds}\n'
            f'[model]\nmodel = "lattice"\ndim = 2\n[run]\nroot_seed = 1\n')


def sweep_efficiency(spec: str, out, threads: int = SWEEP_THREADS) -> dict:
    """Run ``dlasweep sweep`` on the spec text as a user would, in a fresh process, into ``out``.

    Returns the seconds of the whole process (interpreter, imports, the
    embedded cluster, every task, writing the netCDF: ``process``), the
    kernels' own seconds growing the clusters, summed (``kernels``), the
    ideal (``kernels / threads``), ``ratio`` (process / ideal) and the
    ``target`` for the process (``RATIO_TARGET``).
    """
    import time

    from ..data.netcdf import open_sweep

    path = Path(out).with_suffix(".toml")
    path.write_text(spec)
    start = time.perf_counter()
    subprocess.run([sys.executable, "-m", "dlasweep", "sweep", str(path), "-o", str(out), "--workers", str(threads)],
                   capture_output=True, text=True, check=True)
    process = time.perf_counter() - start
    with open_sweep(out) as ds:
        kernels = float(ds["wall_time"].isel(n_particles=-1).sum())
    ideal = kernels / threads
    return {"process": process, "kernels": kernels, "ideal": ideal, "ratio": process / ideal,
            "target": RATIO_TARGET[0] * ideal + RATIO_TARGET[1]}


def sweep_ratios(echo=print, sweeps=SWEEPS, threads: int = SWEEP_THREADS) -> dict:
    """``sweep_efficiency`` of each of ``sweeps`` ((seeds, counts) pairs), one line each.

    The target holds with the kernels' cache warm: an untimed sweep of two
    small clusters fills it first (after an install it compiles them).

    Returns ``sweep_<seeds>x<counts>_<figure>`` -> value (e.g. ``sweep_1000x100_1000_ratio``)
    for the figures of ``sweep_efficiency``.
    """
    import tempfile

    figures = {}
    echo(f"sweeps of 2D lattice clusters, whole process on {threads} threads, against ideal = kernels' sum / "
         f"{threads} (target: process <= {RATIO_TARGET[0]} x ideal + {RATIO_TARGET[1]:g} s)")
    with tempfile.TemporaryDirectory() as scratch:
        sweep_efficiency(sweep_spec(2, [10]), Path(scratch) / "warm.nc", threads)
        for seeds, counts in sweeps:
            name = f"{seeds}x{'_'.join(map(str, counts))}"
            eff = sweep_efficiency(sweep_spec(seeds, counts), Path(scratch) / f"{name}.nc", threads)
            figures.update({f"sweep_{name}_{key}": value for key, value in eff.items()})
            echo(f"  {seeds:>5} x {counts!s:<16} process {eff['process']:6.2f} s, "
                 f"kernels {eff['kernels']:6.2f} s, ideal {eff['ideal']:6.2f} s: ratio {eff['ratio']:4.2f}; "
                 f"target {eff['target']:6.2f} s "
                 + shortfall(eff["process"], eff["target"]))
    return figures


def shortfall(seconds: float, target: float) -> str:
    """"met", or by how much ``seconds`` is over ``target``, never "over by 0.00 s"."""
    over = seconds - target
    if over <= 0:
        return "met"
    return f"over by {over:.2f} s" if over >= 0.005 else f"over by {over * 1000:.1g} ms"


def _tiled_cluster(model: str, n: int = 100_000, tiles: int = 10) -> np.ndarray:
    """``tiles**2`` translated copies of one 2D cluster of ``n`` particles, 1.25 extents apart, copy after copy."""
    from ..growth.cluster import grow

    points = grow(n, seed=1, model=model, dim=2).points
    step = np.ceil(1.25 * (points.max(axis=0) - points.min(axis=0)).max())
    shifts = np.stack(np.meshgrid(np.arange(tiles), np.arange(tiles)), axis=-1).reshape(-1, 1, 2) * step
    return (points[None] + shifts.astype(points.dtype)).reshape(-1, 2)


def analysis_bench(echo=print) -> dict:
    """Time the measurement of a 1e7-particle 2D set and the report of a 64-cluster sweep.

    Growing one 1e7-particle cluster takes minutes, so a stand-in is
    timed: 100 translated copies (10 x 10, 1.25 cluster extents apart) of
    one 1e5-particle DLA cluster, lattice and off-lattice. Its extent (about
    16 000, against about 20 000 for one 1e7 cluster) and its box occupancy
    are close to a 1e7 cluster's, and they set the cost of box counting; the
    radius of gyration of every prefix costs the same for any 1e7 points
    (the D fitted to the copies means nothing). ``REPORT_SPEC`` is swept by
    ``sweep_efficiency`` (parallel efficiency, start-up included), then
    reported. Compilation is excluded from the measurement timings.

    Parameters
    ----------
    echo : callable
        Receives one line per measurement.

    Returns
    -------
    dict
        Wall seconds: ``box_<model>`` (``box_counts`` + ``fit_dimension``),
        ``rg_<model>`` (``radius_of_gyration`` + ``fit_mass_radius``) for
        ``lattice`` and ``offlattice``, ``sweep_*`` from ``sweep_ratios`` and ``sweep_efficiency``,
        and ``report``.
    """
    import tempfile
    import time

    from ..data.netcdf import open_sweep
    from ..measures.boxes import box_counts
    from ..measures.shape import radius_of_gyration
    from ..reporting.folder import report
    from ..stats.fit import fit_dimension, fit_mass_radius

    seconds = {}
    for model in ("lattice", "offlattice"):
        points = _tiled_cluster(model)
        lattice = model == "lattice"
        box_counts(points[:1000], lattice=lattice)  # load the compiled kernels
        radius_of_gyration(points[:10])
        start = time.perf_counter()
        fit = fit_dimension(*box_counts(points, lattice=lattice))
        seconds[f"box_{model}"] = time.perf_counter() - start
        start = time.perf_counter()
        fit_mass_radius(radius_of_gyration(points))
        seconds[f"rg_{model}"] = time.perf_counter() - start
        echo(f"{model} 2D, {len(points)} points: box counting + fit {seconds[f'box_{model}']:.2f} s (D={fit.D:.3f}), "
             f"Rg of every prefix + fit {seconds[f'rg_{model}']:.2f} s")
    seconds.update(sweep_ratios(echo))
    with tempfile.TemporaryDirectory() as scratch:
        eff = sweep_efficiency(REPORT_SPEC, Path(scratch) / "sweep.nc")
        seconds.update({f"sweep_{k}": v for k, v in eff.items()})
        echo(f"sweep of 64 clusters of 1e4 on {SWEEP_THREADS} threads: {eff['process']:.2f} s for the whole "
             f"process; kernels {eff['kernels']:.2f} s in all, ideal {eff['ideal']:.2f} s; ratio {eff['ratio']:.2f}")
        ds = open_sweep(Path(scratch) / "sweep.nc")
        start = time.perf_counter()
        report(ds, Path(scratch) / "report")
        seconds["report"] = time.perf_counter() - start
        ds.close()
    echo(f"report of a {ds.sizes['cluster']}-cluster sweep (N up to {int(ds['n_particles'].max())}): "
         f"{seconds['report']:.1f} s")
    return seconds
