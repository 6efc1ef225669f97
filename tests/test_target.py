"""Precision on demand: ``[run] target_ci`` adds seeds batch after batch, never regrowing one."""

import math

import numpy as np
import pytest
import xarray as xr

import dlasweep as dla
from conftest import science
from dlasweep.stats.summary import summarise
from dlasweep.sweep import precision
from dlasweep.sweep.spec import DEFAULT_MAX_SEEDS, SpecError, parse_spec
from test_sweep import Interrupt, interrupt_after, record_writes

FIRST = 4
"""The first batch of seeds."""

TARGET = 0.075
"""Above the half-width this spec reaches with 8 seeds, below the one it has with 4."""


def spec_text(seeds=FIRST, run=f"target_ci = {TARGET}\nmax_seeds = 32"):
    """Two configurations of small 2D lattice clusters; ``run`` adds to ``[run]``."""
    return f"""\
name = "target"
[grid]
n_particles = [500, 2000]
seeds = {seeds}
[model]
model = "lattice"
stickiness = [1.0, 0.5]
[run]
root_seed = 7
{run}
"""


def half_width(ds):
    top = summarise(ds).isel(n_particles=-1)
    return ((top["D_ci_hi"] - top["D_ci_lo"]) / 2).values


@pytest.fixture(scope="module")
def reached(dask_client):
    """The target sweep, run once, with the keys of the tasks it computed in order."""
    with pytest.MonkeyPatch.context() as patch:
        written = record_writes(patch)
        ds = dla.run_sweep(parse_spec(spec_text()), client=dask_client)
    return ds, written


def test_the_target_is_reached_and_the_result_is_a_fixed_sweep(reached, dask_client):
    ds, _ = reached
    n = ds.sizes["seed"]
    assert ds.attrs["stop_reason"] == precision.TARGET_REACHED and FIRST < n < 32
    assert ds.attrs["target_ci"] == TARGET and ds.attrs["max_seeds"] == 32
    assert (ds["D_ci_half_width"] <= TARGET).all()
    fixed = dla.run_sweep(parse_spec(spec_text(seeds=n, run="")), client=dask_client)
    xr.testing.assert_identical(science(ds), science(fixed))
    np.testing.assert_array_equal(ds["D_ci_half_width"].values, half_width(fixed))
    # One batch earlier the target was not reached everywhere: the second batch was needed.
    fewer = dla.run_sweep(parse_spec(spec_text(seeds=FIRST, run="")), client=dask_client)
    assert (half_width(fewer) > TARGET).any()
    # A fixed sweep carries no stop record.
    assert "stop_reason" not in fixed.attrs and "D_ci_half_width" not in fixed


def test_later_batches_grow_only_new_replicates(reached):
    ds, written = reached
    final = parse_spec(spec_text()).with_seeds(ds.sizes["seed"])
    assert sorted(written) == sorted(t.key for t in final.tasks())
    first = len(written) * FIRST // ds.sizes["seed"]
    replicate = [int(key.rsplit("-", 1)[1]) for key in written]
    assert max(replicate[:first]) < FIRST <= min(replicate[first:])


def test_an_unreachable_target_stops_at_max_seeds(dask_client):
    ds = dla.run_sweep(parse_spec(spec_text(run="target_ci = 1e-4\nmax_seeds = 8")), client=dask_client)
    assert ds.sizes["seed"] == 8 and ds.attrs["stop_reason"] == precision.CAP_REACHED
    assert not (ds["D_ci_half_width"] <= 1e-4).all()


def test_a_killed_target_sweep_resumes_to_the_same_result(tmp_path, dask_client, reached, monkeypatch):
    ds, written = reached
    out = tmp_path / "target.nc"
    spec = parse_spec(spec_text())
    before = interrupt_after(monkeypatch, len(written) - 2)  # in the last batch
    with pytest.raises(Interrupt):
        dla.run_sweep(spec, client=dask_client, out=out)
    monkeypatch.undo()
    resumed_writes = record_writes(monkeypatch)
    # The target and the cap may change on resume: each replicate is the same either way.
    same = parse_spec(spec_text(run=f"target_ci = {TARGET}\nmax_seeds = 64"))
    resumed = dla.run_sweep(same, client=dask_client, out=out, resume=True)
    # Which parts finish before the kill depends on the threads' timing: what is certain is that
    # the kill came in the second batch of seeds, and that the resumed run grew exactly the rest.
    assert len(before) > len(written) * FIRST // ds.sizes["seed"]
    assert resumed_writes and sorted(before + resumed_writes) == sorted(written)
    xr.testing.assert_identical(science(resumed), science(ds))
    xr.testing.assert_identical(resumed["D_ci_half_width"], ds["D_ci_half_width"])
    assert resumed.attrs["stop_reason"] == precision.TARGET_REACHED and resumed.attrs["max_seeds"] == 64
    assert {"units", "long_name"} <= set(resumed["D_ci_half_width"].attrs)
    assert not out.with_name("target.nc.parts").exists()
    resumed.close()


