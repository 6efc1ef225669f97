"""Numba settings, set once for every kernel in the package.

``cache`` keeps compiled kernels on disk so that each dask worker compiles
once; ``nogil`` lets threads of one worker share it; ``fastmath`` stays off so
that results are bit-identical wherever they are computed.
"""

import time
import warnings

import numba
from numba.core.errors import NumbaWarning

jit = numba.njit(cache=True, nogil=True, fastmath=False, error_model="numpy")
"""Decorator for every kernel."""

# The clock below needs object mode for an instant per checkpoint; numba warns
# that such a block takes the GIL, which is what we want there.
warnings.filterwarnings("ignore", message=".*object mode.*", category=NumbaWarning)


@numba.njit(cache=True)
def clock():
    """Seconds from a monotonic clock, callable from kernels."""
    with numba.objmode(t="float64"):
        t = time.perf_counter()
    return t
