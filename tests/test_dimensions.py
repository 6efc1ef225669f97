"""The growth kernels are compiled for one dimension at a time, and only for
those in use (``dlasweep._jit``'s note): in a fresh process, a 2D growth of
each model, one cluster and a batch, leaves one compiled kernel each, for the
literal 2 and one walker (``kernels.model.lockstep_flag``: None), and its calls
never ask numba for a plain int's (``_jit.call_literal``: 7 ms a call). Off the
lattice, a walk of exact moves leaves the Gaussian step out (``kernels.model.gaussian_flag``)."""

import json
import subprocess
import sys

from numba.core import compiler, ir, types
from numba.core.analysis import dead_branch_prune

from dlasweep.kernels.offlattice import contact, walker

SCRIPT = """
import json
import dlasweep as dla
from dlasweep.growth.cluster import grow_many
from dlasweep.kernels.lattice import lattice_growth as lattice
from dlasweep.kernels.offlattice import offlattice_growth as offlattice
for model in ("lattice", "offlattice"):
    for seed in (1, 2):
        dla.grow(300, seed=seed, model=model, dim=2)
    grow_many(300, [1, 2], model=model, dim=2)  # a batch: the same kernel
kernels = [kernel._grow for kernel in (lattice, offlattice)]
print(json.dumps([[str(sig[:2]) for sig in kernel.signatures] for kernel in kernels]))
asked = {str(sig[0]) for kernel in kernels for sig in [*kernel.stats.cache_hits, *kernel.stats.cache_misses]}
print(json.dumps(sorted(asked)))
"""


def test_a_2d_growth_compiles_and_asks_for_the_kernels_for_2d_alone():
    out = subprocess.run([sys.executable, "-c", SCRIPT], capture_output=True, text=True, check=True)
    compiled, asked = map(json.loads, out.stdout.strip().splitlines()[-2:])
    assert compiled == [["(Literal[int](2), none)"], ["(Literal[int](2), none)"]]
    assert asked == ["Literal[int](2)"]


def globals_typed(kernel, flag):
    """The globals ``kernel``'s body reads once numba has pruned its branches for the literal dimension 2 and
    ``flag`` as its second argument's type: what numba goes on to type and compile."""
    func = kernel.py_func
    func_ir = compiler.run_frontend(func)
    dead_branch_prune(func_ir, [types.literal(2), flag] + [types.float64] * (func.__code__.co_argcount - 2))
    return {stmt.value.value for block in func_ir.blocks.values() for stmt in block.body
            if isinstance(stmt, ir.Assign) and isinstance(stmt.value, ir.Global)}


def test_an_exact_walk_leaves_the_gaussian_step_uncompiled():
    assert contact.gauss_move not in globals_typed(walker.walk_to_contact, types.none)
    assert contact.gauss_move in globals_typed(walker.walk_to_contact, types.boolean)
