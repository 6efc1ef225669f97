"""A sweep: its spec, plan, tasks, parts and progress, precision on demand, the dask session and runner, SLURM."""
