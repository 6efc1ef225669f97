"""The netCDF side of dlasweep: dataset layout, atomic writes, reading back.

Layout (README, "The dataset"): the measured quantities on dims
``(<swept params>..., size, n_particles, seed[, scale])``; the clusters as a
CF contiguous ragged array, ``x``, ``y`` (``z``) and ``diffusion_time`` along
``particle`` with the count variable ``cluster_particles(cluster)``, whose
parameters are the ``cluster_<name>`` coordinates on ``cluster``. Every
model parameter that is not swept is a scalar coordinate, so ``ds["dim"]``
or ``ds["model"]`` works whether or not it is a sweep axis.

CF (checked with cfchecker, CF-1.8):

* ``featureType = "point"``. CF requires a featureType once a count
  variable (``sample_dimension``) makes the file a ragged array, and offers
  only point, timeSeries, trajectory, profile and their combinations. A
  cluster has no time axis, path or vertical profile: its particles are
  points in space, located by ``x``, ``y`` (``z``), which is what "point"
  describes. The count variable then groups those points by cluster; CF
  defines its contiguous ragged layout for the other feature types, and
  readers that know it (``cluster_points`` here) apply it unchanged.
* The count variable is 32-bit ``int``, the integer type the CF-1.8 check
  asks of it (a cluster holds at most ``spec.MAX_PARTICLES`` particles).
* Strings (``model``, ``seed_shape``, ``launch`` and their ``cluster_``
  coordinates) are char arrays with a string-length dimension
  (``string<N>``) and ``_Encoding = "utf-8"``: the CF-1.8 check rejects
  netCDF-4 variable-length strings, and char arrays read everywhere.
  xarray and netCDF4-python turn them back into strings. They have a
  ``long_name`` and no ``units``. A swept string parameter stays a
  variable named after its dimension, so that xarray selects by it; the
  checker warns there, as a CF coordinate variable is numeric.
* Booleans (``jumps``) are int8 0/1 with ``flag_values``/``flag_meanings``
  plus xarray's ``dtype = "bool"`` marker, so they come back as bool
  through xarray and read as 0/1 anywhere else.
"""

from __future__ import annotations

import datetime
import os
from pathlib import Path

import numpy as np
import xarray as xr

from . import __version__
from . import params as _params

STATUS_FLAGS = _params.STATUSES
"""Meaning of each integer code of ``status``."""

AXES = ("x", "y", "z")
SCIENCE = ("box_count", "n_grown", "status", "radius_gyration", "max_radius", "anisotropy", "walk_steps")
"""Variables that depend only on the spec, bit for bit (``wall_time`` aside)."""

_LENGTH = "lattice spacings (lattice) or particle diameters (offlattice)"
_DESCRIPTIONS = {
    "box_count": ("number of boxes of side `scale` holding particles", "1"),
    "n_grown": ("particles attached at this count (less when growth stopped early)", "1"),
    "status": ("growth outcome at this count", "1"),
    "radius_gyration": (f"radius of gyration, in {_LENGTH}", "1"),
    "max_radius": (f"largest distance of a particle from the seed particle, in {_LENGTH}", "1"),
    "anisotropy": ("cubic anisotropy of the outer half of the mass about the seed: <cos 4 theta> in 2D, "
                   "the cubic harmonic scaled alike in 3D (1: along the axes, 0: isotropic)", "1"),
    "wall_time": ("seconds spent growing the cluster to this count", "s"),
    "walk_steps": ("walk steps (or exact jumps) of every walker until this count", "1"),
    "n_particles": ("target number of particles", "1"),
    "seed": ("replicate number (with root_seed and the grid indices it names the random stream)", "1"),
    "scale": (f"box side for box counting, in {_LENGTH}", "1"),
    "cluster_particles": ("number of particles of the cluster", "1"),
    "diffusion_time": ("walk steps (or exact jumps) from release to sticking", "1"),
    "cluster_seed": ("replicate number of the cluster", "1"),
    "D_ci_half_width": ("half-width of the 95% bootstrap confidence interval over seeds of the headline "
                        "(mass-radius) fractal dimension D at the largest particle count", "1"),
    **{a: (f"{a} coordinate of the particle centre, in {_LENGTH}", "1") for a in AXES},
    # Strings have no units.
    **{name: (p.meaning, None if isinstance(p.default, str) else "1") for name, p in _params.PARAMETERS.items()},
}


class StoreError(ValueError):
    """A file that is not a readable dlasweep dataset; one line naming it."""


