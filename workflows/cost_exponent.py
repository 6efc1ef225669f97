"""Cost exponent side by side: one long cluster on one core, short ones on the other, at once.

    .venv/bin/python workflows/cost_exponent.py --rounds 2 -o results/bench

``dlasweep bench --full`` times a model's clusters of 1e5 and 1e7 minutes
apart, and a host whose speed drifts between them moves the cost exponent
by more than its targets' margins. Here each round grows one cluster of the
long N (seed = round) on one core while the other core grows clusters of the
short N (seeds 100 on) one after another until the long one ends; rounds
swap the cores. Both sides time CPU seconds of ``grow`` after a warm-up
(compilation excluded). A round's exponent is

    1 + log(ns a particle, long / median ns a particle, short) / log(long N / short N)

and its steps' part the same with the mean steps a particle. It writes
``cost_exponent.csv`` (a row per round and model, as each ends) and ``cost_exponent.md``
(each round's exponent, their mean and ``dlasweep.bench.targets.TARGETS``'
target, and the host's memory before and after the rounds, ``dlasweep.bench.host``)
into the output folder. Needs two cores (Linux: it pins the sides).
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

from dlasweep.bench.host import latency_line, read_latency
from dlasweep.bench.targets import MODELS, SCALING, TARGETS

_SIDE = """
import json, os, sys, time
import dlasweep as dla
params, n, seed, stop = json.loads(sys.argv[1]), int(sys.argv[2]), int(sys.argv[3]), sys.argv[4]
dla.grow(2000, seed=0, **params)  # load the compiled kernels
runs = []
while True:
    t = time.process_time(); c = dla.grow(n, seed=seed, **params); dt = time.process_time() - t
    runs.append(dict(seconds=dt, steps=float(c.steps.astype(float).mean()), seed=seed))
    if stop == "-" or os.path.exists(stop):  # the long side grows one; the short one until told
        break
    seed += 1
print(json.dumps(runs))
"""
SHORT_SEED = 100


class _Parser(argparse.ArgumentParser):
    def error(self, message):
        self.exit(2, f"cost_exponent.py: {message}\n")  # one line, naming what was wrong


def cores() -> list[int]:
    """The cores this process may run on (all of them where the OS does not say)."""
    return sorted(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else list(range(os.cpu_count() or 1))


def _side(params: dict, n: int, seed: int, stop: str, core: int) -> subprocess.Popen:
    """Start one side pinned to ``core``: the long one (``stop`` "-") or the short loop."""
    preexec = (lambda: os.sched_setaffinity(0, {core})) if hasattr(os, "sched_setaffinity") else None
    env = {**os.environ, "NUMBA_NUM_THREADS": "1", "OMP_NUM_THREADS": "1"}
    return subprocess.Popen([sys.executable, "-c", _SIDE, json.dumps(params), str(n), str(seed), stop],
                            stdout=subprocess.PIPE, text=True, env=env, preexec_fn=preexec)


def one_round(params: dict, long_n: int, short_n: int, seed: int, long_core: int, short_core: int) -> dict:
    """Grow the long cluster beside the short loop; the round's figures (``exponent`` computes the rest)."""
    with tempfile.TemporaryDirectory() as scratch:
        stop = str(Path(scratch) / "stop")
        short = _side(params, short_n, SHORT_SEED, stop, short_core)
        long = _side(params, long_n, seed, "-", long_core)
        (big,) = json.loads(long.communicate()[0])
        Path(stop).touch()
        small = json.loads(short.communicate()[0])
    if long.returncode or short.returncode:
        raise RuntimeError(f"a side failed (exit {long.returncode}, {short.returncode})")
    return {"long_n": long_n, "short_n": short_n, "seed": seed, "long_core": long_core,
            "long_ns": big["seconds"] / long_n * 1e9, "long_steps": big["steps"], "short_runs": len(small),
            "short_ns": statistics.median(r["seconds"] for r in small) / short_n * 1e9,
            "short_steps": statistics.fmean(r["steps"] for r in small)}


def exponent(row: dict) -> tuple[float, float]:
    """A round's cost exponent and its steps' part."""
    span = math.log(row["long_n"] / row["short_n"])
    return (1 + math.log(row["long_ns"] / row["short_ns"]) / span,
            math.log(row["long_steps"] / row["short_steps"]) / span)


