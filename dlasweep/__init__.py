"""dlasweep: parameter sweeps of diffusion-limited aggregation.

Data flows one way: kernels -> ``grow`` -> ``measure`` -> ``fit`` -> ``sweep``
(dask) -> ``store`` (netCDF) -> ``report`` (matplotlib) -> ``cli`` (argv).
"""

import importlib

__version__ = "0.1.0"

from .grow import Cluster, grow
from .measure import box_counts, radius_of_gyration
from .fit import fit_dimension, fit_mass_radius
from .spec import load_spec
from .report import report

# dask and xarray load on first use, so that growing a cluster (a benchmark
# probe, a worker) carries neither
_LAZY = {"run_sweep": "sweep", "open_sweep": "store", "cluster_points": "store", "summarise": "analysis"}


def __getattr__(name):
    if name in _LAZY:
        return getattr(importlib.import_module(f".{_LAZY[name]}", __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


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
    "report",
    "__version__",
]
