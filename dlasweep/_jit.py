"""Numba settings, set once for every kernel in the package.

``cache`` keeps compiled kernels on disk so that each dask worker compiles
once; ``nogil`` lets threads of one worker share it; ``fastmath`` stays off so
that results are bit-identical wherever they are computed.

The hot kernels are compiled for one dimension at a time: the dimension
comes down to them as a literal argument (``numba.literally``), compiled
only when used, and is turned there into a constant, ``dim =
np.int64(2) if dimension == 2 else np.int64(3)``, for LLVM to fold the
kernel's branches on it; not the literal itself, which would recompile
every helper it is passed to. numba types and compiles both sides of a
branch on the literal's value all the same: a branch it leaves out while it
types a kernel is one on whether an argument is None, hence the kernels'
None-or-True flags (``kernels.model.lockstep_flag``, ``gaussian_flag``).
Python calls such a kernel through ``call_literal``, or ``literal_entry``
for a batch.

numba's cache checks only the defining file of a function: after editing a
helper in another module, delete ``dlasweep/**/__pycache__/*.nb[ic]`` or the
callers keep the old machine code. An install replaces every file, so users
are not affected.
"""

import time
import warnings

import llvmlite.ir
import numba
import numba.core.cgutils
import numba.extending
import numpy as np
from numba.core.errors import NumbaPendingDeprecationWarning

_SETTINGS = dict(cache=True, nogil=True, fastmath=False, error_model="numpy")
jit = numba.njit(**_SETTINGS)
"""Decorator for every kernel."""
borrow = numba.njit(**_SETTINGS, _nrt=False)
"""Decorator for a hot kernel that only borrows arrays: numba's reference
counting off, so that handing arrays on (to a helper it inlines or calls)
costs no atomic increment and decrement, which otherwise take a large share
of a growth (see docs/performance.md). Such a kernel must allocate no array and
keep none a callee returns: it would never be freed (``test_borrow`` counts
numba's allocations across each growth kernel)."""
owning = numba.njit(**_SETTINGS, _nrt=True)
"""Decorator for a kernel that allocates and frees an array of its own and may be called from one that
borrows. A ``jit`` kernel takes numba's reference counting from the caller it is first compiled for
(numba inherits the flag), so called first from a borrowing kernel it would allocate without ever freeing:
``offlattice.grid.map_dist``, compiled first by the single walker's Gaussian step, leaked its pyramid's level
starts at every step of the lockstep walkers compiled after it (``test_borrow`` counts the allocations, and
follows every borrowing kernel's calls to find such a helper)."""
inline = numba.njit(**_SETTINGS, inline="always")
"""Decorator for small scalar helpers inlined at numba level. Only for scalar
helpers: numba-level inlining of the lattice kernel's array-taking helpers
made the kernel slower, not faster (see docs/performance.md)."""


def call_literal(kernel, first, *args):
    """``kernel(first, *args)``, compiled (or loaded) for the literal ``first``, as the dimension.

    Called plainly, numba's dispatcher first tries to compile the kernel for an
    int (the literal is asked for only once typing reaches ``literally``), at
    every call, which costs more than a small cluster's growth (see
    docs/performance.md). ``compile`` of the literal signature finds the
    compiled overload at once.

    Parameters
    ----------
    kernel : numba dispatcher
        A kernel whose first argument is a literal (``numba.literally``).
    first : int
        That argument's value, the dimension: the kernel is compiled (or
        loaded from numba's cache) for it.
    *args
        The kernel's other arguments, typed as they are passed.
    """
    return literal_entry(kernel, first, *args)(first, *args)


def literal_entry(kernel, first, *args):
    """The compiled ``kernel`` for the literal ``first`` and arguments of the types of ``args``, compiled
    (or loaded) once: calling it skips the dispatcher's typing of every argument, so that a batch's
    clusters can each be one call of it from Python (``call_literal`` takes the arguments' types at
    each call). ``kernel``, ``first`` and ``args`` are ``call_literal``'s."""
    signature = (numba.types.literal(first),) + tuple(numba.typeof(a) for a in args)
    return kernel.compile(signature)