def _label(n: float) -> str:
    """``1e5`` for 100000, ``3e4`` for 30000."""
    return f"{n:.0e}".replace("+0", "").replace("+", "")


def summary(rows: list[dict], command: str, hosts: dict | None = None) -> str:
    """A markdown table: each model's rounds, their mean and its target; under it the host's
    memory (``dlasweep.bench.host.read_latency``) as measured at each of ``hosts``' moments."""
    lines = [f"`{command}`", "",
             "| model | N | rounds: cost exponent (steps' part) | mean | target |", "|---|---|---|---|---|"]
    for name in dict.fromkeys(row["model"] for row in rows):
        mine = [row for row in rows if row["model"] == name]
        each = [exponent(row) for row in mine]
        mean = statistics.fmean(e for e, _ in each)  # the exponent of the rounds' geometric mean ratio
        target = TARGETS[name]["exponent"]
        scaling = (mine[0]["short_n"], mine[0]["long_n"]) == SCALING  # the targets' N
        straddle = min(e for e, _ in each) <= target < max(e for e, _ in each)
        verdict = (f"{target} ({'met' if mean <= target else 'over'}{', rounds on both sides' if straddle else ''})"
                   if scaling else f"{target} is for {_label(SCALING[0])} to {_label(SCALING[1])}")
        lines.append(f"| {name} | {_label(mine[0]['short_n'])} to {_label(mine[0]['long_n'])} | "
                     + ", ".join(f"{e:.3f} ({s:.3f})" for e, s in each) + f" | {mean:.3f} | {verdict} |")
    if hosts:
        lines.append("")
        lines += [f"- {moment}: {latency_line(latency)}" for moment, latency in hosts.items()]
    return "\n".join(lines) + "\n"


def main(argv=None) -> None:
    parser = _Parser(description=__doc__.splitlines()[0])
    parser.add_argument("--models", nargs="+", default=list(MODELS), help="models of dlasweep.bench.targets.MODELS")
    parser.add_argument("--n", type=float, default=SCALING[1], help="the long cluster's N")
    parser.add_argument("--short", type=float, default=SCALING[0], help="the short clusters' N")
    parser.add_argument("--rounds", type=int, default=2, help="rounds, cores swapped each round")
    parser.add_argument("-o", "--out", type=Path, required=True, help="output folder")
    args = parser.parse_args(argv)
    unknown = [m for m in args.models if m not in MODELS]
    if unknown:
        parser.error(f"--models: unknown {unknown[0]!r} (known: {', '.join(MODELS)})")
    if args.rounds < 1:
        parser.error(f"--rounds: {args.rounds} is not a positive count")
    if not 1 <= args.short < args.n or args.n != int(args.n) or args.short != int(args.short):
        parser.error(f"--short {args.short:g} and --n {args.n:g}: whole counts with 1 <= short < n")
    pair = cores()[:2]
    if len(pair) < 2:
        parser.error("needs two cores: one for each side")
    hosts = {"before the rounds": read_latency()}  # both cores idle
    print(latency_line(hosts["before the rounds"]), flush=True)
    rows = []
    for name in args.models:
        for k in range(args.rounds):
            long_core, short_core = pair[k % 2], pair[1 - k % 2]
            row = {"model": name, **one_round(MODELS[name], int(args.n), int(args.short), k + 1, long_core, short_core)}
            rows.append(row)
            e, s = exponent(row)
            print(f"{name} round {k + 1}: long {row['long_ns']:.0f} ns a particle, short {row['short_ns']:.0f} "
                  f"(median of {row['short_runs']}): exponent {e:.3f}, steps' part {s:.3f}", flush=True)
            args.out.mkdir(parents=True, exist_ok=True)
            with open(args.out / "cost_exponent.csv", "w", newline="") as f:  # every round kept as it ends
                writer = csv.DictWriter(f, fieldnames=list(row))
                writer.writeheader()
                writer.writerows(rows)
    hosts["after them"] = read_latency()
    table = summary(rows, "workflows/cost_exponent.py " + " ".join(argv if argv is not None else sys.argv[1:]), hosts)
    (args.out / "cost_exponent.md").write_text(table)
    print(table, end="")


if __name__ == "__main__":
    main()
