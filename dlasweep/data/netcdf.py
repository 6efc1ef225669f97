"""The netCDF side of dlasweep: datasets assembled, written atomically, opened and checked.

The layout and every variable's attributes are ``schema``'s; reading one
cluster back is ``ragged``'s. This module is the only one that knows netCDF.
"""

from __future__ import annotations

import contextlib
import contextvars
import datetime
import os
import shlex
import signal
import threading
from pathlib import Path

import netCDF4
import numpy as np
import xarray as xr

from .. import params as _params
from .._version import FORMAT, __version__
from ..params import one_line
from .paths import writable
from .schema import (
    AXES,
    BOOLEAN,
    HARMONIC,
    HARMONIC_Q,
    SCHEMA,
    SCIENCE,
    STATUS_FLAGS,
    StoreError,
    attributes,
    dims,
    ragged_columns,
    ragged_dtype,
)


def to_dataset(spec, tasks, scales, history, science, cluster_particles, failed=()) -> xr.Dataset:
    """Assemble a sweep's results into the layout of README, "The dataset", clusters aside.

    The per-particle variables are added by ``with_clusters`` (in memory)
    or streamed into the file by ``save``.

    Parameters
    ----------
    spec : dlasweep.sweep.spec.Spec
    tasks : list of the stored clusters' ``dlasweep.sweep.spec.Task`` (``spec.stores``), in task (C) order
    scales : ndarray, (n_scales,)
    history : ndarray of int, (n_history,)
        Counts of the growth history (``fit.growth_counts``).
    science : dict of ndarray
        ``box_count`` on ``(<axes>..., size, n_particles, seed, scale)``,
        ``radius_gyration_history`` on ``(<axes>..., size, seed, history)``,
        the other quantities (``SCIENCE`` and ``wall_time``) on
        ``(<axes>..., size, n_particles, seed)``. ``status`` holds integer
        codes (index into ``STATUS_FLAGS``). With the harmonic measurement
        (``HARMONIC``, ``[measure] harmonic_walkers``), its variables on
        ``(<axes>..., size, seed[, q])``, and the coordinate ``q`` is added.
    cluster_particles : ndarray, (n_stored,)
        Particles per stored cluster (``spec.stores``), in task (C) order.
    failed : sequence of (str, str)
        Task keys and error messages of tasks that raised.

    Returns
    -------
    xarray.Dataset
    """
    coords = {
        **{name: (name, _coordinate(values)) for name, values in spec.axes.items()},
        "size": ("size", np.asarray(spec.sizes, SCHEMA["size"].dtype)),
        "n_particles": ("n_particles", np.asarray(spec.counts, SCHEMA["n_particles"].dtype)),
        "seed": ("seed", np.asarray(spec.seeds, SCHEMA["seed"].dtype)),
        "scale": ("scale", np.asarray(scales, SCHEMA["scale"].dtype)),
        "history": ("history", np.asarray(history, SCHEMA["history"].dtype)),
    }
    fixed = {name: spec.resolved(name) for name in _params.DEFAULTS if name not in spec.axes and name != "size"}
    coords.update((name, ((), value)) for name, value in fixed.items())
    for name in (*spec.axes, "size"):
        # of the axis's type, also when no cluster is stored
        coords[f"cluster_{name}"] = ("cluster", _coordinate([t.params[name] for t in tasks], coords[name][1].dtype))
    coords["cluster_seed"] = ("cluster", np.asarray([t.seed for t in tasks], SCHEMA["cluster_seed"].dtype))
    coords["cluster"] = ("cluster", np.arange(len(tasks), dtype=SCHEMA["cluster"].dtype))

    harmonic = tuple(name for name in HARMONIC if name in science)
    if harmonic:
        coords["q"] = ("q", np.asarray(HARMONIC_Q, SCHEMA["q"].dtype))
    data = {name: (dims(name, tuple(spec.axes)), science[name]) for name in (*SCIENCE, "wall_time", *harmonic)}
    data["cluster_particles"] = ("cluster", np.asarray(cluster_particles))
    attrs = {
        "title": f"dlasweep parameter sweep '{spec.name}': diffusion-limited aggregation clusters",
        "history": provenance("dlasweep.run_sweep"),
        "spec": spec.text,
        "root_seed": spec.root_seed,
    }
    if failed:
        attrs["failed_tasks"] = "; ".join(f"{key}: {message}" for key, message in failed)
    return _describe(xr.Dataset(data, coords=coords, attrs=attrs))


