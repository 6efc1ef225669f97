"""Sweep specifications: a TOML file parsed, typed and validated up front.

A spec names a grid of tasks: every combination of the list-valued model
parameters (the sweep axes, in spec order), the box sizes and the seeds. Each
task grows one cluster to the largest particle count. Every combination is
checked with ``params.resolve`` before anything runs, so a bad value is
reported at once, naming its key.

With ``[run] target_ci`` the seeds are a first batch: the sweep adds
replicates until the headline D of every configuration is known to that
precision, or ``[run] max_seeds`` are grown (``runner.run_sweep``).
"""

from __future__ import annotations

import contextlib
import dataclasses
import functools
import hashlib
import itertools
import json
import math
import tomllib
from dataclasses import dataclass
from pathlib import Path

from .. import params as _params
from .._version import FORMAT

MAX_PARTICLES = 100_000_000
"""Largest particle count a spec may ask for (a guard against typos like 1e12)."""
MAX_TASKS = 10_000_000
"""Most clusters a sweep may grow (a target sweep: at its max_seeds). Its list of tasks is built before
the plan (``plan``) weighs memory and disk, and listing this many takes hours (docs/performance.md, "Sweeps")."""
MAX_WORKERS = 1024
"""Most threads of the embedded cluster (``[run] workers``, ``--workers``)."""

_SECTIONS = ("grid", "model", "run", "measure")
_TOP_KEYS = ("name",)
_GRID_KEYS = ("size", "n_particles", "seeds")
_RUN_KEYS = ("root_seed", "workers", "target_ci", "max_seeds", "store_clusters")
_MEASURE_KEYS = ("harmonic_walkers",)
MAX_WALKERS = 1_000_000_000
"""Most walkers a spec may fire at each cluster (``[measure] harmonic_walkers``; a guard against typos)."""

DEFAULT_MAX_SEEDS = 256
"""Seed cap of a target sweep that names none (``[run] max_seeds``)."""


class SpecError(ValueError):
    """A spec that cannot run; the message is one line naming the key."""


@dataclass(frozen=True)
class Task:
    """One cluster to grow: a point of the sweep grid.

    Attributes
    ----------
    index : tuple of int
        Position on the grid: one index per sweep axis, then size, then seed.
    params : dict
        Every model parameter, resolved (``params.resolve``), for ``grow``.
    seed : int
        The replicate number (the seed coordinate).
    """

    index: tuple
    params: dict
    seed: int

    @property
    def key(self) -> str:
        """Name of the task, unique in its sweep, safe as a file name."""
        return "task-" + "-".join(map(str, self.index))

    @property
    def spawn_key(self) -> tuple:
        """Grid indices for ``SeedSequence``; the seed part is the replicate number.

        With ``seeds = N`` the replicate number equals its index; with a list
        of seeds it makes a replicate name the same stream in any spec. Either
        way replicate j is the same cluster however many seeds a spec has, which
        lets a target sweep add seeds without regrowing any.
        """
        return self.index[:-1] + (self.seed,)


