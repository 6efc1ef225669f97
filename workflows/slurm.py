"""Run a sweep spec on a SLURM cluster: dask-jobqueue workers that come and go.

    pip install 'dlasweep[slurm]'
    python workflows/slurm.py workflows/quick.toml -o results/quick.nc \\
        --queue normal --account myproject --max-jobs 20 \\
        --prologue 'source /path/to/dlasweep/.venv/bin/activate'

``--dry-run`` prints the SLURM job script and stops.

The scheduler runs in this process (run it on a login node or in a small
job of its own); SLURM jobs of ``--cores`` single-threaded workers are
started and stopped as the queue of tasks needs them (adaptive scaling).
Workers retire before their job's wall time runs out (``--lifetime``), so a
task is never cut off by SLURM: dask moves it to another worker. Each result
is saved as it arrives, so a killed run continues with ``--resume``.
The sweep itself is ``dlasweep sweep --scheduler ADDRESS``, with its checks
and exit status.
"""

from __future__ import annotations

import argparse
import sys


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("spec", help="sweep spec (TOML)")
    parser.add_argument("-o", "--output", help="netCDF file to write")
    parser.add_argument("--resume", action="store_true", help="continue an interrupted run")
    parser.add_argument("--queue", help="SLURM partition")
    parser.add_argument("--account", help="SLURM account")
    parser.add_argument("--cores", type=int, default=8, help="workers (cores) per job")
    parser.add_argument("--memory", default="16GB", help="memory per job")
    parser.add_argument("--walltime", default="02:00:00", help="wall time per job")
    parser.add_argument("--lifetime", default="110m",
                        help="retire a worker after this long (keep it below --walltime)")
    parser.add_argument("--max-jobs", type=int, default=10, help="most jobs at once")
    parser.add_argument("--prologue", action="append", default=[],
                        help="shell line to run before each worker starts (e.g. activating the venv)")
    parser.add_argument("--dry-run", action="store_true", help="print the job script and stop")
    args = parser.parse_args(argv)

    try:
        from dask_jobqueue import SLURMCluster
    except ImportError:
        print("slurm.py: needs dask-jobqueue: pip install 'dlasweep[slurm]'", file=sys.stderr)
        return 2
    from dlasweep.cli import main as dlasweep_main

    cluster = SLURMCluster(
        cores=args.cores,
        processes=args.cores,  # one single-threaded process per core: the kernels hold one core each
        memory=args.memory,
        walltime=args.walltime,
        queue=args.queue,
        account=args.account,
        job_script_prologue=args.prologue,
        # Stagger retirements so that not every worker leaves at once.
        worker_extra_args=["--lifetime", args.lifetime, "--lifetime-stagger", "4m"],
    )
    with cluster:
        if args.dry_run:
            print(cluster.job_script())
            return 0
        cluster.adapt(minimum_jobs=0, maximum_jobs=args.max_jobs)
        sweep = ["sweep", args.spec, "--scheduler", cluster.scheduler_address]
        if args.output:
            sweep += ["-o", args.output]
        if args.resume:
            sweep.append("--resume")
        return dlasweep_main(sweep)


if __name__ == "__main__":
    raise SystemExit(main())
