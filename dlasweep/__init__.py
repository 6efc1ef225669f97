"""dlasweep: parameter sweeps of diffusion-limited aggregation.

Subpackages by job, each importing only those below it: ``kernels`` -> ``growth`` -> ``measures`` ->
``data`` -> ``stats`` -> ``sweep`` -> ``reporting`` and ``bench`` -> ``cli`` (the README's tour; the
import contracts in pyproject.toml hold the order).
"""

import importlib
import importlib.abc
import importlib.util
import sys

from ._version import __version__

# Every name loads on first use: growing a cluster (a benchmark probe, a
# worker) carries no dask, xarray or matplotlib, and the command line
# (``_entry``) starts before numba and numpy load, so Ctrl-C is one line then too.
_LAZY = {"Cluster": "growth.cluster", "grow": "growth.cluster", "box_counts": "measures.boxes",
         "radius_of_gyration": "measures.shape", "fit_dimension": "stats.fit", "fit_mass_radius": "stats.fit",
         "load_spec": "sweep.spec", "run_sweep": "sweep.runner", "open_sweep": "data.netcdf",
         "cluster_points": "data.ragged", "cluster_parents": "data.ragged", "read_cluster": "data.ragged",
         "export_cluster": "data.export", "summarise": "stats.summary", "report": "reporting.folder",
         "harmonic_measure": "measures.harmonic", "multifractal_spectrum": "stats.multifractal",
         "size_scaling": "stats.multifractal"}


def _register_accessor():
    from .data import accessor  # noqa: F401 (importing it registers ``Dataset.dla``)


class _AfterXarray(importlib.abc.MetaPathFinder):
    """Registers ``ds.dla`` as soon as xarray is imported, whoever imports it.

    Importing xarray here would double the time of ``import dlasweep``, which
    a dask worker or a benchmark pays for nothing; waiting for xarray keeps
    ``import dlasweep; import xarray as xr; xr.open_dataset(...).dla`` working.
    """

    looking = False  # while it asks the other finders for xarray itself

    def find_spec(self, name, path=None, target=None):
        if name != "xarray" or self.looking:
            return None
        self.looking = True
        try:
            spec = importlib.util.find_spec(name)
        finally:
            self.looking = False
        if spec is not None and spec.loader is not None:
            load = spec.loader.exec_module

            def exec_module(module):
                load(module)
                if self in sys.meta_path:
                    sys.meta_path.remove(self)
                _register_accessor()

            spec.loader.exec_module = exec_module
        return spec


if "xarray" in sys.modules:
    _register_accessor()
else:
    sys.meta_path.insert(0, _AfterXarray())


def __getattr__(name):
    if name in _LAZY:
        value = getattr(importlib.import_module(f".{_LAZY[name]}", __name__), name)
        globals()[name] = value  # once loaded, a plain attribute: no module of the package bears a public name
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__():
    return sorted(__all__)


__all__ = [
    "Cluster",
    "grow",
    "box_counts",
    "radius_of_gyration",
    "fit_dimension",
    "fit_mass_radius",
    "summarise",
    "load_spec",
    "run_sweep",
    "open_sweep",
    "cluster_points",
    "cluster_parents",
    "read_cluster",
    "export_cluster",
    "harmonic_measure",
    "multifractal_spectrum",
    "size_scaling",
    "report",
    "__version__",
]