def test_failed_tasks_stop_the_batches_until_resume_retries_them(tmp_path, dask_client, reached, monkeypatch,
                                                                 replicate_1_fails):
    out = tmp_path / "target.nc"
    with pytest.warns(RuntimeWarning, match="2 of 8 tasks failed"):
        failed = dla.run_sweep(parse_spec(spec_text()), client=dask_client, out=out)
    assert failed.sizes["seed"] == FIRST and failed.attrs["stop_reason"] == precision.TASKS_FAILED
    failed.close()
    monkeypatch.undo()
    healed = dla.run_sweep(parse_spec(spec_text()), client=dask_client, out=out, resume=True)
    xr.testing.assert_identical(science(healed), science(reached[0]))
    assert healed.attrs["stop_reason"] == precision.TARGET_REACHED
    healed.close()


def test_the_next_batch_follows_the_worst_configuration():
    spec = parse_spec(spec_text(run="target_ci = 0.01\nmax_seeds = 100"))
    more = precision.more_seeds
    assert more(spec, 8, np.array([0.005, 0.01]), []) == (None, precision.TARGET_REACHED)
    assert more(spec, 8, np.array([0.005, 0.02]), []) == (math.ceil(1.1 * 8 * 4), None)
    assert more(spec, 8, np.array([0.005, 0.0101]), []) == (8 + FIRST, None)  # at least one first batch
    assert more(spec, 8, np.array([0.005, np.nan]), []) == (16, None)  # no interval yet: twice the seeds
    assert more(spec, 8, np.array([0.005, 1.0]), []) == (100, None)
    assert more(spec, 100, np.array([0.005, 1.0]), []) == (None, precision.CAP_REACHED)
    assert more(spec, 8, np.array([0.005, 0.02]), [("task-0-0-1", "boom")]) == (None, precision.TASKS_FAILED)


def test_precision_asks_for_batches_until_told_the_target_is_met(monkeypatch):
    # ask/tell by hand, no dask: the half-widths the summary would measure are given
    spec = parse_spec(spec_text(run="target_ci = 0.01\nmax_seeds = 100"))
    told = iter([np.array([0.005, 0.02]), np.array([0.005, 0.009])])
    monkeypatch.setattr(precision, "ci_half_width", lambda ds: xr.DataArray(next(told)))
    seeds = precision.Precision(spec)
    assert seeds.ask() is spec
    assert len(seeds.tell(None, []).seeds) == math.ceil(1.1 * FIRST * 4) == len(seeds.ask().seeds)
    assert seeds.tell(None, []) is None and seeds.ask() is None and seeds.reason == precision.TARGET_REACHED
    np.testing.assert_array_equal(seeds.half_width, [0.005, 0.009])
    fixed = precision.Precision(parse_spec(spec_text(run="")))  # no target: one batch, the spec
    assert fixed.tell(None, []) is None and fixed.reason is None and fixed.half_width is None


def test_target_keys_parse_and_leave_the_digest_alone():
    spec = parse_spec(spec_text(run="target_ci = 1"))
    assert spec.target_ci == 1.0 and spec.max_seeds == DEFAULT_MAX_SEEDS and spec.seeds == tuple(range(FIRST))
    fixed = parse_spec(spec_text(run=""))
    assert fixed.target_ci is None and fixed.max_seeds is None
    # Parts of a fixed sweep are parts of a target sweep with that first batch, and back.
    assert spec.digest() == fixed.digest()


@pytest.mark.parametrize("run, seeds, key", [
    ("target_ci = 0", FIRST, "run.target_ci"),
    ("target_ci = -0.01", FIRST, "run.target_ci"),
    ("target_ci = nan", FIRST, "run.target_ci"),
    ("target_ci = inf", FIRST, "run.target_ci"),
    ('target_ci = "0.01"', FIRST, "run.target_ci"),
    ("target_ci = true", FIRST, "run.target_ci"),
    ("target_ci = 0.01\nmax_seeds = 3", FIRST, "run.max_seeds"),
    ("target_ci = 0.01\nmax_seeds = 8.5", FIRST, "run.max_seeds"),
    ("target_ci = 0.01", 300, "run.max_seeds"),  # the default cap is below the first batch
    ("max_seeds = 8", FIRST, "run.max_seeds"),
    ("target_ci = 0.01", "[0, 1, 2]", "grid.seeds"),
])
def test_bad_target_keys_are_named(run, seeds, key):
    with pytest.raises(SpecError) as caught:
        parse_spec(spec_text(seeds=seeds, run=run))
    message = str(caught.value)
    assert message.startswith(key + ":") and "\n" not in message, message


def test_a_bad_target_exits_2_naming_the_key(run_cli, write_spec, tmp_path):
    status, out, err = run_cli("sweep", write_spec(spec_text(run="target_ci = 0")), "-o", tmp_path / "t.nc")
    assert status == 2 and err.startswith("dlasweep sweep: run.target_ci:") and out == ""
    assert not (tmp_path / "t.nc").exists() and not (tmp_path / "t.nc.parts").exists()
