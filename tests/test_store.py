"""The netCDF layer (dlasweep/data/netcdf.py): one round trip of the dataset layout (docs/dataset.md), CF
compliance, atomic writes, bad files."""

import os
import re
import subprocess
import sys
import threading

import cf_xarray  # noqa: F401  (registers ds.cf)
import netCDF4
import numpy as np
import pytest
import xarray as xr

import dlasweep as dla
from conftest import ROOT
from dlasweep.bench import benchmark as bench
from dlasweep.data import netcdf as store
from dlasweep.data import ragged, schema
from dlasweep.growth.cluster import Cluster
from dlasweep.params import PARAMETERS, resolve
from dlasweep.sweep.spec import parse_spec

SPEC = """\
name = "layout"
[grid]
size = [0, 16]
n_particles = [5, 9]
seeds = [3, 7]
[model]
model = ["lattice", "offlattice"]
jumps = [true, false]
[run]
root_seed = 99
"""


def synthetic_parts(spec_text=SPEC, failed=()):
    """Random results in the sweep's layout, without growing anything: the dataset and its clusters apart."""
    rng = np.random.default_rng(0)
    spec = parse_spec(spec_text)
    scales = 2.0 ** np.arange(4)
    history = np.array([5, 7, 9])
    grid = (*spec.shape[:-1], len(spec.counts), spec.shape[-1])
    science = {
        "box_count": rng.integers(1, 9, (*grid, len(scales))),
        "n_grown": rng.integers(1, 9, grid),
        "status": rng.integers(0, 5, grid).astype(np.int8),
        "walk_steps": rng.integers(0, 1000, grid),
        **{k: rng.random(grid) for k in ("radius_gyration", "max_radius", "anisotropy", "wall_time")},
        "radius_gyration_history": rng.random((*spec.shape, len(history))),
    }
    stored = [t for t in spec.tasks() if spec.stores(t)]
    sizes = rng.integers(0, 9, len(stored))
    clusters = [(rng.normal(size=(n, 2)), rng.integers(0, 50, n), (rng.random(n) * np.arange(n)).astype(np.int32) - 1)
                for n in sizes]
    return store.to_dataset(spec, stored, scales, history, science, sizes, failed), clusters


def synthetic_dataset(spec_text=SPEC, failed=()):
    """Random results in the sweep's layout, clusters in memory."""
    return store.with_clusters(*synthetic_parts(spec_text, failed))


@pytest.fixture
def saved(tmp_path):
    ds = synthetic_dataset(failed=[("task-0-0-0-1", "RuntimeError: boom")])
    path = tmp_path / "layout.nc"
    store.save(ds, path)
    return ds, path


def test_round_trip(saved):
    ds, path = saved
    back = store.open_sweep(path)
    xr.testing.assert_identical(back.drop_attrs(deep=False), ds.drop_attrs(deep=False))
    assert back.attrs == ds.attrs
    # Strings and booleans come back as such, and select.
    assert back["model"].dtype.kind in "OU" and back["jumps"].dtype == bool
    assert back["cluster_jumps"].dtype == bool
    assert list(back["cluster_model"].values[:9:8]) == ["lattice", "offlattice"]
    assert (back["cluster_model"] == "lattice").sum() == 8 and back["launch"].item() == "circle"
    assert back.sel(model="offlattice", jumps=False)["box_count"].dims == (
        "size", "n_particles", "seed", "scale")
    back.close()


def test_layout_follows_design(saved):
    ds, _ = saved
    assert ds["box_count"].dims == ("model", "jumps", "size", "n_particles", "seed", "scale")
    for name in ("n_grown", "status", "radius_gyration", "max_radius", "anisotropy", "wall_time", "walk_steps"):
        assert ds[name].dims == ("model", "jumps", "size", "n_particles", "seed")
    for name in ("x", "y", "diffusion_time", "parent"):
        assert ds[name].dims == ("particle",)
    assert ds["parent"].dtype == np.int32 and ds["parent"].attrs["units"] == "1"
    assert "-1 = none" in ds["parent"].attrs["long_name"] and ds["parent"].attrs["valid_min"] == -1
    assert ds["cluster_particles"].dims == ("cluster",)
    assert int(ds["cluster_particles"].sum()) == ds.sizes["particle"]
    for name in ("cluster_model", "cluster_jumps", "cluster_size", "cluster_seed"):
        assert ds[name].dims == ("cluster",) and name in ds.coords
    assert list(ds["cluster_seed"].values[:4]) == [3, 7, 3, 7]
    assert ds["status"].attrs["flag_meanings"] == "ok boundary step_limit exhausted error"
    assert {"Conventions", "title", "source", "history", "spec", "root_seed"} <= set(ds.attrs)
    assert ds.attrs["root_seed"] == 99 and ds.attrs["spec"] == SPEC
    assert "task-0-0-0-1: RuntimeError: boom" in ds.attrs["failed_tasks"]


