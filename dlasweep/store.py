"""The netCDF side of dlasweep: dataset layout, atomic writes, reading back.

Layout (README, "The dataset"): the measured quantities on dims
``(<swept params>..., size, n_particles, seed[, scale])``; the clusters as a
CF contiguous ragged array, ``x``, ``y`` (``z``), ``diffusion_time`` and
``parent`` along ``particle`` with the count variable ``cluster_particles(cluster)``, whose
parameters are the ``cluster_<name>`` coordinates on ``cluster``. Every
model parameter that is not swept is a scalar coordinate, so ``ds["dim"]``
or ``ds["model"]`` works whether or not it is a sweep axis.

CF (checked with cfchecker, CF-1.8; tests/test_store.py):

* A discrete sampling geometry, one cluster per instance: ``featureType =
  "trajectory"``. CF-1.8 (9.1, 9.3.3) gives the contiguous ragged array, a
  count variable with ``sample_dimension``, to timeSeries, trajectory,
  profile and their combinations, not to point, whose every instance is
  one point: a point file's count variable groups nothing CF names. Of
  those, a cluster is a trajectory, "a series of data points along a path
  through space" in order: its particles in the order they attached, the
  growth's clock. A time series stays at one place and a profile on one
  vertical line. CF lists a time coordinate for trajectories; here a
  particle's place in its cluster's block is its attachment order, and no
  variable repeats it (8 bytes a particle).
* ``cluster(cluster)``, the coordinate variable of the instance dimension
  (0, 1, ...: the cluster's position in the file), has ``cf_role =
  "trajectory_id"`` as in CF's examples: the one instance variable of a
  trajectory file (a ``cluster_<name>`` is one of the clusters'
  parameters). ``cluster_particles`` is the count variable (32-bit
  ``int``, the integer type the checker asks of it; a cluster holds at
  most ``spec.MAX_PARTICLES`` particles).
* ``x``, ``y`` (``z``) are the particles' space coordinates, auxiliary
  coordinates of ``diffusion_time`` (its ``coordinates`` attribute), with
  ``axis = "X"``, ``"Y"``, ``"Z"``: cf_xarray's ``ds.cf["X"]`` finds them.
  No ``standard_name``: CF's names for positions (``projection_x_coordinate``
  and the like) are lengths in metres on a map; these are counted in
  lattice spacings or particle diameters.
* cfchecker 4.1 notes "attribute sample_dimension is being used in a
  non-standard way" on every count variable of a CF-1.7 or later file, CF's
  own examples included (its table of attributes names no kind of variable
  for it from CF-1.7 on): that note is the checker's, not this layout's.
* Strings (``model``, ``seed_shape``, ``launch`` and their ``cluster_``
  coordinates) are char arrays with a string-length dimension
  (``string<N>``) and ``_Encoding = "utf-8"``: the CF-1.8 check rejects
  netCDF-4 variable-length strings, and char arrays read everywhere.
  xarray and netCDF4-python turn them back into strings. They have a
  ``long_name`` and no ``units``. A swept string parameter stays a
  variable named after its dimension, so that xarray selects by it; the
  checker warns there, as a CF coordinate variable is numeric.
* Booleans (``jumps``) are int8 0/1 with ``flag_values`` and
  ``flag_meanings = "false true"``, nothing else: ``open_sweep`` turns them
  back into bool (xarray would want its own ``dtype = "bool"`` attribute,
  which is no CF attribute). They are model parameters, so coordinates,
  and the checker notes flags there (CF-1.8 names them for data variables).
* ``history``: when the file was made, by which command line (the CLI's,
  ``command_line``) or Python function, and the dlasweep version.
"""

from __future__ import annotations

import contextlib
import contextvars
import datetime
import os
import shlex
from dataclasses import dataclass, field
from pathlib import Path

import netCDF4
import numpy as np
import xarray as xr

from . import params as _params
from ._version import __version__
from .kernels.model import STEPS_DTYPE
from .selection import selected_clusters

STATUS_FLAGS = _params.STATUSES
"""Meaning of each integer code of ``status``."""

AXES = ("x", "y", "z")

_LENGTH = "lattice spacings (lattice) or particle diameters (offlattice)"
_CONFIG = "..."
"""First of a variable's dims in ``SCHEMA``: the swept model parameters, in spec order."""


