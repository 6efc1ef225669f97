"""What a dlasweep dataset holds: every variable's dims, type, units and CF attributes.

Layout (README, "The dataset"): the measurement variables on dims
``(<swept params>..., size, n_particles, seed[, scale])``; the clusters as a
CF contiguous ragged array, ``x``, ``y`` (``z``), ``diffusion_time`` and
``parent`` along ``particle`` with the count variable ``cluster_particles(cluster)``, whose
parameters are the ``cluster_<name>`` coordinates on ``cluster``. Every
model parameter that is not swept is a scalar coordinate, so ``ds["dim"]``
or ``ds["model"]`` works whether or not it is a sweep axis. ``netcdf``
writes and opens the files; ``ragged`` reads one cluster back. No netCDF
and no xarray here: a worker fills its arrays from this table alone.
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

from dataclasses import dataclass, field

import numpy as np

from .. import params as _params
from ..kernels.model import STEPS_DTYPE
from ..stats.constants import LEVEL

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
        """The value of an entry not yet computed (or failed): NaN for floats, 0 for counts."""
        return np.nan if np.dtype(self.dtype).kind == "f" else 0


BOOLEAN = "false true"
"""``flag_meanings`` of a boolean."""
_FLAG = {"flag_values": np.array([0, 1], np.int8), "flag_meanings": BOOLEAN}
"""The CF attributes of a boolean data variable stored as int8 0/1."""

_SWEPT = (_CONFIG, "size", "n_particles", "seed")
_MEASURED = (_CONFIG, "size", "seed")
"""A measurement taken once per cluster, at its largest particle count (``[measure]`` of a spec)."""
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
                                f"half-width of the {LEVEL} bootstrap confidence interval over seeds of the headline "
                                "(mass-radius) fractal dimension D at the largest particle count"),
    # [measure] harmonic_walkers: the harmonic measure at every count, its box spectrum and deposition depth at
    # the largest (dlasweep.measures.harmonic)
    "harmonic_D": Variable((*_MEASURED, "q"), np.float64, "1",
                           "generalised dimension D(q) of the harmonic measure (the growth probability) of the "
                           "cluster at its largest particle count, by box partition sums over the fitted window"),
    "harmonic_D_stderr": Variable((*_MEASURED, "q"), np.float64, "1",
                                  "standard error of harmonic_D: the fit's, the jackknife's over the walkers and "
                                  "the finite sample's bias, in quadrature"),
    "harmonic_D_ok": Variable((*_MEASURED, "q"), np.int8, "1",
                              "whether harmonic_D is trusted: a flat fitted window of box sides the walkers resolve",
                              _FLAG),
    "harmonic_entropy": Variable((*_SWEPT, "q"), np.float64, "1",
                                 "Renyi entropy of order q, log(sum_i p_i**q) / (1 - q) (Shannon's at q = 1), of the "
                                 "harmonic measure sampled at the particles of the cluster at this count"),
    "harmonic_entropy_half": Variable((*_SWEPT, "q"), np.float64, "1",
                                      "harmonic_entropy of the first half of the walkers: with it, the finite sample's "
                                      "bias, which halves as the walkers double"),
    "harmonic_depth": Variable(_MEASURED, np.float64, "1",
                               "deposition depth: mean distance from the origin (above a substrate: height) "
                               "at which the walkers would stick, over the cluster's radius"),
    "harmonic_depth_spread": Variable(_MEASURED, np.float64, "1",
                                      "standard deviation over the walkers of the distance at which they would "
                                      "stick, over the cluster's radius"),
    # coordinates
    "n_particles": Variable(("n_particles",), np.int64, "1", "target number of particles"),
    "seed": Variable(("seed",), np.int64, "1",
                     "replicate number (with root_seed and the grid indices it names the random stream)"),
    "scale": Variable(("scale",), np.float64, "1", f"box side for box counting, in {_LENGTH}"),
    "history": Variable(("history",), np.int64, "1", "particle count at which the growth history is recorded"),
    "q": Variable(("q",), np.float64, "1", "moment q of the generalised dimensions D(q) of the harmonic measure"),
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

HARMONIC = ("harmonic_D", "harmonic_D_stderr", "harmonic_D_ok", "harmonic_entropy", "harmonic_entropy_half",
            "harmonic_depth", "harmonic_depth_spread")
"""Variables of the harmonic measurement (``[measure] harmonic_walkers``), present only when it is on; they too
depend only on the spec, bit for bit."""
HARMONIC_Q = np.arange(0.0, 6.01, 0.5)
"""The ``q`` coordinate of a sweep's harmonic measurement: 0 to 6 by halves (``stats.multifractal.DEFAULT_Q``,
spelled here because the schema imports no statistics)."""


def blank(name, shape) -> np.ndarray:
    """An array for variable ``name`` of ``SCHEMA``, of its type, every entry missing (``Variable.missing``)."""
    var = SCHEMA[name]
    return np.full(shape, var.missing, var.dtype)


def dims(name, axes) -> tuple:
    """The dims of variable ``name`` of ``SCHEMA`` in a sweep whose swept parameters are ``axes``."""
    return tuple(d for dim in SCHEMA[name].dims for d in (axes if dim == _CONFIG else (dim,)))


def is_sweep(ds) -> bool:
    """Whether a dataset is a sweep's: its box counts at each count grown, not one cluster's from ``grow``."""
    return "box_count" in ds and "n_grown" in ds


def config_dims(ds) -> list:
    """The dims that name a configuration of a sweep ``ds``: the swept parameters (spec order), then ``size``."""
    return [d for d in ds["n_grown"].dims if d not in ("n_particles", "seed")]


def plain(value):
    """A coordinate's value as a plain Python one: a numpy scalar's item, bytes (a char array's) as str."""
    value = value.item() if hasattr(value, "item") else value
    return value.decode() if isinstance(value, bytes) else value


class StoreError(ValueError):
    """A file that is not a readable dlasweep dataset; one line naming it."""


def ragged_dtype(lattice: bool):
    """Type of stored positions: int32 for lattice sites, float64 off the lattice."""
    return np.int32 if lattice else np.float64


def ragged_columns(models, dims) -> dict:
    """The per-particle variables of clusters of these models and dims, and their types: positions, diffusion
    times, parents.

    Lattice positions are int32 sites, off-lattice ones float64 (and float64
    for all when both are swept); with ``dim`` swept, 2D clusters lie in the
    z = 0 plane of 3D columns.
    """
    lattice = bool((np.asarray(models) == "lattice").all())
    return {**{a: ragged_dtype(lattice) for a in AXES[:int(np.max(dims))]},
            **{name: np.dtype(SCHEMA[name].dtype) for name in ("diffusion_time", "parent")}}


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
    elif dtype == bool:  # noqa: E721 (a numpy dtype, equal to bool for booleans; not a type comparison)
        attrs.update(flag_values=np.array([0, 1], np.int8), flag_meanings=BOOLEAN)
    return attrs


