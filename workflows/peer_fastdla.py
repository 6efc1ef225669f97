"""Peer benchmark: 2D off-lattice DLA, dlasweep against fastDLA, in one run.

    .venv/bin/python workflows/peer_fastdla.py --fastdla PATH/TO/fastDLA -o results/bench

fastDLA (github.com/mathsjames/fastDLA, C++, Ossadnik's algorithm) grows
the same model: unit disks, one random walker at a time, exact contact. Point
``--fastdla`` at a checkout of it (a folder holding ``fastDLA.cpp`` and
``fastDLA.hpp``); the script compiles it into a temporary folder with
``g++ --std=gnu++11 -O3 -march=native`` and copies, vendors or downloads
nothing. Each round runs, in turn and each in a fresh single-threaded
process, our kernel (``dlasweep.bench.benchmark.probe``: seconds of ``grow`` with
compilation excluded, peak resident memory of the process and the part that
growth added) and ``fastDLA N '' SEED`` (an empty file name writes nothing:
wall seconds of the whole process and its peak resident memory, from
``/usr/bin/time``). Rounds alternate which goes first, so that a drift in the
machine's speed falls on both.

It writes ``peer_fastdla.csv`` (one row per run) and ``peer_fastdla.md``
(medians and the ratios fastDLA / dlasweep) into the output folder.
"""

from __future__ import annotations

import argparse
import csv
import hashlib
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from dlasweep.bench.benchmark import probe

