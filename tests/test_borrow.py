"""Kernels that borrow arrays (``_jit.borrow``: numba's reference counting off)
must allocate nothing they keep: an array such a kernel receives from a callee
is never freed. Counted with numba's allocation statistics across a growth of
each model, in a fresh process (the statistics are switched on before numba
loads)."""

import json
import os
import subprocess
import sys

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