@dataclass(frozen=True)
class Spec:
    """A validated sweep specification.

    Attributes
    ----------
    name : str
        Short name (the ``name`` key, else the file's stem).
    sizes, counts, seeds : tuple of int
        Box sides (0 = unbounded), particle counts (ascending), replicates.
    fixed : dict
        Scalar model parameters as written in the spec.
    axes : dict
        Swept model parameters (name -> tuple of values), in spec order.
    root_seed : int
        Root of every task's random stream.
    workers : int or None
        Preferred number of local workers (``[run] workers``).
    text : str
        The spec file as written.
    target_ci : float or None
        ``[run] target_ci``: add seeds until the 95% CI half-width of every
        configuration's headline D is at most this; None for a fixed sweep.
    max_seeds : int or None
        ``[run] max_seeds``: the most seeds a target sweep grows (None without
        ``target_ci``).
    store_clusters : int or None
        ``[run] store_clusters``: positions are stored for the first this
        many seeds of each configuration (0: "none"); None ("all", the
        default) stores every cluster. Curves are computed for all.
    harmonic_walkers : int
        ``[measure] harmonic_walkers``: walkers fired at each cluster at its largest count for its
        harmonic measure and spectrum D(q) (``measures.harmonic``); 0 (the default): none.
    """

    name: str
    sizes: tuple
    counts: tuple
    seeds: tuple
    fixed: dict
    axes: dict
    root_seed: int
    workers: int | None
    text: str
    target_ci: float | None = None
    max_seeds: int | None = None
    store_clusters: int | None = None
    harmonic_walkers: int = 0

    @property
    def shape(self) -> tuple:
        """Task grid shape: the sweep axes, then sizes, then seeds."""
        return tuple(len(v) for v in self.axes.values()) + (len(self.sizes), len(self.seeds))

    def configurations(self):
        """Yield the swept values and size of each grid point, seeds aside, in C order."""
        names = [*self.axes, "size"]
        for values in itertools.product(*self.axes.values(), self.sizes):
            yield dict(zip(names, values))

    def tasks(self, replicates=None):
        """Yield every ``Task`` in grid (C) order; with ``replicates``, only each configuration's first that many."""
        indices = itertools.product(*(range(n) for n in self.shape[:-1]))
        for index, params in zip(indices, self._resolved):
            for j, seed in enumerate(self.seeds[:replicates]):
                yield Task(index + (j,), params, seed)

    @functools.cached_property
    def _resolved(self) -> list:
        """Every configuration's parameters (``params.resolve``), in C order: resolved once per spec."""
        return [_params.resolve(**self.fixed, **config) for config in self.configurations()]

    @property
    def parameters(self) -> list:
        """Every configuration's parameters, resolved (``params.resolve``), in C order: a dict per grid point,
        seeds aside."""
        return self._resolved

    def stores(self, task: Task) -> bool:
        """Whether the positions of ``task``'s cluster are stored (``[run] store_clusters``)."""
        return self.store_clusters is None or task.index[-1] < self.store_clusters

    @property
    def n_tasks(self) -> int:
        return math.prod(self.shape)

    def with_seeds(self, n: int) -> Spec:
        """The same spec with replicates 0..n-1: a batch of a target sweep.

        Task keys and streams are those of the same replicates in any batch.
        """
        return dataclasses.replace(self, seeds=tuple(range(n)))

    def identity(self) -> dict:
        """Everything a task's result depends on, as plain JSON types.

        ``target_ci`` and ``max_seeds`` are left out: they decide how many
        replicates are grown, not what any replicate is, so finished tasks
        stay valid when they change. ``store_clusters`` is in when set: a
        task whose cluster is not stored keeps no positions in its part.
        The files' format version (``dlasweep._version.FORMAT``) is in, not
        the package version: a release that grows the same clusters into the
        same parts keeps the format, so its patch releases resume each
        other's parts, and one that changes either changes the format.
        ``measure.harmonic_walkers`` is in when on: its results are part of each task's (left out when
        off, so that the parts of a spec without it keep their identity).
        """
        stored = {} if self.store_clusters is None else {"run.store_clusters": self.store_clusters}
        if self.harmonic_walkers:
            stored["measure.harmonic_walkers"] = self.harmonic_walkers
        return {
            "grid.size": list(self.sizes),
            "grid.n_particles": list(self.counts),
            "grid.seeds": list(self.seeds),
            **{f"model.{k}": v for k, v in self.fixed.items()},
            **{f"model.{k}": list(v) for k, v in self.axes.items()},
            "model (axis order)": list(self.axes),
            "run.root_seed": self.root_seed,
            **stored,
            "dlasweep format": FORMAT,
        }

    def digest(self) -> str:
        """SHA-256 of ``identity()``: equal digests give equal task results."""
        text = json.dumps(self.identity(), sort_keys=True)
        return hashlib.sha256(text.encode()).hexdigest()

    def resolved(self, name: str):
        """Value of a non-swept model parameter after ``params.resolve``.

        Falls back to the spec's value when resolution depends on a sweep
        axis (``neighbours = 0`` with ``dim`` swept).
        """
        values = {params[name] for params in self._resolved}
        if len(values) == 1:
            return values.pop()
        return self.fixed.get(name, _params.DEFAULTS[name])