OFFLATTICE_2D = {"model": "offlattice", "dim": 2}
COUNTS = [100_000, 1_000_000]
LARGE = 10_000_000
SOURCES = ("fastDLA.cpp", "fastDLA.hpp")
TIME = "/usr/bin/time"
SINGLE_THREAD = {"NUMBA_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}


class _Parser(argparse.ArgumentParser):
    def error(self, message):
        self.exit(2, f"peer_fastdla.py: {message}\n")  # one line, naming what was wrong


def build(checkout: Path, into: Path) -> Path:
    """Compile fastDLA from ``checkout`` into ``into``; return the binary's path."""
    binary = into / "fastDLA"
    subprocess.run(["g++", "--std=gnu++11", "-O3", "-march=native", "-o", str(binary), str(checkout / SOURCES[0])],
                   check=True, capture_output=True, text=True)
    return binary


def version(checkout: Path) -> str:
    """The checkout's git commit, else a hash of its two source files."""
    try:
        out = subprocess.run(["git", "-C", str(checkout), "rev-parse", "HEAD"], check=False, capture_output=True,
                             text=True)
        if out.returncode == 0:
            return "commit " + out.stdout.strip()
    except OSError:
        pass
    digest = hashlib.sha256(b"".join((checkout / name).read_bytes() for name in SOURCES)).hexdigest()
    return f"sources sha256 {digest[:16]}"


def run_fastdla(binary: Path, n: int, seed: int) -> dict:
    """Run ``fastDLA n '' seed``; its wall seconds and peak resident memory (MiB).

    The peak comes from ``/usr/bin/time``: a child of this process would
    inherit this process's own peak in its ``ru_maxrss``.
    """
    start = time.perf_counter()
    out = subprocess.run([TIME, "-f", "%M", str(binary), str(n), "", str(seed)],
                         check=False, capture_output=True, text=True)
    seconds = time.perf_counter() - start
    if out.returncode != 0:
        raise RuntimeError(f"fastDLA {n} '' {seed} failed: {out.stderr.strip()}")
    return {"seconds": seconds, "peak_mb": int(out.stderr.split()[-1]) / 1024, "added_mb": float("nan")}


def run_ours(n: int, seed: int) -> dict:
    """Grow one 2D off-lattice cluster of ``n`` in a fresh process (``dlasweep.bench.benchmark.probe``)."""
    r = probe(OFFLATTICE_2D, n, seed=seed)
    if r["n_grown"] != n:
        raise RuntimeError(f"dlasweep grew {r['n_grown']} of {n} particles ({r['status']})")
    return {"seconds": r["seconds"], "peak_mb": r["peak_mb"], "added_mb": r["added_mb"]}


def measure(binary: Path, plan, echo=print) -> list[dict]:
    """Both codes at every (count, rounds) of ``plan``, alternating which goes first."""
    rows = []
    runners = {"dlasweep": run_ours, "fastDLA": lambda n, seed: run_fastdla(binary, n, seed)}
    for n, rounds in plan:
        for k in range(rounds):
            seed = k + 1
            order = list(runners) if k % 2 == 0 else list(runners)[::-1]
            for code in order:
                r = runners[code](n, seed)
                rows.append(dict(code=code, n=n, round=k, seed=seed, **r))
                echo(f"{code:<9}{n:>10}  seed {seed}: {r['seconds']:8.2f} s, peak {r['peak_mb']:6.0f} MB")
    return rows


def summary(rows, fastdla_version: str, command: str, load: tuple) -> str:
    """Medians and ratios as a markdown table; ``load``: the 1-minute load average before and after."""
    lines = [
        "# 2D off-lattice DLA: dlasweep against fastDLA",
        "",
        f"`{command}`",
        "",
        (f"fastDLA {fastdla_version}, g++ -O3 -march=native; {platform.processor() or platform.machine()}, "
        f"{os.cpu_count()} cores, Python {platform.python_version()}. Each run a fresh single-threaded process; "
        "dlasweep's seconds exclude compilation and interpreter start, fastDLA's are its whole process. "
        "Medians over the rounds (range in brackets); ratio > 1: dlasweep is faster or smaller. "
         f"Load average (1 min) {load[0]:.1f} before, {load[1]:.1f} after: above 1 per core, other work shared "
         "the machine and slowed both codes alike only on average."),
        "",
        ("| N | rounds | dlasweep s | fastDLA s | time fastDLA/dlasweep | dlasweep peak MB (added) | fastDLA peak MB "
        "| memory fastDLA/dlasweep |"),
        "|---|---|---|---|---|---|---|---|",
    ]

    def stat(values, fmt):
        return f"{fmt.format(statistics.median(values))} ({fmt.format(min(values))}-{fmt.format(max(values))})"

    for n in sorted({r["n"] for r in rows}):
        ours = [r for r in rows if r["n"] == n and r["code"] == "dlasweep"]
        theirs = [r for r in rows if r["n"] == n and r["code"] == "fastDLA"]
        time_ratio = [t["seconds"] / o["seconds"] for o, t in zip(ours, theirs)]
        mem_ratio = [t["peak_mb"] / o["peak_mb"] for o, t in zip(ours, theirs)]
        lines.append(
            f"| {n:,} | {len(ours)} | {stat([r['seconds'] for r in ours], '{:.2f}')} "
            f"| {stat([r['seconds'] for r in theirs], '{:.2f}')} | {stat(time_ratio, '{:.2f}')} "
            f"| {statistics.median(r['peak_mb'] for r in ours):.0f} "
            f"({statistics.median(r['added_mb'] for r in ours):.0f}) "
            f"| {statistics.median(r['peak_mb'] for r in theirs):.0f} | {stat(mem_ratio, '{:.2f}')} |"
        )
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    parser = _Parser(description=__doc__.splitlines()[0])
    parser.add_argument("--fastdla", type=Path, required=True, help="checkout of mathsjames/fastDLA")
    parser.add_argument("-o", "--output", type=Path, default=Path("results/bench"), help="output folder")
    parser.add_argument("--rounds", type=int, default=3, help="runs of each code at each N (default 3)")
    parser.add_argument("--large", action="store_true", help=f"add N = {LARGE:.0e} (minutes per run)")
    parser.add_argument("--large-rounds", type=int, default=1, help=f"runs of each code at N = {LARGE:.0e} (default 1)")
    parser.add_argument("--counts", type=int, nargs="+", help=f"counts instead of {COUNTS} (and --large)")
    args = parser.parse_args(argv)
    missing = [name for name in SOURCES if not (args.fastdla / name).is_file()]
    if missing:
        parser.error(f"--fastdla: {args.fastdla} holds no {', '.join(missing)}")
    if not os.access(TIME, os.X_OK):
        parser.error(f"needs {TIME} (GNU time) for fastDLA's peak memory")
    for key in ("rounds", "large_rounds"):
        if getattr(args, key) < 1:
            parser.error(f"--{key.replace('_', '-')}: expected an integer >= 1, got {getattr(args, key)}")
    if args.counts and min(args.counts) < 1:
        parser.error(f"--counts: expected integers >= 1, got {args.counts}")
    if args.output.exists() and not args.output.is_dir():
        parser.error(f"-o: {args.output} is a file, not a folder")
    plan = [(n, args.rounds) for n in args.counts or COUNTS] + ([(LARGE, args.large_rounds)] if args.large else [])
    os.environ.update(SINGLE_THREAD)  # both codes on one core each; the probes inherit it
    command = "python workflows/peer_fastdla.py " + " ".join(sys.argv[1:] if argv is None else argv)
    with tempfile.TemporaryDirectory() as scratch:
        try:
            binary = build(args.fastdla, Path(scratch))
        except subprocess.CalledProcessError as err:
            print(f"peer_fastdla.py: --fastdla: g++ failed: {err.stderr.strip().splitlines()[-1:]}", file=sys.stderr)
            return 2
        load = os.getloadavg()[0]
        rows = measure(binary, plan)
    table = summary(rows, version(args.fastdla), command, (load, os.getloadavg()[0]))
    args.output.mkdir(parents=True, exist_ok=True)
    with open(args.output / "peer_fastdla.csv", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    (args.output / "peer_fastdla.md").write_text(table)
    print(table)
    print(f"{args.output}: peer_fastdla.csv, peer_fastdla.md")
    return 0


if __name__ == "__main__":
    sys.exit(main())
