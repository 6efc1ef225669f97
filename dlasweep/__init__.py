"""dlasweep: parameter sweeps of diffusion-limited aggregation.

Data flows one way: kernels -> ``grow`` -> ``measure`` -> ``fit`` -> ``sweep``
(dask) -> ``store`` (netCDF) -> ``report`` (matplotlib) -> ``cli`` (argv).
"""

import importlib
import importlib.abc
import importlib.util
import sys
import types

from ._version import __version__

# Every name loads on first use: growing a cluster (a benchmark probe, a
# worker) carries no dask, xarray or matplotlib, and the command line
# (``_entry``) starts before numba and numpy load, so Ctrl-C is one line then too.
_LAZY = {"Cluster": "grow", "grow": "grow", "box_counts": "boxes", "radius_of_gyration": "measure",
         "fit_dimension": "fit", "fit_mass_radius": "fit", "load_spec": "spec",
         "run_sweep": "sweep", "open_sweep": "store", "cluster_points": "ragged", "cluster_parents": "ragged",
         "read_cluster": "ragged", "export_cluster": "export",
         "summarise": "analysis", "report": "report",
         "harmonic_measure": "measures.harmonic", "multifractal_spectrum": "stats.multifractal"}


class _Package(types.ModuleType):
    """The package, whose ``grow`` and ``report`` stay the functions when the submodules of those names load.

    Importing a submodule binds it on its package; loaded lazily, module
    ``dlasweep.report`` would then hide function ``dlasweep.report``.
    """

    def __setattr__(self, name, value):
        if not (isinstance(value, types.ModuleType) and _LAZY.get(name) == name):
            super().__setattr__(name, value)


sys.modules[__name__].__class__ = _Package


def _register_accessor():
    from . import accessor  # noqa: F401 (importing it registers ``Dataset.dla``)


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
        return getattr(importlib.import_module(f".{_LAZY[name]}", __name__), name)
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
    "report",
    "__version__",
]
