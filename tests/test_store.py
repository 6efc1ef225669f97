"""The netCDF layer: one round trip of the dataset layout (README, "The dataset"), CF compliance, atomic writes, bad files."""

import subprocess

import netCDF4
import numpy as np
import pytest
import xarray as xr

import dlasweep as dla
from dlasweep import store
from dlasweep.grow import Cluster
from dlasweep.params import PARAMETERS, resolve
from dlasweep.spec import parse_spec

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
    clusters = [(rng.normal(size=(n, 2)), rng.integers(0, 50, n)) for n in sizes]
    return store.to_dataset(spec, scales, history, science, sizes, failed), clusters


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
    for name in ("x", "y", "diffusion_time"):
        assert ds[name].dims == ("particle",)
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
        assert nc.Conventions == "CF-1.8" and nc.featureType == "point" and nc.source.startswith("dlasweep ")
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


def cf_errors(path, tables, cfchecks):
    """ERROR and FATAL messages of cfchecker on ``path``, as ``variable: message`` lines."""
    checker = cfchecks.CFChecker(cfStandardNamesXML=tables["standard_names"], cfAreaTypesXML=tables["area_types"],
                                 cfRegionNamesXML=tables["regions"], version=cfchecks.CFVersion(), silent=True)
    results = checker.checker(str(path))
    found = {"global": results["global"], **results["variables"]}
    return [f"{name}: {message}" for name, result in found.items()
            for category in ("FATAL", "ERROR") for message in result[category]]


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


def test_cf_checker_finds_no_errors(saved, cf_tables, cfchecks, tmp_path):
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
        assert cf_errors(path, cf_tables, cfchecks) == [], path.name


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


def test_cluster_points(tmp_path):
    ds = synthetic_dataset()
    counts = ds["cluster_particles"].values
    k = int(np.flatnonzero(counts)[2])
    start = counts[:k].sum()
    expected = np.stack([ds["x"].values, ds["y"].values], axis=1)[start:start + counts[k]]
    np.testing.assert_array_equal(store.cluster_points(ds, k), expected)
    where = {name.removeprefix("cluster_"): ds[name].values[k]
             for name in ds.coords if name.startswith("cluster_")}
    np.testing.assert_array_equal(store.cluster_points(ds, **where), expected)
    with pytest.raises(ValueError, match="matches 8 clusters"):
        store.cluster_points(ds, model="lattice")
    with pytest.raises(ValueError, match="colour: not a cluster parameter"):
        store.cluster_points(ds, colour="red")
    with pytest.raises(IndexError):
        store.cluster_points(ds, 99)


def test_one_cluster_file(tmp_path):
    points = np.array([[0, 0], [1, 0], [1, 1]])
    cluster = Cluster(points, np.array([0, 5, 7]), "boundary", resolve(size=16))
    path = tmp_path / "one.nc"
    store.save(store.cluster_dataset(cluster, seed=4), path)
    ds = store.open_sweep(path)
    np.testing.assert_array_equal(store.cluster_points(ds, 0), points)
    assert ds["x"].dtype == np.int32 and int(ds["size"]) == 16 and bool(ds["jumps"])
    assert store.STATUS_FLAGS[int(ds["status"][0])] == "boundary"
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
    np.testing.assert_array_equal(whole["x"].values, np.concatenate([p[:, 0] for p, _ in clusters]))


def test_particle_writer_writes_whole_chunks_as_soon_as_full(tmp_path, monkeypatch):
    monkeypatch.setattr(store, "PARTICLE_CHUNK", 5)
    writer = store.ParticleWriter(tmp_path / "part.nc", {"x": np.dtype(np.int32), "diffusion_time": np.dtype(np.int64)})
    written = []
    for n in (3, 9, 0, 4):
        writer.add(np.arange(2 * n, dtype=np.int32).reshape(n, 2), np.full(n, n))
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
            "x": (np.int32, False), "y": (np.int32, False), "diffusion_time": (np.int64, True)}
