"""Numba settings, set once for every kernel in the package.

``cache`` keeps compiled kernels on disk so that each dask worker compiles
once; ``nogil`` lets threads of one worker share it; ``fastmath`` stays off so
that results are bit-identical wherever they are computed.

numba's cache checks only the defining file of a function: after editing a
helper in another module, delete ``dlasweep/**/__pycache__/*.nb[ic]`` or the
callers keep the old machine code. An install replaces every file, so users
are not affected.
"""

import time
import warnings

import numba
from numba.core.errors import NumbaWarning

_SETTINGS = dict(cache=True, nogil=True, fastmath=False, error_model="numpy")
jit = numba.njit(**_SETTINGS)
"""Decorator for every kernel."""
inline = numba.njit(**_SETTINGS, inline="always")
"""Decorator for small scalar helpers inlined at numba level. Measured: on the
lattice kernel's array-taking helpers it made the kernel 1.5x slower."""

# The clock below needs object mode for an instant per checkpoint; numba warns
# that such a block takes the GIL, which is what we want there.
warnings.filterwarnings("ignore", message=".*object mode.*", category=NumbaWarning)


@numba.njit(cache=True)
def clock():
    """Seconds from a monotonic clock, callable from kernels."""
    with numba.objmode(t="float64"):
        t = time.perf_counter()
    return t
