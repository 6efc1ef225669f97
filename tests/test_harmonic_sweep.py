"""The harmonic measure in a sweep: ``[measure] harmonic_walkers`` validated, its variables stored by the
schema's rules, read back, and drawn by the report."""

from __future__ import annotations

import numpy as np
import pytest

import dlasweep as dla
from conftest import files_under
from dlasweep.data import schema
from dlasweep.growth.cluster import grow
from dlasweep.sweep import task as worker
from dlasweep.sweep.spec import SpecError, parse_spec

HARMONIC_SPEC = """\
name = "harmonic-tiny"

[grid]
n_particles = [200, 600]
seeds = 3

[model]
model = "offlattice"
dim = 2

[run]
root_seed = 7

[measure]
harmonic_walkers = 3000
"""


@pytest.fixture(scope="module")
def harmonic_sweep(tmp_path_factory, dask_client):
    out = tmp_path_factory.mktemp("harmonic") / "harmonic.nc"
    dla.run_sweep(parse_spec(HARMONIC_SPEC), client=dask_client, out=out)
    ds = dla.open_sweep(out)
    yield ds
    ds.close()


def test_the_measurement_round_trips_through_the_file_with_the_schemas_attributes(harmonic_sweep):
    ds = harmonic_sweep
    assert ds["harmonic_D"].dims == ("size", "seed", "q")
    assert ds["harmonic_depth"].dims == ("size", "seed")
    assert ds["harmonic_entropy"].dims == ds["harmonic_entropy_half"].dims == ("size", "n_particles", "seed", "q")
    np.testing.assert_array_equal(ds["q"].values, schema.HARMONIC_Q)
    assert ds["harmonic_D_ok"].dtype == bool  # int8 flags in the file, bool when read
    for name in (*schema.HARMONIC, "q"):
        assert ds[name].attrs["long_name"] == schema.SCHEMA[name].long_name
        assert ds[name].attrs["units"] == "1"
    # each seed's values are those of its cluster measured directly, with the seed its task derives
    spec = parse_spec(HARMONIC_SPEC)
    for task in spec.tasks():
        cluster = grow(spec.counts[-1], worker._stream(spec.root_seed, task), **task.params)
        direct = worker.harmonic(cluster, spec.harmonic_walkers, worker.harmonic_seed(spec.root_seed, task),
                                 spec.counts)
        where = {"size": 0, "seed": task.seed}
        np.testing.assert_array_equal(ds["harmonic_D"][where].values, direct["harmonic_D"])
        np.testing.assert_array_equal(ds["harmonic_D_ok"][where].values, direct["harmonic_D_ok"].astype(bool))
        assert ds["harmonic_depth"][where].item() == direct["harmonic_depth"]
        for name in ("harmonic_entropy", "harmonic_entropy_half"):  # at every count, n_particles before seed
            np.testing.assert_array_equal(ds[name][where].transpose("n_particles", "q").values, direct[name])
    assert np.isfinite(ds["harmonic_D"].values).any()
    assert 0 < np.nanmin(ds["harmonic_depth"].values) <= np.nanmax(ds["harmonic_depth"].values) <= 1


def test_the_seeds_walkers_differ_and_do_not_depend_on_the_batch():
    spec = parse_spec(HARMONIC_SPEC)
    seeds = [worker.harmonic_seed(spec.root_seed, task) for task in spec.tasks()]
    assert len(set(seeds)) == len(seeds)
    assert seeds == [worker.harmonic_seed(spec.root_seed, task) for task in spec.tasks()]


def test_a_sweep_without_the_measurement_has_none_of_its_variables(reference):
    assert not set(schema.HARMONIC) & set(reference.data_vars)
    assert "q" not in reference.coords


def test_the_report_draws_the_spectrum_and_writes_its_section(harmonic_sweep, tmp_path):
    from dlasweep.reporting.folder import report

    written = report(harmonic_sweep, tmp_path / "report")
    assert tmp_path / "report" / "harmonic_spectrum.png" in written
    text = (tmp_path / "report" / "report.md").read_text()
    assert "## Harmonic measure" in text
    assert "Makarov (D(1) = 1)" in text and "Halsey (2 D(3) = D)" in text
    assert "by cluster size (N = 200 to 600, 3 seeds)" in text


def test_the_report_of_a_sweep_without_it_has_no_spectrum(reference, tmp_path):
    from dlasweep.reporting.folder import report

    written = report(reference, tmp_path / "report")
    assert not any(path.name == "harmonic_spectrum.png" for path in written)
    assert "## Harmonic measure" not in (tmp_path / "report" / "report.md").read_text()


def test_the_key_is_part_of_the_identity_when_on():
    on = parse_spec(HARMONIC_SPEC)
    off = parse_spec(HARMONIC_SPEC.replace("harmonic_walkers = 3000", "harmonic_walkers = 0"))
    absent = parse_spec(HARMONIC_SPEC.replace("[measure]\nharmonic_walkers = 3000\n", ""))
    assert on.identity()["measure.harmonic_walkers"] == 3000
    assert on.digest() != off.digest()
    assert off.digest() == absent.digest() and off.harmonic_walkers == 0
    assert parse_spec(HARMONIC_SPEC.replace("= 3000", "= 1e4")).harmonic_walkers == 10_000


@pytest.mark.parametrize("line", ["harmonic_walkers = -1", "harmonic_walkers = 2.5", 'harmonic_walkers = "many"',
                                  "harmonic_walkers = true", "harmonic_walkers = 1e12", "walkers = 100"])
def test_bad_values_are_refused_naming_the_key_and_nothing_is_written(line, run_cli, write_spec, tmp_path):
    text = HARMONIC_SPEC.replace("harmonic_walkers = 3000", line)
    with pytest.raises(SpecError) as caught:
        parse_spec(text)
    assert str(caught.value).startswith(f"measure.{line.split()[0]}:")
    path = write_spec(text)
    status, out, err = run_cli("sweep", path, "-o", tmp_path / "out.nc")
    assert status == 2
    assert len(err.strip().splitlines()) == 1 and f"measure.{line.split()[0]}" in err
    assert files_under(tmp_path) == {path.relative_to(tmp_path)}