@dataclass(frozen=True)
class Variable:
    """One variable of a dataset: its dims, type and attributes.

    Attributes
    ----------
    dims : tuple of str
        ``"..."`` first stands for the swept model parameters (spec order).
    dtype : numpy dtype or None
        None where it depends on the data (positions: ``ragged_dtype``).
    units : str or None
        None for strings, which have no units.
    long_name : str
    cf : dict
        Its other CF attributes (``axis``, ``cf_role``, ``sample_dimension``).
    """

    dims: tuple
    dtype: object
    units: str | None
    long_name: str
    cf: dict = field(default_factory=dict)

    @property
    def missing(self):
        """The value of a not-yet-measured (or failed) entry: NaN for floats, 0 for counts."""
        return np.nan if np.dtype(self.dtype).kind == "f" else 0


_SWEPT = (_CONFIG, "size", "n_particles", "seed")
SCHEMA = {
    "box_count": Variable((*_SWEPT, "scale"), np.int64, "1", "number of boxes of side `scale` holding particles"),
    "n_grown": Variable(_SWEPT, np.int64, "1", "particles attached at this count (less when growth stopped early)"),
    "status": Variable(_SWEPT, np.int8, "1", "growth outcome at this count"),
    "radius_gyration": Variable(_SWEPT, np.float64, "1", f"radius of gyration, in {_LENGTH}"),
    "radius_gyration_history": Variable((_CONFIG, "size", "seed", "history"), np.float64, "1",
                                        f"radius of gyration of the first `history` particles, in {_LENGTH}"),
    "max_radius": Variable(_SWEPT, np.float64, "1",
                           f"largest distance of a particle from the seed particle, in {_LENGTH}"),
    "anisotropy": Variable(_SWEPT, np.float64, "1",
                           "cubic anisotropy of the outer half of the mass about the seed: <cos 4 theta> in 2D, "
                           "the cubic harmonic scaled alike in 3D (1: along the axes, 0: isotropic)"),
    "walk_steps": Variable(_SWEPT, np.int64, "1", "walk steps (or exact jumps) of every walker until this count"),
    "wall_time": Variable(_SWEPT, np.float64, "s", "seconds spent growing the cluster to this count"),
    "D_ci_half_width": Variable((_CONFIG, "size"), np.float64, "1",
                                "half-width of the 95% bootstrap confidence interval over seeds of the headline "
                                "(mass-radius) fractal dimension D at the largest particle count"),
    # coordinates
    "n_particles": Variable(("n_particles",), np.int64, "1", "target number of particles"),
    "seed": Variable(("seed",), np.int64, "1",
                     "replicate number (with root_seed and the grid indices it names the random stream)"),
    "scale": Variable(("scale",), np.float64, "1", f"box side for box counting, in {_LENGTH}"),
    "history": Variable(("history",), np.int64, "1", "particle count at which the growth history is recorded"),
    # the clusters: a CF contiguous ragged array of trajectories (see CF in the module docstring)
    "cluster_particles": Variable(("cluster",), np.int32, "1", "number of particles of the cluster",
                                  {"sample_dimension": "particle"}),
    "cluster": Variable(("cluster",), np.int32, "1", "number of the cluster: its position in the file",
                        {"cf_role": "trajectory_id"}),
    "cluster_seed": Variable(("cluster",), np.int64, "1", "replicate number of the cluster"),
    **{a: Variable(("particle",), None, "1", f"{a} coordinate of the particle centre, in {_LENGTH}",
                   {"axis": a.upper()}) for a in AXES},
    "diffusion_time": Variable(("particle",), STEPS_DTYPE, "1",
                               "walk steps (or exact jumps) from release to sticking; 4294967295: at least that many"),
    "parent": Variable(("particle",), np.int32, "1",
                       "position in its cluster (0 = first) of the particle this one stuck to; "
                       "-1 = none: a seed particle, or one that stuck to the substrate",
                       {"valid_min": np.int32(-1)}),
    # Every model parameter: a sweep axis, else a scalar; strings have no units.
    **{name: Variable((name,), p.kind, p.units, p.meaning) for name, p in _params.PARAMETERS.items()},
}
"""Every variable of a dataset dlasweep writes (a sweep, or one grown cluster): the one place
its dims, type, units and long name are spelled. ``cluster_<name>`` coordinates take the
attributes of ``<name>``; the other per-cluster variables of one grown cluster (``status``)
are on ``cluster`` there."""

SCIENCE = ("box_count", "n_grown", "status", "radius_gyration", "max_radius", "anisotropy", "walk_steps",
           "radius_gyration_history")
"""Variables that depend only on the spec, bit for bit (``wall_time`` aside)."""

def blank(name, shape) -> np.ndarray:
    """An array for variable ``name`` of ``SCHEMA``, of its type, every entry missing (``Variable.missing``)."""
    var = SCHEMA[name]
    return np.full(shape, var.missing, var.dtype)