def record_stop(ds, half_width, target_ci, max_seeds, reason) -> xr.Dataset:
    """Add why a target sweep (``[run] target_ci``) stopped to its dataset.

    Parameters
    ----------
    ds : xarray.Dataset
        From ``to_dataset``.
    half_width : xarray.DataArray
        ``D_ci_half_width`` on ``(<swept params>..., size)``: the precision
        reached per configuration (NaN: no interval).
    target_ci : float
    max_seeds : int
        The spec's target and seed cap, recorded as global attributes.
    reason : str
        ``stop_reason``: "target_ci reached", "max_seeds reached" or
        "tasks failed".

    Returns
    -------
    xarray.Dataset
    """
    ds["D_ci_half_width"] = half_width
    ds.attrs.update(target_ci=target_ci, max_seeds=max_seeds, stop_reason=reason)
    return _describe(ds)


def cluster_dataset(cluster, seed) -> xr.Dataset:
    """One grown cluster in the same ragged layout as a sweep (one ``cluster``).

    Parameters
    ----------
    cluster : dlasweep.Cluster
    seed : int
        The seed it was grown with.
    """
    points = cluster.points
    coords = {name: ((), value) for name, value in cluster.params.items()}
    coords["cluster_seed"] = ("cluster", np.asarray([seed], SCHEMA["cluster_seed"].dtype))
    coords["cluster"] = ("cluster", np.zeros(1, SCHEMA["cluster"].dtype))
    data = {
        "cluster_particles": ("cluster", np.asarray([len(points)])),
        "status": ("cluster", np.asarray([STATUS_FLAGS.index(cluster.status)], np.int8)),
        **{a: ("particle", _positions(points[:, k])) for k, a in enumerate(AXES[: points.shape[1]])},
        "diffusion_time": ("particle", np.asarray(cluster.steps, SCHEMA["diffusion_time"].dtype)),
        "parent": ("particle", np.asarray(cluster.parents, np.int32)),
    }
    attrs = {
        "title": "dlasweep: one diffusion-limited aggregation cluster",
        "history": provenance("dlasweep.data.netcdf.cluster_dataset"),
        "seed": int(seed),
    }
    return _describe(xr.Dataset(data, coords=coords, attrs=attrs))


def with_clusters(ds: xr.Dataset, clusters) -> xr.Dataset:
    """``ds`` (from ``to_dataset``) with its stored clusters as per-particle variables in memory.

    Parameters
    ----------
    ds : xarray.Dataset
        The sweep's dataset without its clusters (``to_dataset``).
    clusters : iterable of (ndarray, ndarray, ndarray)
        Each stored cluster's points ``(n, dim)``, diffusion times and
        parents, in ``cluster`` order.
    """
    columns = ragged_columns(ds["model"], ds["dim"])
    ragged = {name: np.zeros(int(ds["cluster_particles"].sum()), dtype) for name, dtype in columns.items()}
    start = 0
    for points, times, parents in clusters:
        for name, values in _cluster_columns(columns, points, times, parents).items():
            ragged[name][start:start + len(times)] = values
        start += len(times)
    return _describe(ds.assign({name: ("particle", values) for name, values in ragged.items()}))


def _cluster_columns(columns, points, times, parents) -> dict:
    """One cluster's values of each of ``columns``; 2D points get z = 0 among 3D columns."""
    axes = [name for name in columns if name in AXES]
    return {**{a: points[:, k] if k < points.shape[1] else np.zeros(len(points), points.dtype)
               for k, a in enumerate(axes)}, "diffusion_time": times, "parent": parents}


PARTICLE_CHUNK = 1 << 16
"""Values per HDF5 chunk of a per-particle variable.

Larger chunks barely shrink a file, while reading one cluster decompresses more
that it does not need (``workflows/ragged_encoding.py``; docs/performance.md,
"Data files")."""
PARTICLE_ZLIB = 1
"""zlib level of the per-particle variables (shuffled as ``shuffled`` says).

Level 1 takes most of what zlib can take off a file for a small share of the
time a sweep takes to grow its clusters; higher levels save little more at
several times the time (docs/performance.md, "Data files")."""


def shuffled(dtype) -> bool:
    """Whether a per-particle variable of this type is byte-shuffled before zlib: all but lattice sites.

    Shuffling makes diffusion times and off-lattice positions smaller and faster
    to write; lattice sites it makes no smaller (docs/performance.md, "Data files").

    Parameters
    ----------
    dtype : numpy dtype or str
        The type of the variable's values.
    """
    return np.dtype(dtype) != np.dtype(ragged_dtype(True))