def to_dataset(spec, scales, science, cluster_particles, ragged, failed=()) -> xr.Dataset:
    """Assemble a sweep's results into the layout of README, "The dataset".

    Parameters
    ----------
    spec : dlasweep.spec.Spec
    scales : ndarray, (n_scales,)
    science : dict of ndarray
        ``box_count`` on ``(<axes>..., size, n_particles, seed, scale)``, the
        other quantities (``SCIENCE`` and ``wall_time``) without ``scale``.
        ``status`` holds integer codes (index into ``STATUS_FLAGS``).
    cluster_particles : ndarray, (n_tasks,)
        Particles per cluster, in task (C) order.
    ragged : dict of array_like
        ``x``, ``y`` (``z``) and ``diffusion_time`` for every particle of
        every cluster, clusters concatenated in task order (numpy or dask).
    failed : sequence of (str, str)
        Task keys and error messages of tasks that raised.

    Returns
    -------
    xarray.Dataset
    """
    dims = (*spec.axes, "size", "n_particles", "seed")
    coords = {
        **{name: (name, _coordinate(values)) for name, values in spec.axes.items()},
        "size": ("size", np.asarray(spec.sizes, np.int64)),
        "n_particles": ("n_particles", np.asarray(spec.counts, np.int64)),
        "seed": ("seed", np.asarray(spec.seeds, np.int64)),
        "scale": ("scale", np.asarray(scales, np.float64)),
    }
    for name in _params.DEFAULTS:
        if name not in spec.axes and name != "size":
            coords[name] = ((), spec.resolved(name))
    tasks = list(spec.tasks())
    for name in (*spec.axes, "size"):
        coords[f"cluster_{name}"] = ("cluster", _coordinate([t.params[name] for t in tasks]))
    coords["cluster_seed"] = ("cluster", np.asarray([t.seed for t in tasks], np.int64))

    data = {name: ((*dims, "scale") if name == "box_count" else dims, science[name])
            for name in (*SCIENCE, "wall_time")}
    data["cluster_particles"] = ("cluster", np.asarray(cluster_particles))
    data.update({name: ("particle", values) for name, values in ragged.items()})
    attrs = {
        "title": f"dlasweep parameter sweep '{spec.name}': diffusion-limited aggregation clusters",
        "history": f"{_now()} created by dlasweep {__version__} (run_sweep)",
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
    coords["cluster_seed"] = ("cluster", np.asarray([seed], np.int64))
    data = {
        "cluster_particles": ("cluster", np.asarray([len(points)])),
        "status": ("cluster", np.asarray([STATUS_FLAGS.index(cluster.status)], np.int8)),
        **{a: ("particle", _positions(points[:, k])) for k, a in enumerate(AXES[: points.shape[1]])},
        "diffusion_time": ("particle", np.asarray(cluster.steps, np.int64)),
    }
    attrs = {
        "title": "dlasweep: one diffusion-limited aggregation cluster",
        "history": f"{_now()} created by dlasweep {__version__} (grow)",
        "seed": int(seed),
    }
    return _describe(xr.Dataset(data, coords=coords, attrs=attrs))


def ragged_dtype(lattice: bool):
    """Type of stored positions: int32 for lattice sites, float64 off the lattice."""
    return np.int32 if lattice else np.float64


def save(ds: xr.Dataset, path) -> None:
    """Write ``ds`` to netCDF-4 with zlib, atomically.

    The file is written under a temporary name in the target folder and
    renamed, so the final name never holds a partial file.
    """
    path = Path(path)
    tmp = path.with_name(f"{path.name}.tmp{os.getpid()}")
    encoding = {}
    for name, var in ds.variables.items():
        compressible = var.ndim > 0 and var.dtype.kind in "biuf"
        enc = {"zlib": True, "complevel": 4, "shuffle": True} if compressible else {}
        if name in ds.coords or var.dtype.kind in "biu":
            # Coordinates and counts have no missing values; CF wants no fill there.
            enc["_FillValue"] = None
        if var.dtype.kind in "OU":
            enc["dtype"] = "S1"  # a char array: see CF in the module docstring
        encoding[name] = enc
    try:
        ds.to_netcdf(tmp, engine="netcdf4", format="NETCDF4", encoding=encoding)
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            tmp.unlink()


def open_sweep(path) -> xr.Dataset:
    """Open a dataset written by dlasweep (a sweep or one cluster).

    Everything but the per-particle arrays is read at once, so a damaged
    file fails here rather than later.

    Raises
    ------
    StoreError
        When the file is missing, not netCDF, truncated, or not from dlasweep.
    """
    path = Path(path)
    if not path.is_file():
        raise StoreError(f"{path}: no such file")
    try:
        ds = xr.open_dataset(path, engine="netcdf4")
    except Exception as err:  # netCDF4/HDF5 raise OSError, RuntimeError, ValueError...
        raise StoreError(f"{path}: not a readable netCDF file ({_one_line(err)})") from None
    missing = [v for v in ("cluster_particles", "x", "y", "diffusion_time") if v not in ds.variables]
    if not str(ds.attrs.get("source", "")).startswith("dlasweep") or missing:
        ds.close()
        what = f"missing {', '.join(missing)}" if missing else "no 'source = dlasweep' attribute"
        raise StoreError(f"{path}: not a dlasweep dataset ({what})")
    try:
        for var in ds.variables.values():
            if "particle" not in var.dims:
                var.load()
    except Exception as err:
        ds.close()
        raise StoreError(f"{path}: damaged or truncated ({_one_line(err)})") from None
    return ds


def cluster_points(ds: xr.Dataset, index=None, **where) -> np.ndarray:
    """Positions of one stored cluster, in attachment order.

    Parameters
    ----------
    ds : xarray.Dataset
        From ``open_sweep`` or ``run_sweep``.
    index : int, optional
        Position along ``cluster`` (task order).
    **where
        Otherwise, the cluster's parameters, e.g. ``stickiness=0.5, seed=3``;
        names without the ``cluster_`` prefix. They must pick one cluster.

    Returns
    -------
    ndarray, (n, dim)
    """
    if (index is None) == (not where):
        raise TypeError("cluster_points: give either an index or parameter values")
    if index is None:
        index = _find_cluster(ds, where)
    counts = ds["cluster_particles"].values
    if not -len(counts) <= index < len(counts):
        raise IndexError(f"cluster: index {index} is outside 0..{len(counts) - 1}")
    index %= len(counts)
    start = int(counts[:index].sum())
    stop = start + int(counts[index])
    # With dim swept, 2D clusters sit in the z = 0 plane of a 3D ragged array.
    dim = int(ds["cluster_dim"][index]) if "cluster_dim" in ds.coords else int(ds["dim"])
    return np.stack([ds[a][start:stop].values for a in AXES[:dim]], axis=1)


def _find_cluster(ds, where) -> int:
    match = np.ones(ds.sizes["cluster"], bool)
    for name, value in where.items():
        coord = f"cluster_{name}"
        if coord not in ds.coords:
            known = [c[len("cluster_"):] for c in ds.coords if c.startswith("cluster_")]
            raise ValueError(f"{name}: not a cluster parameter (known: {', '.join(known)})")
        match &= ds[coord].values == value
    found = np.flatnonzero(match)
    if len(found) != 1:
        raise ValueError(f"{where}: matches {len(found)} clusters, not one")
    return int(found[0])


def _coordinate(values) -> np.ndarray:
    """Values as an array whose type survives netCDF (strings as objects)."""
    array = np.asarray(values)
    return array.astype(object) if array.dtype.kind == "U" else array


def _positions(column) -> np.ndarray:
    return column.astype(ragged_dtype(column.dtype.kind in "iu"))


def _describe(ds: xr.Dataset) -> xr.Dataset:
    """Give every variable its long_name and units, flags their meanings, the file its globals."""
    ds["cluster_particles"] = ds["cluster_particles"].astype(np.int32)
    for name, var in ds.variables.items():
        key = name if name in _DESCRIPTIONS else name.removeprefix("cluster_")
        long_name, units = _DESCRIPTIONS[key]
        if key != name:
            long_name = f"the cluster's {key}: {long_name}"
        var.attrs.update(long_name=long_name, **({"units": units} if units else {}))
        if name == "status":
            var.attrs.update(flag_values=np.arange(len(STATUS_FLAGS), dtype=np.int8),
                             flag_meanings=" ".join(STATUS_FLAGS))
        elif var.dtype == bool:
            var.attrs.update(flag_values=np.array([0, 1], np.int8), flag_meanings="false true")
    ds["cluster_particles"].attrs["sample_dimension"] = "particle"
    ds.attrs = {"Conventions": "CF-1.8", "featureType": "point", "source": f"dlasweep {__version__}",
                **ds.attrs}
    return ds


def _now() -> str:
    return datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")


def _one_line(err) -> str:
    return " ".join(str(err).split()) or err.__class__.__name__