def differences(old: dict, new: dict) -> list:
    """Lines ``key: old -> new`` for every key where two identities differ."""
    keys = sorted(set(old) | set(new))
    return [f"{k}: {old.get(k, '(unset)')!r} -> {new.get(k, '(unset)')!r}"
            for k in keys if old.get(k) != new.get(k)]


def load_spec(path) -> Spec:
    """Read and validate a sweep spec.

    Parameters
    ----------
    path : str or Path
        A TOML file (see README, "Sweep spec").

    Returns
    -------
    Spec

    Raises
    ------
    SpecError
        On a missing or unreadable file, TOML syntax, an unknown key, a wrong
        type or an invalid value; the message names the key.
    """
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as err:
        raise SpecError(f"{path}: cannot read spec ({err.__class__.__name__}: {err})") from None
    return parse_spec(text, default_name=path.stem)


def parse_spec(text: str, default_name: str = "sweep") -> Spec:
    """Validate spec ``text`` (the body of ``load_spec``)."""
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as err:
        raise SpecError(f"TOML syntax: {err}") from None
    _reject_unknown("", doc, _TOP_KEYS + _SECTIONS)
    for section in _SECTIONS:
        if not isinstance(doc.get(section, {}), dict):
            raise SpecError(f"{section}: expected a [{section}] table")
    grid, model, run, measure = (doc.get(s, {}) for s in _SECTIONS)
    _reject_unknown("grid.", grid, _GRID_KEYS)
    _reject_unknown("run.", run, _RUN_KEYS)
    _reject_unknown("measure.", measure, _MEASURE_KEYS)
    name = doc.get("name", default_name)
    if not isinstance(name, str) or not name.strip():
        raise SpecError(f"name: expected a non-empty string, got {name!r}")

    if "n_particles" not in grid:
        raise SpecError("grid.n_particles: missing (the particle counts to measure at)")
    counts = sorted(_int_list("grid.n_particles", grid["n_particles"], 1, MAX_PARTICLES))
    sizes = _int_list("grid.size", grid.get("size", [0]), 0, _params.MAX_SIZE)
    seeds = grid.get("seeds", 1)
    if isinstance(seeds, list):
        seeds = _int_list("grid.seeds", seeds, 0, _params.MAX_SEED)
    else:
        seeds = list(range(_integer("grid.seeds", seeds, 1, MAX_TASKS)))

    fixed, axes = {}, {}
    for key, value in model.items():
        if key not in _params.DEFAULTS:
            raise SpecError(f"model.{key}: unknown model parameter (known: {', '.join(_params.DEFAULTS)})")
        if key == "size":
            raise SpecError("model.size: box sizes belong in grid.size")
        if isinstance(value, list):
            if not value:
                raise SpecError(f"model.{key}: empty list")
            value = [_typed(key, v) for v in value]
            _unique(f"model.{key}", value)
            axes[key] = tuple(value)
        else:
            fixed[key] = _typed(key, value)

    root_seed = _integer("run.root_seed", run.get("root_seed", 0), 0, _params.MAX_SEED)
    workers = run.get("workers")
    if workers is not None:
        workers = _integer("run.workers", workers, 1, MAX_WORKERS)
    target_ci, max_seeds = _precision(grid, run, len(seeds))
    store_clusters = _store_clusters(run.get("store_clusters", "all"))
    harmonic_walkers = _integer("measure.harmonic_walkers", measure.get("harmonic_walkers", 0), 0, MAX_WALKERS)

    spec = Spec(name.strip(), tuple(sizes), tuple(counts), tuple(seeds), fixed, axes,
                root_seed, workers, text, target_ci, max_seeds, store_clusters, harmonic_walkers)
    _check_tasks(spec)
    _check_grid(spec)
    return spec


def _typed(key, value):
    """A model value as its parameter's type where the one integer rule (``params.integer``) allows:
    ``walkers = 1e3`` is 1000, as ``--walkers 1e3`` is; anything else is left for ``resolve`` to judge."""
    if _params.PARAMETERS[key].kind is int and _params.is_number(value):
        with contextlib.suppress(ValueError):
            return _params.integer(value)
    return value