def dims(name, axes) -> tuple:
    """The dims of variable ``name`` of ``SCHEMA`` in a sweep whose swept parameters are ``axes``."""
    return tuple(d for dim in SCHEMA[name].dims for d in (axes if dim == _CONFIG else (dim,)))


class StoreError(ValueError):
    """A file that is not a readable dlasweep dataset; one line naming it."""


def to_dataset(spec, scales, history, science, cluster_particles, failed=()) -> xr.Dataset:
    """Assemble a sweep's results into the layout of README, "The dataset", clusters aside.

    The per-particle variables are added by ``with_clusters`` (in memory)
    or streamed into the file by ``save``.

    Parameters
    ----------
    spec : dlasweep.spec.Spec
    scales : ndarray, (n_scales,)
    history : ndarray of int, (n_history,)
        Counts of the growth history (``fit.growth_counts``).
    science : dict of ndarray
        ``box_count`` on ``(<axes>..., size, n_particles, seed, scale)``,
        ``radius_gyration_history`` on ``(<axes>..., size, seed, history)``,
        the other quantities (``SCIENCE`` and ``wall_time``) on
        ``(<axes>..., size, n_particles, seed)``. ``status`` holds integer
        codes (index into ``STATUS_FLAGS``).
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
    tasks = [t for t in spec.tasks() if spec.stores(t)]
    for name in (*spec.axes, "size"):
        # of the axis's type, also when no cluster is stored
        coords[f"cluster_{name}"] = ("cluster", _coordinate([t.params[name] for t in tasks], coords[name][1].dtype))
    coords["cluster_seed"] = ("cluster", np.asarray([t.seed for t in tasks], SCHEMA["cluster_seed"].dtype))
    coords["cluster"] = ("cluster", np.arange(len(tasks), dtype=SCHEMA["cluster"].dtype))

    data = {name: (dims(name, tuple(spec.axes)), science[name]) for name in (*SCIENCE, "wall_time")}
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
    cluster : dlasweep.grow.Cluster
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
        "history": provenance("dlasweep.store.cluster_dataset"),
        "seed": int(seed),
    }
    return _describe(xr.Dataset(data, coords=coords, attrs=attrs))


def ragged_dtype(lattice: bool):
    """Type of stored positions: int32 for lattice sites, float64 off the lattice."""
    return np.int32 if lattice else np.float64


def with_clusters(ds: xr.Dataset, clusters) -> xr.Dataset:
    """``ds`` (from ``to_dataset``) with its stored clusters as per-particle variables in memory.

    Parameters
    ----------
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


def ragged_columns(models, dims) -> dict:
    """The per-particle variables of clusters of these models and dims, and their types: positions, diffusion times, parents.

    Lattice positions are int32 sites, off-lattice ones float64 (and float64
    for all when both are swept); with ``dim`` swept, 2D clusters lie in the
    z = 0 plane of 3D columns.
    """
    lattice = bool((np.asarray(models) == "lattice").all())
    return {**{a: ragged_dtype(lattice) for a in AXES[:int(np.max(dims))]}, "diffusion_time": np.dtype(SCHEMA["diffusion_time"].dtype),
            "parent": np.dtype(SCHEMA["parent"].dtype)}


PARTICLE_CHUNK = 1 << 16
"""Values per HDF5 chunk of a per-particle variable.

Measured by ``workflows/ragged_encoding.py`` on 1000 lattice 2D clusters of
10^5 (10^8 particles, 16 bytes each unpacked; a shared 2-core machine):
write s / bytes per particle / open and read one cluster s, at zlib 1:
2^14: 14.0 / 4.52 / 0.019; 2^16: 17.2 / 4.46 / 0.022; 2^18: 17.5 / 4.45 /
0.037; 2^20: 18.4 / 4.44 / 0.053. Beyond 2^16 a file shrinks by under 0.5%
while reading one cluster decompresses more that it does not need."""
PARTICLE_ZLIB = 1
"""zlib level of the per-particle variables (shuffled as ``shuffled`` says).

Same measurement, 2^16 values per chunk: level 0 (shuffle only) 1.9 s and
16.0 bytes per particle; 1: 17.2 s, 4.46; 4: 38.8 s, 4.20; 9 (2^14): 339 s,
3.80. Level 1 takes 3.6x off the file for about 10% of the time the sweep
takes to grow the clusters; higher levels save 6-15% more at 2-20x the time.
Off-lattice (float64 positions, 24 bytes unpacked), 2^16: level 0 4.9 s, 24.0;
1: 50.8 s, 15.05; 4: 55.1 s, 14.89."""