def test_readable_without_xarray(saved):
    _, path = saved
    with netCDF4.Dataset(path) as nc:
        assert nc.Conventions == "CF-1.8" and nc.featureType == "trajectory" and nc.source.startswith("dlasweep ")
        assert nc["cluster_particles"].sample_dimension == "particle"
        assert nc["cluster_particles"].dtype == np.int32
        assert nc["x"].filters()["zlib"]
        for name, var in nc.variables.items():
            assert var.long_name and "model parameter" not in var.long_name, name
            # Strings have no units; everything else does.
            assert hasattr(var, "units") == (var.dtype != "S1"), name
        assert nc["stickiness"].long_name == PARAMETERS["stickiness"].meaning
        assert nc["cluster_model"].long_name == f"the cluster's model: {PARAMETERS['model'].meaning}"
        # Strings are char arrays with a length dimension; netCDF4 joins them back.
        for name in ("model", "cluster_model", "seed_shape", "launch"):
            assert nc[name].dtype == "S1" and nc[name].dimensions[-1].startswith("string"), name
        assert list(nc["model"][:]) == ["lattice", "offlattice"]
        assert list(nc["jumps"][:]) == [1, 0]


def cf_messages(path, tables, cfchecks) -> dict:
    """cfchecker's messages on ``path`` by category (FATAL, ERROR, WARN, INFO), as ``variable: message`` lines."""
    checker = cfchecks.CFChecker(cfStandardNamesXML=tables["standard_names"], cfAreaTypesXML=tables["area_types"],
                                 cfRegionNamesXML=tables["regions"], version=cfchecks.CFVersion(), silent=True)
    results = checker.checker(str(path))
    found = {"global": results["global"], **results["variables"]}
    return {category: [f"{name}: {message}" for name, result in found.items() for message in result[category]]
            for category in ("FATAL", "ERROR", "WARN", "INFO")}


CHECKER_NOTE = "cluster_particles: attribute sample_dimension is being used in a non-standard way"
"""cfchecker's note on every count variable of a CF-1.7+ file (``test_the_checker_notes_every_count_variable``)."""


def unexplained(path, messages) -> list:
    """cfchecker's messages less those dlasweep.data.netcdf explains (CF in its docstring): the checker's note on
    the count variable, its notes on booleans' flags (coordinates, where CF-1.8 names none) and its warning
    on swept strings (coordinate variables of char, for xarray to select by)."""
    with netCDF4.Dataset(path) as nc:
        booleans = {name for name, var in nc.variables.items() if getattr(var, "flag_meanings", "") == "false true"}
        strings = {name for name, var in nc.variables.items() if var.dimensions[:1] == (name,) and var.dtype == "S1"}
    flags = re.compile(r"(\w+): attribute flag_(?:values|meanings) is being used in a non-standard way")
    declared = re.compile(r"(\w+): \(5\): Possible incorrect declaration of a coordinate variable.")
    return [line for category, lines in messages.items() for line in lines
            if not (category == "INFO" and (line == CHECKER_NOTE or _named(flags, line) in booleans)
                    or category == "WARN" and _named(declared, line) in strings)]


def _named(pattern, line):
    """The variable a message of ``pattern`` names (None: another message)."""
    match = pattern.fullmatch(line)
    return match and match[1]


