"""The growth kernels are compiled for one dimension at a time, and only for
those in use (``dlasweep._jit``'s note): in a fresh process, a 2D growth of
each model leaves one compiled kernel each, for the literal 2 and one walker
(``kernels.model.lockstep_flag``: None), and its calls never ask numba for a
plain int's (``_jit.call_literal``: 7 ms a call)."""

import json
import subprocess
import sys

SCRIPT = """
import json
import dlasweep as dla
from dlasweep.kernels.lattice import lattice_growth as lattice
from dlasweep.kernels.offlattice import offlattice_growth as offlattice
for model in ("lattice", "offlattice"):
    for seed in (1, 2):
        dla.grow(300, seed=seed, model=model, dim=2)
kernels = [kernel._grow_each for kernel in (lattice, offlattice)]
print(json.dumps([[str(sig[:2]) for sig in kernel.signatures] for kernel in kernels]))
asked = {str(sig[0]) for kernel in kernels for sig in [*kernel.stats.cache_hits, *kernel.stats.cache_misses]}
print(json.dumps(sorted(asked)))
"""


def test_a_2d_growth_compiles_and_asks_for_the_kernels_for_2d_alone():
    out = subprocess.run([sys.executable, "-c", SCRIPT], capture_output=True, text=True, check=True)
    compiled, asked = map(json.loads, out.stdout.strip().splitlines()[-2:])
    assert compiled == [["(Literal[int](2), none)"], ["(Literal[int](2), none)"]]
    assert asked == ["Literal[int](2)"]