def _check_tasks(spec):
    """Refuse a grid of more than ``MAX_TASKS`` clusters (a target sweep's at its max_seeds), naming the key of
    its seeds."""
    n = spec.n_tasks if spec.max_seeds is None else spec.n_tasks // len(spec.seeds) * spec.max_seeds
    if n > MAX_TASKS:
        key = "run.max_seeds" if spec.max_seeds is not None else "grid.seeds"
        raise SpecError(f"{key}: the sweep would grow {n:,} clusters, more than {MAX_TASKS:,} "
                        f"({' x '.join(map(str, spec.shape[:-1]))} configurations)")


def _precision(grid, run, first_batch):
    """``[run] target_ci`` and ``max_seeds``, checked against the first batch of seeds."""
    if "target_ci" not in run:
        if "max_seeds" in run:
            raise SpecError("run.max_seeds: applies only with run.target_ci (a fixed sweep grows grid.seeds)")
        return None, None
    target_ci = run["target_ci"]
    if not _params.is_number(target_ci) or not math.isfinite(target_ci) or target_ci <= 0:
        raise SpecError(f"run.target_ci: expected a finite number > 0, got {target_ci!r}")
    if isinstance(grid.get("seeds"), list):
        raise SpecError("grid.seeds: with run.target_ci it must be a count (the first batch, "
                        "replicates 0..n-1), not a list")
    max_seeds = _integer("run.max_seeds", run.get("max_seeds", DEFAULT_MAX_SEEDS), 1, MAX_TASKS)
    if max_seeds < first_batch:
        raise SpecError(f"run.max_seeds: {max_seeds} is below grid.seeds = {first_batch}, the first batch")
    return float(target_ci), max_seeds


def _store_clusters(value):
    """``[run] store_clusters``: "all" (None), "none" (0), or a count K >= 0 of seeds per configuration."""
    if value in ("all", "none"):
        return None if value == "all" else 0
    if isinstance(value, str) or not _params.is_number(value) or not math.isfinite(value) or value % 1:
        raise SpecError(f'run.store_clusters: expected "all", "none" or an integer >= 0 '
                        f"(the first K seeds of each configuration), got {value!r}")
    return _integer("run.store_clusters", value, 0, MAX_TASKS)


def _reject_unknown(prefix, table, known):
    for key in table:
        if key not in known:
            raise SpecError(f"{prefix}{key}: unknown key (known: {', '.join(known)})")


def _integer(key, value, low, high):
    """``value`` as an int in [low, high], by the command line's rule (``params.integer``: ``1e5`` is one)."""
    try:
        if isinstance(value, str):  # TOML text is not a number
            raise ValueError(f"expected an integer, got {value!r}")
        number = _params.integer(value)
    except ValueError as err:
        raise SpecError(f"{key}: {err}") from None
    if not low <= number <= high:
        raise SpecError(f"{key}: {_params.text(value)} is not in [{low}, {high}]")
    return number


def _int_list(key, value, low, high):
    """A non-empty list of distinct integers (a bare integer counts as a list of one)."""
    values = value if isinstance(value, list) else [value]
    if not values:
        raise SpecError(f"{key}: empty list")
    values = [_integer(key, v, low, high) for v in values]
    _unique(key, values)
    return values


def _unique(key, values):
    seen = []
    for v in values:
        # Compare with types so that true and 1 stay distinct.
        if any(type(v) is type(s) and v == s for s in seen):
            raise SpecError(f"{key}: {v!r} appears twice")
        seen.append(v)


def _check_grid(spec: Spec):
    """Resolve every grid point's parameters; the first failure names its key."""
    for config in spec.configurations():
        try:
            _params.resolve(**spec.fixed, **config)
        except ValueError as err:
            message = str(err)
            section = "grid" if message.startswith("size:") else "model"
            where = ", ".join(f"{k}={v!r}" for k, v in config.items())
            context = f" (at {where})" if len(config) > 1 or len(spec.sizes) > 1 else ""
            raise SpecError(f"{section}.{message}{context}") from None