@pytest.fixture
def cf_tables(tmp_path):
    """Empty CF name tables: the checker downloads the real ones by default, and the files use none of them."""
    tables = {"standard_names": "<standard_name_table><version_number>0</version_number>"
                                "<last_modified>none</last_modified></standard_name_table>",
              "area_types": "<area_type_table><version_number>0</version_number><date>none</date></area_type_table>",
              "regions": "<standardized_region_list><version_number>0</version_number><date>none</date>"
                         "</standardized_region_list>"}
    for name, text in tables.items():
        (tmp_path / f"{name}.xml").write_text(f'<?xml version="1.0"?>{text}')
    return {name: str(tmp_path / f"{name}.xml") for name in tables}


def test_cf_checker_finds_nothing_but_its_notes(saved, cf_tables, cfchecks, tmp_path):
    ds, sweep = saved
    target = tmp_path / "target.nc"
    half_width = ds["box_count"].isel(n_particles=-1, seed=0, scale=0, drop=True).astype(float) / 100
    store.save(store.record_stop(ds.copy(), half_width, 0.01, 64, "max_seeds reached"), target)
    files = [sweep, target]
    for name, params in {"lattice": {}, "offlattice-3d": {"model": "offlattice", "dim": 3, "size": 40}}.items():
        files.append(tmp_path / f"{name}.nc")
        store.save(store.cluster_dataset(dla.grow(30, 1, **params), seed=1), files[-1])
    for value in ('"none"', "1"):
        files.append(tmp_path / f"store-{value.strip(chr(34))}.nc")
        ds, clusters = synthetic_parts(SPEC.replace("root_seed = 99", f"root_seed = 99\nstore_clusters = {value}"))
        store.save(ds, files[-1], clusters)
    for path in files:
        messages = cf_messages(path, cf_tables, cfchecks)
        assert unexplained(path, messages) == [], path.name
        assert CHECKER_NOTE in messages["INFO"], path.name


def test_the_checker_notes_every_count_variable(cf_tables, cfchecks, tmp_path):
    """CF-1.8's own contiguous ragged array of trajectories (its example H.4.3, cut down) gets the same note:
    the checker's table of attributes names no kind of variable for sample_dimension from CF-1.7 on."""
    path = tmp_path / "cf_example.nc"
    with netCDF4.Dataset(path, "w") as nc:
        nc.Conventions, nc.featureType = "CF-1.8", "trajectory"
        nc.createDimension("obs", 5)
        nc.createDimension("trajectory", 2)
        trajectory = nc.createVariable("trajectory", "i4", ("trajectory",))
        trajectory.setncatts({"cf_role": "trajectory_id", "long_name": "trajectory number"})
        trajectory[:] = [0, 1]
        row_size = nc.createVariable("rowSize", "i4", ("trajectory",))
        row_size.setncatts({"long_name": "number of obs for this trajectory", "sample_dimension": "obs"})
        row_size[:] = [2, 3]
        for name, units in {"time": "days since 1970-01-01 00:00:00", "lon": "degrees_east", "lat": "degrees_north",
                            "z": "m"}.items():
            nc.createVariable(name, "f8", ("obs",)).setncatts({"long_name": name, "units": units})
        humidity = nc.createVariable("humidity", "f4", ("obs",))
        humidity.setncatts({"long_name": "specific humidity", "units": "1", "coordinates": "time lat lon z"})
    assert "rowSize: attribute sample_dimension is being used in a non-standard way" in cf_messages(
        path, cf_tables, cfchecks)["INFO"]


def test_clusters_are_a_cf_ragged_array_of_trajectories(saved, tmp_path):
    _, path = saved
    with netCDF4.Dataset(path) as nc:
        assert nc.featureType == "trajectory"
        roles = {name: var.cf_role for name, var in nc.variables.items() if "cf_role" in var.ncattrs()}
        assert roles == {"cluster": "trajectory_id"} and nc["cluster"].dimensions == ("cluster",)
        np.testing.assert_array_equal(nc["cluster"][:], np.arange(nc.dimensions["cluster"].size))
        assert nc["diffusion_time"].coordinates == nc["parent"].coordinates == "x y"
        assert (nc["x"].axis, nc["y"].axis) == ("X", "Y")
        # No attribute but CF's: xarray's own marker of booleans ("dtype") is gone.
        assert [name for name, var in nc.variables.items() if "dtype" in var.ncattrs()] == []
        assert nc["jumps"].dtype == np.int8 and nc["jumps"].flag_meanings == "false true"


