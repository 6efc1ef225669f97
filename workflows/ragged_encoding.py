"""What the zlib level and the chunk size of the per-particle arrays cost, at 10^8 stored particles.

Writes a sweep file of CLUSTERS clusters of N particles with ``store.save``
(the clusters streamed, as a sweep writes them) for each zlib level and
chunk size, then reads one cluster back with ``ragged.cluster_points``, as
the report does. The clusters are SAMPLES real clusters grown once and
repeated: every HDF5 chunk is compressed on its own, so a chunk of a
repeated cluster compresses as one of a new cluster would.

    python workflows/ragged_encoding.py --model lattice -o /tmp/encoding   # 1000 x 1e5, 1.6 GB per file

Prints one row per (level, chunk): write seconds, file MB, bytes per
particle, and the median seconds to open the file and read one cluster.
"""

from __future__ import annotations

import argparse
import itertools
import statistics
import time
from pathlib import Path

import numpy as np

import dlasweep as dla
from dlasweep.data import netcdf as store
from dlasweep.data import ragged
from dlasweep.sweep.spec import parse_spec


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--model", default="lattice", choices=("lattice", "offlattice"))
    parser.add_argument("-n", type=int, default=100_000, help="particles per cluster")
    parser.add_argument("--clusters", type=int, default=1000)
    parser.add_argument("--samples", type=int, default=8, help="distinct clusters grown")
    parser.add_argument("--levels", default="0,1,4,9")
    parser.add_argument("--chunks", default="14,16,18,20", help="log2 of values per chunk")
    parser.add_argument("-o", "--out", type=Path, default=Path("/tmp/encoding"))
    args = parser.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)

    grown = [dla.grow(args.n, seed, model=args.model) for seed in range(args.samples)]
    spec = parse_spec(f'[grid]\nn_particles = [{args.n}]\nseeds = {args.clusters}\n'
                      f'[model]\nmodel = "{args.model}"\n')
    ds = store.to_dataset(spec, np.ones(1), np.array([args.n]), _empty(spec), [args.n] * args.clusters)
    print(f"{args.clusters} clusters of {args.n} ({args.model}), {args.clusters * args.n:.2e} particles")
    print("level  chunk   write_s   file_MB  bytes/particle  read_one_s")
    rng = np.random.default_rng(0)
    for level, log_chunk in itertools.product(map(int, args.levels.split(",")), map(int, args.chunks.split(","))):
        store.PARTICLE_ZLIB, store.PARTICLE_CHUNK = level, 1 << log_chunk
        path = args.out / f"z{level}-c{log_chunk}.nc"
        clusters = ((grown[i % len(grown)].points, grown[i % len(grown)].steps, grown[i % len(grown)].parents)
                    for i in range(args.clusters))
        start = time.perf_counter()
        store.save(ds, path, clusters)
        write = time.perf_counter() - start
        reads = []
        for index in rng.integers(0, args.clusters, 5):
            start = time.perf_counter()
            with store.open_sweep(path) as back:
                ragged.cluster_points(back, int(index))
                np.asarray(back["diffusion_time"][int(index) * args.n:(int(index) + 1) * args.n])
            reads.append(time.perf_counter() - start)
        size = path.stat().st_size
        print(f"{level:5d}  2^{log_chunk:<4d} {write:8.1f}  {size / 1e6:8.0f}  {size / (args.clusters * args.n):14.2f}"
              f"  {statistics.median(reads):10.3f}", flush=True)
        path.unlink()


def _empty(spec):
    """Science arrays of the right shapes (their values do not matter here)."""
    grid = (*spec.shape[:-1], len(spec.counts), spec.shape[-1])
    return {"box_count": np.zeros((*grid, 1), np.int64), "n_grown": np.zeros(grid, np.int64),
            "status": np.zeros(grid, np.int8), "walk_steps": np.zeros(grid, np.int64),
            **{name: np.zeros(grid) for name in ("radius_gyration", "max_radius", "anisotropy", "wall_time")},
            "radius_gyration_history": np.zeros((*spec.shape, 1))}


if __name__ == "__main__":
    main()