def shuffled(dtype) -> bool:
    """Whether a per-particle variable of this type is byte-shuffled before zlib: all but lattice sites.

    Measured with zlib 1 on chunks of 2^16, ns per value and bytes per value,
    shuffled against not: lattice x, 10,000 clusters of 10^3: 47 and 1.51
    against 36 and 1.27; 10 of 10^5: 51 and 1.80 against 55 and 1.82.
    Diffusion times 33-42 and 0.81-0.88 against 46-49 and 1.46-1.60;
    off-lattice x (10 of 10^5) 153 and 7.03 against 198 and 7.67.
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
    path = Path(path)
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
        rest.to_netcdf(self.tmp, mode="a", engine="netcdf4", format="NETCDF4", encoding=encoding, unlimited_dims=[])
        os.replace(self.tmp, path)

    def discard(self):
        """Close and remove the unfinished file (nothing, once finished)."""
        if self._nc.isopen():
            self._nc.close()
        self.tmp.unlink(missing_ok=True)


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
    ds = _open(path, required)
    try:
        return ds.load()
    except Exception as err:
        ds.close()
        raise StoreError(f"{path}: damaged or truncated ({one_line(err)})") from None


def open_dataset(path) -> xr.Dataset:
    """Open any file dlasweep wrote: a benchmark (dimension ``run``) whole (``open_whole``), else ``open_sweep``."""
    with _open(path, ()) as ds:
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
    return ds


def cluster_points(ds: xr.Dataset, index=None, **where) -> np.ndarray:
    """Positions of one stored cluster, in attachment order.

    Parameters
    ----------
    ds : xarray.Dataset
        From ``open_sweep`` or ``run_sweep``, or a selection of one
        (``ds.sel(stickiness=0.5)``): ``where`` then looks among the clusters
        of the selection only (``selected_clusters``).
    index : int, optional
        Position along ``cluster`` (task order).
    **where
        Otherwise, the cluster's parameters, e.g. ``stickiness=0.5, seed=3``;
        names without the ``cluster_`` prefix. They must pick one cluster.

    Returns
    -------
    ndarray, (n, dim)
    """
    index = _index(ds, index, where)
    start, stop = _particles_of(ds, index)
    # With dim swept, 2D clusters sit in the z = 0 plane of a 3D ragged array.
    return np.stack([ds[a][start:stop].values for a in AXES[:_cluster_value(ds, "dim", index)]], axis=1)


def cluster_parents(ds: xr.Dataset, index=None, **where) -> np.ndarray:
    """Parents of one stored cluster's particles, in attachment order (``Cluster.parents``).

    Parameters
    ----------
    ds, index, where
        As for ``cluster_points``.

    Returns
    -------
    ndarray, (n,) int32
        Position in the cluster of the particle each one stuck to; -1 for
        the seed particles and those that stuck to a substrate.

    Raises
    ------
    StoreError
        When the file predates parents (no ``parent`` variable).
    """
    if "parent" not in ds.variables:
        raise StoreError("parent: this file holds no parents (written before dlasweep stored them)")
    index = _index(ds, index, where)
    start, stop = _particles_of(ds, index)
    return ds["parent"][start:stop].values.astype(np.int32)


def read_cluster(ds: xr.Dataset, index=None, **where):
    """One stored cluster, as ``grow`` returned it: points, diffusion times, status and parameters.

    Only that cluster's range of the per-particle arrays is read (with dask
    chunks, only the chunks that hold it).

    Parameters
    ----------
    ds, index, where
        As for ``cluster_points``.

    Returns
    -------
    dlasweep.grow.Cluster
        ``status`` is the growth's outcome at the largest count; no
        checkpoint times (a sweep keeps them in ``wall_time``).
    """
    from .grow import Cluster

    index = _index(ds, index, where)
    start, stop = _particles_of(ds, index)
    # a parameter younger than the file takes its default, the behaviour of the code that wrote it
    params = {name: _cluster_value(ds, name, index) for name in _params.PARAMETERS
              if name in ds.coords or f"cluster_{name}" in ds.coords}
    return Cluster(cluster_points(ds, index), ds["diffusion_time"][start:stop].values, _status(ds, index),
                   _params.resolve(**params),
                   parents=cluster_parents(ds, index) if "parent" in ds.variables else None)


def _index(ds, index, where) -> int:
    """The position on ``cluster`` that ``index`` or ``where`` names (``cluster_points``), checked."""
    if (index is None) == (not where):
        raise TypeError("cluster: give either an index or parameter values")
    if index is None:
        return _find_cluster(ds, where)
    count = ds.sizes.get("cluster", 0)
    if not -count <= index < count:
        raise IndexError(f"cluster: index {index} is outside 0..{count - 1}")
    return int(index) % count


def _particles_of(ds, index) -> tuple:
    """The range of ``particle`` that holds cluster ``index``."""
    counts = ds["cluster_particles"].values
    start = int(counts[:index].sum())
    return start, start + int(counts[index])


def _cluster_value(ds, name, index):
    """Model parameter ``name`` of cluster ``index``: its ``cluster_<name>`` value, else the dataset's scalar.

    A boolean comes back as bool also from a file opened without ``open_sweep`` (int8 flags there).
    """
    coord = f"cluster_{name}"
    var = ds[coord][index] if coord in ds.coords else ds[name]
    value = var.values.item()
    return bool(value) if var.attrs.get("flag_meanings") == _BOOLEAN else value


def _status(ds, index) -> str:
    """Cluster ``index``'s growth outcome: at the largest count of a sweep, or its own in a grown cluster's file."""
    status = ds["status"]
    if status.dims == ("cluster",):
        return STATUS_FLAGS[int(status[index])]
    at = {d: ds[f"cluster_{d}"].values[index] for d in status.dims if d != "n_particles"}
    return STATUS_FLAGS[int(status.sel(at).isel(n_particles=-1))]


def _find_cluster(ds, where) -> int:
    """The position on ``cluster`` of the one cluster of ``ds``'s selection whose parameters are ``where``."""
    candidates = selected_clusters(ds)
    match = np.ones(len(candidates), bool)
    for name, value in where.items():
        coord = f"cluster_{name}"
        if coord not in ds.coords:
            known = [c[len("cluster_"):] for c in ds.coords if c.startswith("cluster_")]
            raise ValueError(f"{name}: not a cluster parameter (known: {', '.join(known)})")
        match &= ds[coord].values[candidates] == value
    found = candidates[match]
    if len(found) != 1:
        raise ValueError(f"{where}: matches {len(found)} clusters, not one")
    return int(found[0])