@pytest.mark.parametrize("dim", [2, 3])
def test_cf_xarray_finds_the_axes_and_the_clusters(tmp_path, dim):
    path = tmp_path / "one.nc"
    store.save(store.cluster_dataset(dla.grow(30, 1, dim=dim), seed=1), path)
    with xr.open_dataset(path) as ds:
        assert ds.cf.axes == {a.upper(): [a] for a in schema.AXES[:dim]}
        assert ds.cf["X"].name == "x" and ds.cf["Y"].name == "y"
        assert ds.cf.cf_roles == {"trajectory_id": ["cluster"]}


def test_history_names_the_command_line_and_the_version(tmp_path, saved):
    stamp = r"\d{4}-\d\d-\d\dT\d\d:\d\d:\d\dZ"
    path = tmp_path / "one.nc"
    done = subprocess.run([sys.executable, "-m", "dlasweep", "grow", "-n", "40", "--seed", "3", "-o", str(path)],
                          capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    with netCDF4.Dataset(path) as nc:
        assert re.fullmatch(rf"{stamp}: dlasweep grow -n 40 --seed 3 -o {re.escape(str(path))} "
                            rf"\(dlasweep {re.escape(dla.__version__)}\)", nc.history), nc.history
    # From Python, the function that made it.
    assert re.fullmatch(rf"{stamp}: dlasweep.run_sweep \(dlasweep {re.escape(dla.__version__)}\)",
                        saved[0].attrs["history"])


def fake_bench(monkeypatch):
    """``bench.run_bench(quick=True)``'s dataset, its kernels not run: made-up measurements, the real layout."""
    def probe(params, n, seed=1):
        naive = not params.get("jumps", True)
        return {"seconds": n * (4e-6 if naive else 1e-6), "n_grown": n, "status": "ok", "steps": 30 * n,
                "peak_mb": 120.5, "added_mb": 3.25}

    monkeypatch.setattr(bench, "probe", probe)
    return bench.run_bench(quick=True, echo=lambda line: None)


def test_bench_files_are_cf_clean_and_info_describes_them(cf_tables, cfchecks, tmp_path, monkeypatch, run_cli):
    path = tmp_path / "bench.nc"
    store.save(fake_bench(monkeypatch), path)
    for checked in (path, ROOT / "results" / "bench" / "bench.nc"):
        assert unexplained(checked, cf_messages(checked, cf_tables, cfchecks)) == [], checked
        status, out, err = run_cli("info", checked)
        assert status == 0 and err == "", err
        assert out.splitlines()[0] == f"{checked}: dlasweep kernel benchmark"
    lines = run_cli("info", path)[1].splitlines()
    assert lines[2] == ("runs: 16 (exact 5, noise_reduction=4 2, neighbour_alpha=0.2 1, drift=0.01 4, "
                        "contact_distance=0.5 2, neighbour_alpha=0.5 1, naive 1)")  # the growth laws beside each
    # model (bench.LAWS)
    assert lines[3].split() == ["model", "N", "(exact)", "largest", "seconds", "peak", "MiB", "time", "~", "N^"]
    # no cost exponent: it is fitted over N from 1e5 (bench_targets.cost_exponent), and a quick bench runs 2000
    assert lines[4].split() == ["lattice-2d", "500,", "2000", "2000", "0.002", "120"]
    assert lines[-2] == "naive walk / exact jumps, time: N=500 4.0x"
    assert lines[-1].startswith("host memory, ns a read waiting on the last: 0.25 MiB ")  # bench.run_bench's probe
    with netCDF4.Dataset(path) as nc:
        assert nc["peak_memory"].units == bench.MIB and nc["peak_memory"][:].tolist() == [120.5] * 16
    with pytest.raises(store.StoreError, match="not a dlasweep dataset .missing cluster_particles"):
        store.open_sweep(path)  # nor does report take it


def test_ncdump_reads_the_header(saved, ncdump):
    _, path = saved
    header = subprocess.run([ncdump, "-h", str(path)], capture_output=True, text=True, check=True).stdout
    assert 'cluster_particles:sample_dimension = "particle"' in header


def test_save_is_atomic(tmp_path, monkeypatch):
    path = tmp_path / "out.nc"

    def crash(*args, **kwargs):
        raise OSError("disk full")

    monkeypatch.setattr(xr.Dataset, "to_netcdf", crash)
    with pytest.raises(OSError):
        store.save(synthetic_dataset(), path)
    assert list(tmp_path.iterdir()) == []


def test_one_cluster_file(tmp_path):
    points = np.array([[0, 0], [1, 0], [1, 1]])
    cluster = Cluster(points, np.array([0, 5, 7]), "boundary", resolve(size=16), parents=np.array([-1, 0, 1]))
    path = tmp_path / "one.nc"
    store.save(store.cluster_dataset(cluster, seed=4), path)
    ds = store.open_sweep(path)
    np.testing.assert_array_equal(ragged.cluster_points(ds, 0), points)
    np.testing.assert_array_equal(dla.cluster_parents(ds, 0), [-1, 0, 1])
    np.testing.assert_array_equal(ragged.read_cluster(ds, 0).parents, [-1, 0, 1])
    older = ds.drop_vars("parent")  # a file written before parents were stored
    assert ragged.read_cluster(older, 0).parents is None
    with pytest.raises(store.StoreError, match="parent: this file holds no parents"):
        ragged.cluster_parents(older, 0)
    assert ds["x"].dtype == np.int32 and int(ds["size"]) == 16 and bool(ds["jumps"])
    assert schema.STATUS_FLAGS[int(ds["status"][0])] == "boundary"
    ds.close()


def test_bad_files_are_refused_clearly(tmp_path, saved):
    _, good = saved
    text = tmp_path / "notes.nc"
    text.write_text("not netCDF")
    truncated = tmp_path / "truncated.nc"
    truncated.write_bytes(good.read_bytes()[: good.stat().st_size // 2])
    foreign = tmp_path / "foreign.nc"
    xr.Dataset({"t": ("time", [1.0, 2.0])}).to_netcdf(foreign)
    cases = {tmp_path / "absent.nc": "no such file", text: "not a readable netCDF file",
             truncated: "not a readable netCDF file|truncated", foreign: "not a dlasweep dataset"}
    for path, reason in cases.items():
        with pytest.raises(store.StoreError, match=reason) as caught:
            store.open_sweep(path)
        assert "\n" not in str(caught.value)


def test_streamed_clusters_fill_whole_compressed_chunks(tmp_path, monkeypatch):
    monkeypatch.setattr(store, "PARTICLE_CHUNK", 5)
    ds, clusters = synthetic_parts()
    whole = store.with_clusters(ds, clusters)
    path = tmp_path / "streamed.nc"
    store.save(ds, path, iter(clusters))
    back = store.open_sweep(path)
    xr.testing.assert_identical(back.drop_attrs(deep=False), whole.drop_attrs(deep=False))
    back.close()
    with netCDF4.Dataset(path) as nc:
        for name in ("x", "y", "diffusion_time"):
            assert nc[name].chunking() == [5] and nc[name].filters()["complevel"] == store.PARTICLE_ZLIB
            assert nc[name].filters()["shuffle"] == store.shuffled(nc[name].dtype)  # float64: both models swept
            assert "_FillValue" not in nc[name].ncattrs()
    np.testing.assert_array_equal(whole["x"].values, np.concatenate([p[:, 0] for p, _, _ in clusters]))
    np.testing.assert_array_equal(whole["parent"].values, np.concatenate([parents for _, _, parents in clusters]))


def test_a_file_is_streamed_from_a_thread_as_from_the_main_thread(tmp_path, monkeypatch):
    # Signals are held over netCDF writes (``store._signals_held``) in the main thread only: a
    # handler can be set nowhere else, and no handler runs elsewhere.
    monkeypatch.setattr(store, "PARTICLE_CHUNK", 5)
    ds, clusters = synthetic_parts()
    paths = {where: tmp_path / f"{where}.nc" for where in ("main", "thread")}
    store.save(ds, paths["main"], iter(clusters))
    errors = []
    worker = threading.Thread(target=lambda: _caught(errors, store.save, ds, paths["thread"], iter(clusters)))
    worker.start()
    worker.join()
    assert not errors, errors
    with store.open_sweep(paths["main"]) as main, store.open_sweep(paths["thread"]) as thread:
        xr.testing.assert_identical(thread.drop_attrs(deep=False), main.drop_attrs(deep=False))


def _caught(errors, call, *args):
    try:
        call(*args)
    except Exception as err:  # noqa: BLE001 (reported by the test, in its own thread)
        errors.append(err)


def test_particle_writer_writes_whole_chunks_as_soon_as_full(tmp_path, monkeypatch):
    monkeypatch.setattr(store, "PARTICLE_CHUNK", 5)
    writer = store.ParticleWriter(tmp_path / "part.nc", {"x": np.dtype(np.int32), "diffusion_time": np.dtype(np.int64),
                                                         "parent": np.dtype(np.int32)})
    written = []
    for n in (3, 9, 0, 4):
        writer.add(np.arange(2 * n, dtype=np.int32).reshape(n, 2), np.full(n, n), np.arange(n, dtype=np.int32) - 1)
        written.append(writer.written)
    assert written == [0, 10, 10, 15]  # the last value waits for finish
    writer.discard()
    assert list(tmp_path.iterdir()) == []


def test_a_cluster_count_that_disagrees_writes_nothing(tmp_path):
    ds, clusters = synthetic_parts()
    with pytest.raises(ValueError, match="cluster_particles says"):
        store.save(ds, tmp_path / "short.nc", [c for c in clusters if c is not max(clusters, key=lambda c: len(c[1]))])
    assert list(tmp_path.iterdir()) == []


def test_lattice_sites_alone_are_written_unshuffled(tmp_path):
    ds, clusters = synthetic_parts(SPEC.replace('model = ["lattice", "offlattice"]', 'model = "lattice"'))
    store.save(ds, tmp_path / "lattice.nc", iter(clusters))
    with netCDF4.Dataset(tmp_path / "lattice.nc") as nc:
        assert {name: (nc[name].dtype, nc[name].filters()["shuffle"]) for name in ("x", "y", "diffusion_time")} == {
            "x": (np.int32, False), "y": (np.int32, False), "diffusion_time": (np.uint32, True)}


def test_an_opened_dataset_closes_its_file(saved):
    _, path = saved

    def open_files():
        return {os.path.realpath(f"/proc/self/fd/{fd}") for fd in os.listdir("/proc/self/fd")}

    with store.open_sweep(path) as ds:
        assert ds["jumps"].dtype == bool and str(path) in open_files()
    assert str(path) not in open_files()


def _set_format(path, value):
    with netCDF4.Dataset(path, "a") as nc:
        if value is None:
            nc.delncattr("dlasweep_format")
        else:
            nc.setncattr("dlasweep_format", value)


def test_every_file_records_its_format_and_one_of_a_later_format_is_refused_in_one_line(saved, tmp_path, run_cli):
    from dlasweep._version import FORMAT

    _, path = saved
    with store.open_sweep(path) as ds:
        assert ds.attrs["dlasweep_format"] == FORMAT and store.file_format(ds) == FORMAT
    one = tmp_path / "one.nc"
    cluster = Cluster(np.array([[0, 0], [1, 0]]), np.array([0, 5]), "ok", resolve(), parents=np.array([-1, 0]))
    store.save(store.cluster_dataset(cluster, seed=0), one)
    with store.open_sweep(one) as ds:
        assert store.file_format(ds) == FORMAT
    _set_format(path, None)  # a file from before the attribute: format 1, which still opens
    with store.open_sweep(path) as ds:
        assert store.file_format(ds) == 1
    for value, shown in ((FORMAT + 1, f"file format {FORMAT + 1}"), ("two", "file format 'two'")):
        _set_format(path, value)
        with pytest.raises(store.StoreError, match=re.escape(f"{path}: {shown}, from dlasweep ")):
            store.open_sweep(path)
        status, out, err = run_cli("info", path)
        assert status == 2 and out == "" and len(err.strip().splitlines()) == 1
        assert f"reads formats 1 to {FORMAT}: upgrade dlasweep to read it" in err
