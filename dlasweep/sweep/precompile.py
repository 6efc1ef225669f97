"""The kernels a first run of each model needs, compiled ahead of it into numba's cache.

A model's first grow compiles its growth kernel and every helper it calls, and a first sweep compiles the
measures beside them: tens of seconds of one core for each model (docs/performance.md). ``precompile``
grows and measures a cluster of a few particles of a model as a sweep's first task does
(``load_kernels``), so that numba's cache holds all of it. The wheel's build runs it for every model
(``setup.py``): the package a user installs then carries its kernels compiled for the processor it was built
on, and its first grow loads them. ``dlasweep compile`` runs it where they are missing: an editable
install, or a wheel built on another processor (numba's cache keys its code by the processor and compiles
again where it differs).

Importing this module loads numpy and numba, not dask or xarray: the wheel's build environment holds only
those.
"""

from __future__ import annotations

import contextlib
import importlib
import time

import numpy as np

from ..growth.cluster import kernel_of
from ..params import MODEL_KINDS
from .spec import parse_spec
from .task import measure_tasks, sweep_scales

_FIRST_RUN = """
[grid]
size = [0]
n_particles = [10]
seeds = 1

[model]
model = "{model}"
dim = {dim}
"""


def first_task_of_each_kernel(spec) -> dict:
    """``growth.cluster.kernel_of`` (model, dimension, lockstep walkers, Gaussian steps) -> the first task of
    the sweep ``spec`` (a ``Spec``) that grows it: each is a kernel of its own."""
    first = {}
    for task in spec.tasks(replicates=1):
        first.setdefault(kernel_of(task.params), task)
    return first


def load_kernels(spec):
    """Grow and measure a cluster of a few particles of each kernel the sweep ``spec`` (a ``Spec``) grows.

    The kernels its tasks call load (or compile) here, once, before they run: a sweep calls it while its
    embedded cluster starts, not in each of its threads at once, one waiting for the other under numba's
    lock. So does dask.array, which xarray imports when it builds the dataset: imported while the tasks
    ran, it held the GIL they need between kernels (where dask is missing, as in the wheel's build, that
    import is skipped).
    """
    first = list(first_task_of_each_kernel(spec).values())
    counts = np.array([min(spec.counts[0], 10)])
    measure_tasks(first, counts, sweep_scales(spec), spec.root_seed, [False] * len(first))
    with contextlib.suppress(ImportError):
        importlib.import_module("dask.array")


def precompile(kind: str):
    """Compile (or load) into numba's cache the kernels a first grow and a first sweep of a model need.

    Parameters
    ----------
    kind : str
        The model and dimension, a key of ``params.MODEL_KINDS`` (``lattice-2d``, ...): its default
        parameters are compiled, those of ``dlasweep grow --model M --dim D`` and of a sweep that
        names no other.
    """
    load_kernels(parse_spec(_FIRST_RUN.format(**MODEL_KINDS[kind]), default_name=f"compile {kind}"))


def precompile_each(kinds, say):
    """``precompile`` each model of ``kinds`` in turn, and ``say(kind, seconds)`` as each is done.

    Parameters
    ----------
    kinds : iterable of str
        Keys of ``params.MODEL_KINDS``.
    say : callable
        Receives each model's name and the seconds its kernels took to compile (or load).
    """
    for kind in kinds:
        start = time.perf_counter()
        precompile(kind)
        say(kind, time.perf_counter() - start)


def build(kinds: str):
    """``precompile`` each model named in ``kinds``, saying how long each took: the wheel's build step.

    Parameters
    ----------
    kinds : str
        ``all`` (every key of ``params.MODEL_KINDS``), ``none``, or names separated by commas
        (``lattice-2d,offlattice-2d``): the value of ``DLASWEEP_PRECOMPILE`` (setup.py). A name it does not
        know raises ``ValueError`` that names it, before anything compiles.
    """
    names = {"all": list(MODEL_KINDS), "none": []}.get(kinds.strip(), [kind.strip() for kind in kinds.split(",")])
    unknown = [kind for kind in names if kind not in MODEL_KINDS]
    if unknown:
        raise ValueError(f"DLASWEEP_PRECOMPILE: unknown model {unknown[0]!r}; one of all, none, "
                         f"{', '.join(MODEL_KINDS)}, or several separated by commas")
    precompile_each(names, lambda kind, seconds: print(f"dlasweep: compiled the {kind} kernels in {seconds:.0f} s",
                                                        flush=True))
