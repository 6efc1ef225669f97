"""Where the compile time of a first grow goes: each compiled function's share, on an empty numba cache.

    NUMBA_CACHE_DIR=$(mktemp -d) python workflows/compile_time.py --model offlattice --dim 2

grows one small cluster in a fresh process and prints the whole grow's time and, from numba's
``numba:compile`` events, the functions that took longest to compile: each one's own time (its callees
compiled inside it excluded) and its inclusive time. Run it with an empty ``NUMBA_CACHE_DIR``, or the
kernels load from the cache and nothing compiles. Beside the wall time it prints the process's
processor time: compiling runs on one core, so on a host shared with other work the processor
time is the steadier figure. The figures are in docs/performance.md.
"""

from __future__ import annotations

import argparse
import collections
import time

from numba.core import event

import dlasweep as dla


class CompileTimes(event.Listener):
    """Inclusive and own seconds of every function numba compiles while it is registered."""

    def __init__(self):
        self.inclusive = collections.defaultdict(float)
        self.own = collections.defaultdict(float)
        self._stack = []  # [start, seconds of the compiles nested in it]

    def on_start(self, ev):
        self._stack.append([time.perf_counter(), 0.0])

    def on_end(self, ev):
        start, nested = self._stack.pop()
        took = time.perf_counter() - start
        func = ev.data["dispatcher"].py_func
        name = f"{func.__module__.removeprefix('dlasweep.')}.{func.__qualname__}"
        self.inclusive[name] += took
        self.own[name] += took - nested
        if self._stack:
            self._stack[-1][1] += took


def main():
    parser = argparse.ArgumentParser(description=__doc__.partition("\n")[0])
    parser.add_argument("--model", default="lattice", choices=["lattice", "offlattice"])
    parser.add_argument("--dim", type=int, default=2, choices=[2, 3])
    parser.add_argument("-n", type=int, default=1000, help="particles of the cluster (default 1000)")
    parser.add_argument("--top", type=int, default=12, help="functions listed (default 12)")
    args = parser.parse_args()
    times = CompileTimes()
    event.register("numba:compile", times)
    start, processor = time.perf_counter(), time.process_time()
    dla.grow(n=args.n, seed=1, model=args.model, dim=args.dim)
    took, processor = time.perf_counter() - start, time.process_time() - processor
    print(f"{args.model} {args.dim}D, n = {args.n}: first grow {took:.1f} s ({processor:.1f} s of processor time), "
          f"{len(times.own)} functions compiled in {sum(times.own.values()):.1f} s")
    for name, own in sorted(times.own.items(), key=lambda item: -item[1])[:args.top]:
        print(f"  {own:6.1f} s own  {times.inclusive[name]:6.1f} s inclusive  {name}")


if __name__ == "__main__":
    main()
