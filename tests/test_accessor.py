"""A sweep and a cluster as a notebook user meets them: ``ds.dla``, inline pictures, lazy reading, selections."""

from __future__ import annotations

import struct
import subprocess
import sys
import textwrap

import numpy as np
import pytest

import dlasweep as dla
from dlasweep.data import netcdf as store
from dlasweep.data import ragged

SPEC = """\
name = "accessor"
[grid]
size = [0]
n_particles = [50, 300]
seeds = 4
[model]
model = "lattice"
dim = 2
stickiness = [1.0, 0.5]
[run]
root_seed = 7
workers = 1
"""
"""Eight clusters: each seed number twice, once per stickiness."""


@pytest.fixture(scope="module")
def swept(tmp_path_factory):
    folder = tmp_path_factory.mktemp("accessor")
    (folder / "spec.toml").write_text(SPEC)
    dla.run_sweep(dla.load_spec(folder / "spec.toml"), out=folder / "sweep.nc", progress=False)
    return folder / "sweep.nc"


@pytest.fixture
def ds(swept):
    with dla.open_sweep(swept) as ds:
        yield ds


def png_size(png: bytes):
    """Width and height from a PNG's header, after checking its signature."""
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and png[12:16] == b"IHDR"
    return struct.unpack(">II", png[16:24])


@pytest.mark.parametrize("model, dim, n", [("lattice", 2, 2000), ("offlattice", 2, 500), ("lattice", 3, 500),
                                           ("offlattice", 3, 300)])
def test_a_cluster_shows_as_a_modest_png(model, dim, n):
    png = dla.grow(n, seed=2, model=model, dim=dim)._repr_png_()
    assert png_size(png) == (450, 450)
    assert 2_000 < len(png) < 400_000


def test_growing_loads_neither_xarray_nor_matplotlib_and_xarray_gets_the_accessor_when_it_loads():
    code = textwrap.dedent("""
        import sys
        import dlasweep
        dlasweep.grow(50)
        assert "xarray" not in sys.modules and "matplotlib" not in sys.modules, sorted(sys.modules)
        import xarray
        print(hasattr(xarray.Dataset, "dla"))
    """)
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "True"


def test_a_cluster_comes_back_with_its_diffusion_times_status_and_parameters(ds):
    c = ds.dla.cluster(stickiness=0.5, seed=3)
    assert isinstance(c, dla.Cluster)
    np.testing.assert_array_equal(c.points, ragged.cluster_points(ds, stickiness=0.5, seed=3))
    assert c.n == len(c.steps) == 300
    # the sweep measured the walk steps of every walker to the largest count: the same walkers
    assert c.steps.sum() == int(ds["walk_steps"].sel(stickiness=0.5, size=0, seed=3).isel(n_particles=-1))
    assert c.status == "ok"
    assert c.params == dla.grow(1, stickiness=0.5).params
    assert png_size(c._repr_png_()) == (450, 450)


def test_a_grown_cluster_comes_back_from_its_file(tmp_path):
    grown = dla.grow(400, seed=5, model="offlattice", dim=3, stickiness=0.5)
    store.save(store.cluster_dataset(grown, 5), tmp_path / "c.nc")
    with dla.open_sweep(tmp_path / "c.nc") as ds:
        c = ds.dla.cluster(0)
    np.testing.assert_array_equal(c.points, grown.points)
    np.testing.assert_array_equal(c.steps, grown.steps)
    assert (c.status, c.params) == (grown.status, grown.params)


def test_selection_on_the_grid_subsets_the_clusters(ds):
    sub = ds.sel(stickiness=0.5)
    np.testing.assert_array_equal(ragged.cluster_points(sub, seed=3), ragged.cluster_points(ds, stickiness=0.5, seed=3))
    np.testing.assert_array_equal(sub.dla.cluster(seed=3).points, ds.dla.cluster(stickiness=0.5, seed=3).points)
    assert [c.params["stickiness"] for c in sub.dla] == [0.5] * 4
    assert len(ds.isel(seed=[1, 3]).dla) == 4
    # k counts the clusters of the selection
    np.testing.assert_array_equal(sub.dla.cluster(0).points, ragged.cluster_points(ds, stickiness=0.5, seed=0))
    with pytest.raises(ValueError, match="matches 0 clusters"):
        sub.dla.cluster(stickiness=1.0, seed=0)


def test_clusters_iterate_in_order(ds):
    clusters = list(ds.dla.clusters())
    assert len(clusters) == len(ds.dla) == ds.sizes["cluster"] == 8
    for k, c in enumerate(clusters):
        np.testing.assert_array_equal(c.points, ragged.cluster_points(ds, k))
    assert sum(c.n for c in ds.dla) == ds.sizes["particle"]


@pytest.mark.filterwarnings("ignore:The specified chunks separate the stored chunks")  # small chunks on purpose
@pytest.mark.parametrize("opener", ["open_sweep", "xarray"])
def test_a_lazy_dataset_reads_one_cluster_only(swept, opener):
    import dask
    import xarray as xr
    from dask.callbacks import Callback

    chunks = {"particle": 100}
    ds = dla.open_sweep(swept, chunks=chunks) if opener == "open_sweep" else xr.open_dataset(swept, chunks=chunks)
    with ds:
        assert all(len(ds[v].chunks[0]) == 24 for v in ("x", "y", "diffusion_time", "parent"))
        ran = []
        with dask.config.set(scheduler="sync"), Callback(pretask=lambda key, *_: ran.append(key)):
            c = ds.sel(stickiness=0.5).dla.cluster(seed=2)
        assert c.n == 300 and c.steps.sum() > 0
        # the cluster's particles 1800 to 2100 lie in 3 of each variable's 24 chunks: 12 chunks read from the file
        # (xr.open_dataset leaves the small variables to dask too: their reads are not counted)
        small = [f"open_dataset-{name}-" for name, var in ds.variables.items() if "particle" not in var.dims]
        reads = [key for key in ran if isinstance(key, tuple) and key[0].startswith("open_dataset-")
                 and not key[0].startswith(tuple(small))]
        assert len(reads) == 12, ran
        assert all(not ds[v].variable._in_memory for v in ("x", "y", "diffusion_time", "parent"))
        with dla.open_sweep(swept) as eager:
            np.testing.assert_array_equal(c.points, eager.dla.cluster(stickiness=0.5, seed=2).points)


def test_summarise_and_report_of_a_selection(ds, tmp_path):
    summary = ds.sel(stickiness=1.0).dla.summarise(resamples=50)
    whole = ds.dla.summarise(resamples=50).sel(stickiness=1.0)
    np.testing.assert_allclose(summary["D"].values, whole["D"].values)
    # read from the stored clusters: those of stickiness 1.0, not the other clusters of the same seeds
    np.testing.assert_array_equal(summary["diffusion_median"].values, whole["diffusion_median"].values)
    # the plain functions read a selection as the accessor does
    plain = dla.summarise(ds.sel(stickiness=1.0), resamples=50)
    np.testing.assert_array_equal(plain["diffusion_median"].values, whole["diffusion_median"].values)
    written = ds.sel(stickiness=1.0).dla.report(tmp_path)
    assert tmp_path / "report.md" in written and (tmp_path / "gallery.png").exists()