def save(ds: xr.Dataset, path, clusters=None) -> None:
    """Write ``ds`` to netCDF-4 with zlib, atomically, the per-particle variables streamed.

    The file is written under a temporary name in the target folder and
    renamed, so the final name never holds a partial file. The
    per-particle variables go in ``PARTICLE_CHUNK`` values at a time, each
    a whole compressed chunk, so they are never all in memory
    (``ParticleWriter``).

    Parameters
    ----------
    ds : xarray.Dataset
    path : path
    clusters : iterable of (ndarray, ndarray, ndarray), optional
        For a sweep from ``to_dataset``: each stored cluster's points,
        diffusion times and parents, in ``cluster`` order, written as they come.
        Default: ``ds``'s own per-particle variables, if any.
    """
    path = writable(path)
    particle = [name for name, var in ds.variables.items() if var.dims == ("particle",)]
    columns = ragged_columns(ds["model"], ds["dim"]) if clusters is not None else {
        name: ds[name].dtype for name in particle}
    writer = ParticleWriter(path.with_name(f"{path.name}.tmp{os.getpid()}"), columns)
    try:
        if clusters is not None:
            for cluster in clusters:
                writer.add(*cluster)
        else:
            for i in range(0, ds.sizes.get("particle", 0), PARTICLE_CHUNK):
                writer.add_columns({name: ds[name][i:i + PARTICLE_CHUNK].values for name in particle})
        writer.finish(ds, path)
    finally:
        writer.discard()


class ParticleWriter:
    """A dataset's netCDF file in the making: first its per-particle variables,
    filled cluster after cluster, then (``finish``) the rest, renamed into place.

    Each write is a whole ``PARTICLE_CHUNK`` of values, compressed as it is
    written; netCDF lets other threads run meanwhile, so a sweep stores the
    clusters that finished while it grows the next ones.

    Parameters
    ----------
    tmp : path
        Where the file lies until ``finish``; ``discard`` removes it.
    columns : dict
        The per-particle variables and their types (``ragged_columns``);
        none: the file has no ``particle`` dimension.
    """

    def __init__(self, tmp, columns: dict):
        self.tmp = Path(tmp)
        self.written = 0
        self._variables, self._buffer, self._filled = {}, {}, 0
        cache = netCDF4.get_chunk_cache()
        # No chunk cache (netCDF's setting for the files it opens next): each whole
        # chunk is compressed as it is written, not all of them at close.
        with _signals_held():  # createVariable's lookup of dimensions (utils._find_dim) has bare excepts too
            netCDF4.set_chunk_cache(0)
            try:
                self._nc = netCDF4.Dataset(self.tmp, "w", format="NETCDF4")
                if columns:
                    self._nc.createDimension("particle", None)  # its length is known at the end
                for name, dtype in columns.items():
                    # Never missing, so no fill value (as the counts).
                    var = self._nc.createVariable(name, dtype, ("particle",), zlib=True, complevel=PARTICLE_ZLIB,
                                                  shuffle=shuffled(dtype), chunksizes=(PARTICLE_CHUNK,),
                                                  fill_value=False)
                    var.setncatts(attributes(name, dtype))
                    self._variables[name] = var
                    self._buffer[name] = np.empty(PARTICLE_CHUNK, dtype)
                axes = [name for name in columns if name in AXES]
                for name, var in self._variables.items():
                    if name not in axes:  # what xarray writes for the coordinates x, y (z) of a variable
                        var.setncattr("coordinates", " ".join(axes))
            finally:
                netCDF4.set_chunk_cache(*cache)

    def add(self, points, times, parents):
        """Append one cluster: its points ``(n, dim)`` (2D ones get z = 0 among 3D columns), diffusion times and
        parents."""
        self.add_columns(_cluster_columns(self._variables, points, times, parents))

    def add_columns(self, block: dict):
        """Append values of every per-particle variable (arrays of one length); whole chunks are written."""
        n, done = len(next(iter(block.values()))), 0
        while done < n:
            take = min(PARTICLE_CHUNK - self._filled, n - done)
            for name, values in block.items():
                self._buffer[name][self._filled:self._filled + take] = values[done:done + take]
            self._filled, done = self._filled + take, done + take
            if self._filled == PARTICLE_CHUNK:
                self._flush()

    def _flush(self):
        with _signals_held():
            for name, var in self._variables.items():
                var[self.written:self.written + self._filled] = self._buffer[name][: self._filled]
            self.written, self._filled = self.written + self._filled, 0

    def finish(self, ds: xr.Dataset, path):
        """Write the rest of ``ds`` (all but its per-particle variables) and rename the file to ``path``."""
        self._flush()
        total = int(ds["cluster_particles"].sum()) if self._variables else 0
        if self.written != total:
            raise ValueError(f"clusters hold {self.written} particles, cluster_particles says {total}")
        self._nc.close()
        rest = ds.drop_vars([name for name, var in ds.variables.items() if var.dims == ("particle",)])
        encoding = {}
        for name, var in rest.variables.items():
            compressible = var.ndim > 0 and var.dtype.kind in "biuf"
            enc = {"zlib": True, "complevel": 4, "shuffle": True} if compressible else {}
            if name in ds.coords or var.dtype.kind in "biu":
                # Coordinates and counts have no missing values; CF wants no fill there.
                enc["_FillValue"] = None
            if var.dtype.kind in "OU":
                enc["dtype"] = "S1"  # a char array: see CF in the module docstring
            elif var.dtype == bool:
                enc["dtype"] = "i1"  # flags, without xarray's own dtype attribute: see CF
            encoding[name] = enc
        # unlimited_dims: not the ``particle`` of a dataset opened from a file, which the file has
        with _signals_held():
            rest.to_netcdf(self.tmp, mode="a", engine="netcdf4", format="NETCDF4", encoding=encoding,
                           unlimited_dims=[])
        os.replace(self.tmp, path)

    def discard(self):
        """Close and remove the unfinished file (nothing, once finished)."""
        if self._nc.isopen():
            self._nc.close()
        self.tmp.unlink(missing_ok=True)