def _coordinate(values, dtype=None) -> np.ndarray:
    """Values as an array whose type survives netCDF: strings as objects, none as str (xarray
    writes an empty object array as doubles)."""
    array = np.asarray(values, dtype)
    if array.dtype.kind not in "OU":
        return array
    return array.astype(object) if array.size else array.astype("U1")


def _positions(column) -> np.ndarray:
    # no copy when the type is already right: 10^8 sites' columns are 400 MB each
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
        Its variables' table (default ``SCHEMA``; ``bench.BENCH_SCHEMA`` for ``dlasweep bench``).
    **globals_
        More global attributes (``featureType``), put first with ``Conventions`` and ``source``.
    """
    for name, var in ds.variables.items():
        var.attrs.update(attributes(name, var.dtype, schema))
    first = {"Conventions": "CF-1.8", **globals_, "source": f"dlasweep {__version__}"}
    ds.attrs = {**first, **{k: v for k, v in ds.attrs.items() if k not in first}}
    return ds


_BOOLEAN = "false true"
"""``flag_meanings`` of a boolean."""


def attributes(name, dtype=None, schema=None) -> dict:
    """A variable's ``long_name`` and ``units`` (none for strings), its other CF attributes, the meanings of its flags.

    From its row of ``schema`` (default ``SCHEMA``); a ``cluster_<name>``
    coordinate takes ``<name>``'s, as "the cluster's <name>: ...".
    """
    schema = SCHEMA if schema is None else schema
    key = name if name in schema else name.removeprefix("cluster_")
    var = schema[key]
    long_name = var.long_name if key == name else f"the cluster's {key}: {var.long_name}"
    attrs = {"long_name": long_name, **({"units": var.units} if var.units else {}), **var.cf}
    if name == "status":
        attrs.update(flag_values=np.arange(len(STATUS_FLAGS), dtype=np.int8), flag_meanings=" ".join(STATUS_FLAGS))
    elif dtype == bool:
        attrs.update(flag_values=np.array([0, 1], np.int8), flag_meanings=_BOOLEAN)
    return attrs


def _booleans(ds: xr.Dataset) -> xr.Dataset:
    """Turn ``ds``'s booleans (int8 flags ``_BOOLEAN`` in the file) back into bool, in place: it still closes its file."""
    for name, var in list(ds.variables.items()):
        if var.attrs.get("flag_meanings") == _BOOLEAN and var.dtype != bool:
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
    return datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")


def one_line(err) -> str:
    """An exception's message on one line (its type's name when it has none): error messages stay one line."""
    return " ".join(str(err).split()) or err.__class__.__name__
