"""Join the finished seeds of a continuation run to an earlier sweep file of the same spec, along ``seed``.

    python workflows/join_seeds.py CONTINUE.toml CONTINUE.nc.parts EARLIER.nc OUT.nc

A sweep stopped before its seeds were all grown (``results/dimension_1e7``) goes on as a spec equal to
it but for ``seeds = [k, k + 1, ...]``, the seeds it had not grown: a list of seeds names replicates by
their number, so replicate j is the same cluster in either spec (the same root seed). This script takes
the longest run of finished seeds of that continuation from its parts folder (even while it still runs),
assembles them as the sweep's runner does, joins them to EARLIER.nc (its seeds 0..k-1), recomputes the
headline D's CI half-width, and saves the whole, which ``dlasweep report`` reads as any sweep file.
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

import xarray as xr

from dlasweep.data import netcdf
from dlasweep.sweep.parts import Parts
from dlasweep.sweep.precision import ci_half_width
from dlasweep.sweep.runner import _assemble
from dlasweep.sweep.spec import parse_spec


def main(spec_path, parts_path, earlier_path, out_path):
    text = Path(spec_path).read_text()
    seeds = [int(s) for s in re.search(r"seeds = \[([^\]]*)\]", text).group(1).split(",")]
    parts = Parts(Path(parts_path))
    done = [parts.finished(task.key) for task in parse_spec(text).tasks()]
    k = next((i for i, finished in enumerate(done) if not finished), len(done))
    if k == 0:
        sys.exit(f"{parts_path}: no finished seed to join")
    print(f"joining seeds {seeds[0]} to {seeds[k - 1]} ({k} finished in a row) to {earlier_path}")
    spec = parse_spec(re.sub(r"seeds = \[[^\]]*\]", "seeds = [" + ", ".join(map(str, seeds[:k])) + "]", text))
    new, failed = _assemble(spec, spec.tasks(), parts)
    if failed:
        sys.exit(f"{parts_path}: failed tasks {failed}")
    old = netcdf.open_sweep(earlier_path).load()
    science = [name for name in new.data_vars if "seed" in new[name].dims]
    scales = slice(0, min(old.sizes["scale"], new.sizes["scale"]))
    joined = xr.concat([old[science].isel(scale=scales), new[science].isel(scale=scales)], dim="seed")
    out = old.drop_vars(science).drop_dims("seed", errors="ignore").isel(scale=scales).merge(joined, join="outer")
    out.attrs = dict(old.attrs)
    out.attrs["stop_reason"] = f"interrupted at {out.sizes['seed']} seeds"
    out.attrs["history"] = (f"{old.attrs.get('history', '')}; seeds {seeds[0]}-{seeds[k - 1]} grown by a continuation "
                            f"(the same spec with seeds = [{seeds[0]}, ...]) and joined along seed")
    half = out["D_ci_half_width"]
    out["D_ci_half_width"] = half.copy(data=ci_half_width(out).transpose(*half.dims).values)
    netcdf.save(out, out_path)
    print(f"{out_path}: {out.sizes['seed']} seeds, headline D's CI half-width {out['D_ci_half_width'].values}")


if __name__ == "__main__":
    main(*sys.argv[1:])