@contextlib.contextmanager
def _signals_held():
    """Ctrl-C and a SIGTERM handled in Python held back until the block's netCDF reads or writes end, then raised.

    netCDF4's indexing runs Python code under bare ``except:`` clauses (``utils._StartCountStride``):
    a ``KeyboardInterrupt`` raised there is swallowed, and the sweep runs on to its end (docs/performance.md,
    "Data files"). Only the main thread runs signal handlers; other threads
    need no hold.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    held = []
    handlers = {}
    for signum in (signal.SIGINT, signal.SIGTERM):
        if callable(signal.getsignal(signum)):
            handlers[signum] = signal.signal(signum, lambda *received: held.append(received))
    try:
        yield
    finally:
        for signum, handler in handlers.items():
            signal.signal(signum, handler)
        if held:
            signum, frame = held[0]
            handlers[signum](signum, frame)


def open_sweep(path, chunks=None) -> xr.Dataset:
    """Open a dataset written by dlasweep (a sweep or one cluster).

    Everything but the per-particle arrays is read at once, so a damaged
    file fails here rather than later. Booleans come back as bool.

    Parameters
    ----------
    path : path
    chunks : dict, int or "auto", optional
        Passed to ``xarray.open_dataset``: the per-particle arrays become dask
        arrays (``{}``: the file's own chunks, ``PARTICLE_CHUNK`` values), and
        reading a cluster reads only the chunks that hold it. Default: lazy
        arrays without dask.

    Raises
    ------
    StoreError
        When the file is missing, not netCDF, truncated, or not from dlasweep.
    """
    with _signals_held():
        ds = _open(path, ("cluster_particles", "x", "y", "diffusion_time"), chunks)
        try:
            for var in ds.variables.values():
                if "particle" not in var.dims:
                    var.load()
        except Exception as err:
            ds.close()
            raise StoreError(f"{path}: damaged or truncated ({one_line(err)})") from None
    return _booleans(ds)


def open_whole(path, required=()) -> xr.Dataset:
    """Open, and read whole, a small file dlasweep wrote (a benchmark's) with the variables ``required``;
    ``StoreError`` as ``open_sweep``."""
    with _signals_held():
        ds = _open(path, required)
        try:
            return ds.load()
        except Exception as err:
            ds.close()
            raise StoreError(f"{path}: damaged or truncated ({one_line(err)})") from None


def open_dataset(path) -> xr.Dataset:
    """Open any file dlasweep wrote: a benchmark (dimension ``run``) whole (``open_whole``), else ``open_sweep``."""
    with _signals_held(), _open(path, ()) as ds:
        bench = "run" in ds.dims
    return open_whole(path) if bench else open_sweep(path)


def _open(path, required, chunks=None) -> xr.Dataset:
    """A netCDF file from dlasweep with the variables ``required``, opened lazily (``chunks`` as
    ``open_sweep``); else ``StoreError``."""
    path = Path(path)
    if not path.is_file():
        raise StoreError(f"{path}: " + ("not a regular file" if path.exists() else "no such file"))
    try:
        ds = xr.open_dataset(path, engine="netcdf4", chunks=chunks)
    except Exception as err:  # netCDF4/HDF5 raise OSError, RuntimeError, ValueError...
        raise StoreError(f"{path}: not a readable netCDF file ({one_line(err)})") from None
    missing = [v for v in required if v not in ds.variables]
    if not str(ds.attrs.get("source", "")).startswith("dlasweep") or missing:
        ds.close()
        what = f"missing {', '.join(missing)}" if missing else "no 'source = dlasweep' attribute"
        raise StoreError(f"{path}: not a dlasweep dataset ({what})")
    written = file_format(ds)
    if written is None or written > FORMAT:
        ds.close()
        which = f"file format {written}" if written else f"file format {ds.attrs['dlasweep_format']!r}"
        raise StoreError(f"{path}: {which}, from {ds.attrs['source']}; this dlasweep ({__version__}) reads "
                         f"formats 1 to {FORMAT}: upgrade dlasweep to read it")
    return ds


def file_format(ds: xr.Dataset) -> int | None:
    """The format version (``dlasweep._version.FORMAT``) a file was written in: its ``dlasweep_format``
    attribute, 1 for a file written before the attribute existed (which still opens: the readers keep that
    layout's paths), None for an attribute that is not a positive integer."""
    value = ds.attrs.get("dlasweep_format", 1)
    try:
        written = int(value)
    except (TypeError, ValueError):
        return None
    return written if written == value and written >= 1 else None


def _coordinate(values, dtype=None) -> np.ndarray:
    """Values as an array whose type survives netCDF: strings as objects, none as str (xarray
    writes an empty object array as doubles)."""
    array = np.asarray(values, dtype)
    if array.dtype.kind not in "OU":
        return array
    return array.astype(object) if array.size else array.astype("U1")


def _positions(column) -> np.ndarray:
    # no copy when the type is already right: 10^8 sites' columns are 4e8 bytes each
    return column.astype(ragged_dtype(column.dtype.kind in "iu"), copy=False)


def _describe(ds: xr.Dataset) -> xr.Dataset:
    """``describe`` a sweep or a cluster, the positions as coordinates: a CF trajectory ragged array."""
    ds["cluster_particles"] = ds["cluster_particles"].astype(np.int32)
    return describe(ds.set_coords([a for a in AXES if a in ds.data_vars]), featureType="trajectory")


def describe(ds: xr.Dataset, schema=None, **globals_) -> xr.Dataset:
    """Give every variable its attributes (``attributes``), the file the global attributes of all dlasweep files.

    Parameters
    ----------
    ds : xarray.Dataset
        Changed in place and returned.
    schema : dict, optional
        Its variables' table (default ``SCHEMA``; ``bench.benchmark.BENCH_SCHEMA`` for ``dlasweep bench``).
    **globals_
        More global attributes (``featureType``), put first with ``Conventions`` and ``source``.
    """
    for name, var in ds.variables.items():
        var.attrs.update(attributes(name, var.dtype, schema))
    first = {"Conventions": "CF-1.8", **globals_, "source": f"dlasweep {__version__}", "dlasweep_format": FORMAT}
    ds.attrs = {**first, **{k: v for k, v in ds.attrs.items() if k not in first}}
    return ds


def _booleans(ds: xr.Dataset) -> xr.Dataset:
    """Turn ``ds``'s booleans (int8 flags ``BOOLEAN`` in the file) back into bool, in place: it still closes its
    file."""
    for name, var in list(ds.variables.items()):
        if var.attrs.get("flag_meanings") == BOOLEAN and var.dtype != bool:
            (ds.coords if name in ds.coords else ds)[name] = var.astype(bool)
    return ds


_COMMAND = contextvars.ContextVar("dlasweep_command", default=None)


@contextlib.contextmanager
def command_line(argv):
    """Within, the files written record the command line ``argv`` (a list) in their ``history``.

    The command line runs each command so; a Python caller's files name
    the function that made them instead.
    """
    token = _COMMAND.set(shlex.join(argv))
    try:
        yield
    finally:
        _COMMAND.reset(token)


def provenance(function) -> str:
    """A file's ``history``: now, the command line (``command_line``) or else the Python ``function``, the version."""
    return f"{_now()}: {_COMMAND.get() or function} (dlasweep {__version__})"


def _now() -> str:
    return datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%dT%H:%M:%SZ")
