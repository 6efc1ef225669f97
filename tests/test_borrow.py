"""Kernels that borrow arrays (``_jit.borrow``: numba's reference counting off)
must allocate nothing they keep: an array such a kernel receives from a callee
is never freed. Counted with numba's allocation statistics across a growth of
each model, in a fresh process (the statistics are switched on before numba
loads); and, over every kernel of the package, by reading their sources: no
borrowing kernel calls a helper that allocates with no reference counting
of its own (``_jit.owning``)."""

import json
import os
import subprocess
import sys

import numpy as np
import pytest

CASES = [
    dict(model="lattice", dim=2),
    dict(model="lattice", dim=3),
    dict(model="offlattice", dim=2),
    dict(model="offlattice", dim=3),
    dict(model="offlattice", dim=2, stickiness=0.3),
    dict(model="offlattice", dim=2, seed_shape="line", size=200),
    dict(model="offlattice", dim=2, launch="box", size=400),
    dict(model="offlattice", dim=2, walkers=500, size=120),  # a walk a turn: 3000 walkers in 300 took 64 s
    dict(model="lattice", dim=2, walkers=500, size=120),  # compiled apart from one walker's (``lockstep_flag``)
]

SCRIPT = """
import gc, json, sys
from numba.core.runtime import rtsys
import dlasweep as dla
params = json.loads(sys.argv[1])
dla.grow(500, seed=1, **params)  # compiled and warmed
gc.collect()  # a fresh compilation leaves arrays in garbage cycles: freed here, not below
before = rtsys.get_allocation_stats()
cluster = dla.grow(20000, seed=2, **params)
del cluster
gc.collect()
after = rtsys.get_allocation_stats()
print(json.dumps([after.mi_alloc - before.mi_alloc, after.mi_free - before.mi_free]))
"""


@pytest.mark.parametrize("params", CASES, ids=lambda p: "-".join(str(v) for v in p.values()))
def test_a_growth_frees_every_array_it_allocates(params):
    env = dict(os.environ, NUMBA_NRT_STATS="1")
    out = subprocess.run([sys.executable, "-c", SCRIPT, json.dumps(params)], capture_output=True, text=True, env=env,
                         check=True)
    allocated, freed = json.loads(out.stdout.strip().splitlines()[-1])
    # a kept array per walk would leave about 20000 unfreed
    assert allocated == freed, (allocated, freed)


ALLOCATORS = {"empty", "zeros", "ones", "full", "arange", "array", "concatenate", "sort", "argsort", "cumsum",
              "unique", "copy", "empty_like", "zeros_like", "ones_like", "full_like"}
"""numpy functions that return a new array."""


def _kernels():
    """Every numba dispatcher defined in a module of the package."""
    import importlib
    import pkgutil

    from numba.core.registry import CPUDispatcher

    import dlasweep

    found = {}
    for info in pkgutil.walk_packages(dlasweep.__path__, "dlasweep."):
        if info.name.endswith("__main__"):  # importing it runs the CLI
            continue
        module = importlib.import_module(info.name)
        for value in vars(module).values():
            if isinstance(value, CPUDispatcher) and value.py_func.__module__ == info.name:
                found[f"{info.name}.{value.py_func.__name__}"] = value
    return found


def _callees(kernel):
    """The numba dispatchers a kernel's source calls by name (``f(...)``, ``module.f(...)``), and whether it
    calls a numpy function that allocates (or an array's ``copy`` or ``astype``)."""
    import ast
    import inspect
    import textwrap

    from numba.core.registry import CPUDispatcher

    tree = ast.parse(textwrap.dedent(inspect.getsource(kernel.py_func)))
    names = kernel.py_func.__globals__
    callees, allocates = [], False
    for node in ast.walk(tree):
        if not isinstance(node, ast.Call):
            continue
        func = node.func
        target = None
        if isinstance(func, ast.Name):
            target = names.get(func.id)
        elif isinstance(func, ast.Attribute) and isinstance(func.value, ast.Name):
            owner = names.get(func.value.id)
            if owner is np and func.attr in ALLOCATORS:
                allocates = True
            elif func.attr in ("copy", "astype"):
                allocates = True
            target = getattr(owner, func.attr, None)
        if isinstance(target, CPUDispatcher):
            callees.append(target)
    return callees, allocates


def _reference_counting(kernel):
    """True (``_jit.owning``), False (``_jit.borrow``) or None: inherited from the caller numba compiles it for."""
    return kernel.targetoptions.get("_nrt")


def borrowed_allocations(kernels):
    """The call chains from a borrowing kernel to one that allocates and has no reference counting of its own.

    numba compiles a ``jit`` (or ``inline``) helper with the reference counting of the caller it is first
    compiled for: under a borrowing caller its arrays are never freed (``_jit.owning``)."""
    chains = []
    for name, kernel in kernels.items():
        if _reference_counting(kernel) is not False:
            continue
        stack, seen = [(callee, [name]) for callee in _callees(kernel)[0]], set()
        while stack:
            callee, path = stack.pop()
            if callee in seen or _reference_counting(callee) is not None:
                continue
            seen.add(callee)
            more, allocates = _callees(callee)
            path = path + [callee.py_func.__qualname__]
            if allocates:
                chains.append(" -> ".join(path))
            stack += [(c, path) for c in more]
    return chains


def test_no_borrowing_kernel_calls_a_helper_that_allocates_without_reference_counting():
    """The static twin of the counts above, over every kernel of the package, not only those a growth runs:
    ``offlattice.grid.map_dist`` as plain ``jit`` (it allocates its pyramid's level starts) is found here."""
    kernels = _kernels()
    assert len(kernels) > 100 and any(_reference_counting(k) is False for k in kernels.values())
    assert borrowed_allocations(kernels) == []
