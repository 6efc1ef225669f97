"""Off-lattice noise reduction against fastDLA: mean Rg at three sizes, side by side.

    .venv/bin/python workflows/peer_noise_fastdla.py --fastdla PATH/TO/fastDLA [--clusters 32] [--factor 0.5]

fastDLA (github.com/mathsjames/fastDLA) grows 2D off-lattice DLA with a
``noiseReductionFactor`` f: a walker that touches the cluster is put at f
diameters from the particle it touched, along the line between them; dlasweep
grows the same law as ``contact_distance`` f. The script builds fastDLA as
``peer_fastdla.py`` does (``build``: g++ into a temporary folder, nothing
vendored), grows ``--clusters`` clusters of the largest size with each code
(seeds 1, 2, ...; fastDLA's points written to a temporary file, its units of
radius 1 halved to diameters), and prints, at each size (a prefix of each
cluster: both codes attach particles in order), the mean radius of gyration of
each, their standard errors, and the difference in standard errors of the
difference. Both at ``--factor`` and, as a control that the comparison can
fail, dlasweep at the factor against fastDLA at 1 (plain DLA).

fastDLA's seed is two touching particles (at one diameter, whatever f), ours
one particle: a difference of one particle's place, far below the
clusters' spread at 1e3 particles and more.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
from peer_fastdla import SOURCES, build, version

import dlasweep as dla
from dlasweep.measures.shape import radius_of_gyration

SIZES = (1_000, 10_000, 100_000)


def fastdla_points(binary: Path, n: int, seed: int, factor: float, scratch: Path) -> np.ndarray:
    """fastDLA's cluster of n particles for ``seed`` at noise reduction ``factor``, in diameters."""
    out = scratch / f"fastdla-{seed}.bin"
    subprocess.run([str(binary), str(n), str(out), str(seed), repr(factor)], check=True, capture_output=True)
    z = np.fromfile(out, dtype=np.complex128)
    out.unlink()
    return np.column_stack([z.real, z.imag]) / 2.0  # fastDLA's particles have radius 1


def rg_at(points, sizes):
    rg = radius_of_gyration(points)
    return [rg[k - 1] for k in sizes]


def table(name_a, a, name_b, b, sizes) -> str:
    """Mean Rg of ``a`` and ``b`` (clusters by sizes) at each size, standard errors, and their difference in
    standard errors of the difference."""
    lines = [f"| n | {name_a} mean Rg | s.e. | {name_b} mean Rg | s.e. | difference / s.e. |",
             "|---|---|---|---|---|---|"]
    for j, n in enumerate(sizes):
        ma, mb = a[:, j].mean(), b[:, j].mean()
        ea, eb = a[:, j].std(ddof=1) / np.sqrt(len(a)), b[:, j].std(ddof=1) / np.sqrt(len(b))
        lines.append(f"| {n:,} | {ma:.3f} | {ea:.3f} | {mb:.3f} | {eb:.3f} | {(ma - mb) / np.hypot(ea, eb):+.2f} |")
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--fastdla", type=Path, required=True, help="checkout of mathsjames/fastDLA")
    parser.add_argument("--clusters", type=int, default=32)
    parser.add_argument("--factor", type=float, default=0.5)
    parser.add_argument("--sizes", type=int, nargs=3, default=SIZES)
    args = parser.parse_args(argv)
    missing = [name for name in SOURCES if not (args.fastdla / name).is_file()]
    if missing:
        print(f"peer_noise_fastdla.py: --fastdla: {args.fastdla} holds no {', '.join(missing)}", file=sys.stderr)
        return 2
    sizes, n = list(args.sizes), max(args.sizes)
    seeds = range(1, args.clusters + 1)
    with tempfile.TemporaryDirectory() as scratch:
        binary = build(args.fastdla, Path(scratch))
        theirs = {f: np.array([rg_at(fastdla_points(binary, n, s, f, Path(scratch)), sizes) for s in seeds])
                  for f in (args.factor, 1.0)}
    ours = np.array([rg_at(dla.grow(n, seed=s, model="offlattice", contact_distance=args.factor).points, sizes)
                     for s in seeds])
    print(f"fastDLA {version(args.fastdla)}; {args.clusters} clusters each, seeds 1 to {args.clusters}; "
          f"command: python workflows/peer_noise_fastdla.py {' '.join(sys.argv[1:] if argv is None else argv)}\n")
    print(f"contact_distance {args.factor} against noiseReductionFactor {args.factor}:\n")
    print(table(f"dlasweep f={args.factor}", ours, f"fastDLA f={args.factor}", theirs[args.factor], sizes))
    print(f"\ncontrol: contact_distance {args.factor} against noiseReductionFactor 1 (plain DLA):\n")
    print(table(f"dlasweep f={args.factor}", ours, "fastDLA f=1", theirs[1.0], sizes))
    return 0


if __name__ == "__main__":
    sys.exit(main())