def cached(kernel, first, *more, last=...) -> bool:
    """Whether numba's on-disk cache holds compiled code of ``kernel`` (a function ``jit`` made)
    for the literal first argument ``first`` (a kernel compiled apart for each, as the dimension)
    and arguments of the types of ``more`` after it, and, when ``last`` is given, a last argument
    of its type.

    Reads numba's own cache index, the one place this package looks inside numba."""
    types = tuple(numba.typeof(a) for a in more)
    ends = [] if last is ... else [numba.typeof(last)]
    return any(getattr(key[0][0], "literal_value", None) == first and tuple(key[0][1:1 + len(types)]) == types
               and list(key[0][len(key[0]) - len(ends):]) == ends
               for key in kernel._cache._cache_file._load_index())


# The growth kernels take a batch's generators as a Python list: numba's
# typed list costs more a generator to build than the call it saves (docs/performance.md).
warnings.filterwarnings("ignore", message="(?s).*reflected list", category=NumbaPendingDeprecationWarning)
# ``maps.zeroed`` maps its largest arrays in object mode (``maps._unreserved``), a call that holds the
# GIL once a regrid: numba warns of it at every load of each kernel that calls it.
warnings.filterwarnings("ignore", message="(?s).*Code running in object mode won't allow parallel",
                        category=numba.NumbaWarning)

_clock_gettime = numba.types.ExternalFunction("clock_gettime", numba.int32(numba.int32, numba.types.voidptr))
"""The C library's, linked by name (a ctypes pointer would keep numba from caching its callers)."""


@numba.extending.intrinsic
def _address(typingctx, array):
    """The address of an array's data, for C."""
    def codegen(context, builder, signature, args):
        data = context.make_array(array)(context, builder, args[0]).data
        return builder.bitcast(data, context.get_value_type(numba.types.voidptr))
    return numba.types.voidptr(array), codegen


@numba.extending.intrinsic
def prefetch(typingctx, array, index):
    """Ask the processor to bring the cache line of ``array[index]`` (its row, for a 2D array) in
    while other work goes on: a hint (``llvm.prefetch``) that reads nothing and never faults."""
    def codegen(context, builder, signature, args):
        aryty = signature.args[0]
        ary = context.make_array(aryty)(context, builder, args[0])
        zero = context.get_constant(numba.types.intp, 0)
        where = numba.core.cgutils.get_item_pointer(context, builder, aryty, ary, [args[1]] + [zero] * (aryty.ndim - 1),
                                                    wraparound=False)
        i8 = llvmlite.ir.IntType(8).as_pointer()
        i32 = llvmlite.ir.IntType(32)
        hint = numba.core.cgutils.get_or_insert_function(
            builder.module, llvmlite.ir.FunctionType(llvmlite.ir.VoidType(), [i8, i32, i32, i32]), "llvm.prefetch.p0")
        # a read (0), kept in every cache level (3), of data (1)
        builder.call(hint, [builder.bitcast(where, i8), i32(0), i32(3), i32(1)])
        return context.get_dummy_value()
    return numba.types.void(array, index), codegen


@jit
def clock():
    """Seconds from the monotonic clock (``time.CLOCK_MONOTONIC``), callable from kernels without the GIL.

    It reads the C library's ``clock_gettime`` without the GIL, so that a
    kernel of a sweep's thread does not wait at each checkpoint while another
    thread runs Python, as it would in numba's object mode.
    """
    timespec = np.empty(2, np.int64)  # seconds, nanoseconds: a struct timespec on 64-bit systems
    _clock_gettime(time.CLOCK_MONOTONIC, _address(timespec))
    return timespec[0] + timespec[1] * 1e-9
