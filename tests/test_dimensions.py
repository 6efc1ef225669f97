"""The growth kernels are compiled for one dimension at a time, and only for
those in use (``dlasweep._jit``'s note): in a fresh process, a 2D growth of
each model leaves one compiled kernel each, for the literal 2."""

import json
import subprocess
import sys

SCRIPT = """
import json
import dlasweep as dla
from dlasweep.kernels.lattice import grow as lattice
from dlasweep.kernels.offlattice import grow as offlattice
for model in ("lattice", "offlattice"):
    dla.grow(300, seed=1, model=model, dim=2)
print(json.dumps([[str(sig[0]) for sig in kernel._grow_each.signatures] for kernel in (lattice, offlattice)]))
"""


def test_a_2d_growth_compiles_the_kernels_for_2d_alone():
    out = subprocess.run([sys.executable, "-c", SCRIPT], capture_output=True, text=True, check=True)
    assert json.loads(out.stdout.strip().splitlines()[-1]) == [["Literal[int](2)"], ["Literal[int](2)"]]
