"""dlasweep: parameter sweeps of diffusion-limited aggregation.

Data flows one way: kernels -> ``grow`` -> ``measure`` -> ``fit`` -> ``sweep``
(dask) -> ``store`` (netCDF) -> ``report`` (matplotlib) -> ``cli`` (argv).
"""

__version__ = "0.1.0"

from .grow import Cluster, grow
from .measure import box_counts, radius_of_gyration
from .fit import fit_dimension
from .spec import load_spec
from .sweep import run_sweep
from .store import cluster_points, open_sweep
from .report import report

__all__ = [
    "Cluster",
    "grow",
    "box_counts",
    "radius_of_gyration",
    "fit_dimension",
    "load_spec",
    "run_sweep",
    "open_sweep",
    "cluster_points",
    "report",
    "__version__",
]
