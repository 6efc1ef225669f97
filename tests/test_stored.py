"""``[run] store_clusters``: positions kept for the first K seeds only, every curve for all; the clusters streamed."""

from pathlib import Path

import numpy as np
import pytest
import xarray as xr

import dlasweep as dla
from conftest import TINY_SPEC
from dlasweep.data import netcdf as store
from dlasweep.data import ragged
from dlasweep.measures.shape import radius_of_gyration
from dlasweep.reporting.folder import report
from dlasweep.stats import branches as branching
from dlasweep.stats.fit import fit_mass_radius, growth_counts
from dlasweep.sweep.parts import Parts, ResumeError
from dlasweep.sweep.spec import parse_spec
from test_sweep import Interrupt, batches_of, interrupt_after

PER_PARTICLE = ("x", "y", "diffusion_time", "parent", "cluster_particles")
"""The variables of the stored clusters; everything else is measured for every cluster."""

NOT_CURVES = ("diffusion_density", "diffusion_median", "diffusion_bin", "cluster_index", "seconds_per_particle",
              "pareto", *branching.ATTRS, "order")
"""Summary variables from the stored clusters only (the branch statistics none without them), or from timings
(the cost on the Pareto front)."""


def spec_storing(value):
    return parse_spec(TINY_SPEC.replace("root_seed = 12345", f"root_seed = 12345\nstore_clusters = {value}"))


def curves(ds):
    """Everything but the per-particle variables and the timings, loaded."""
    return ds.drop_vars([*PER_PARTICLE, "wall_time"]).drop_dims("cluster").drop_attrs().load()


def clusters_of(ds):
    """(parameters, seed) -> (points, diffusion times) of every stored cluster."""
    names = [c for c in ds.coords if c.startswith("cluster_")]
    ends = np.cumsum(ds["cluster_particles"].values)
    return {tuple(ds[c].values[i].item() for c in names):
            (ragged.cluster_points(ds, i),
             ds["diffusion_time"].values[ends[i] - ds["cluster_particles"].values[i]:ends[i]])
            for i in range(ds.sizes["cluster"])}


@pytest.fixture(scope="module")
def every(tmp_path_factory, dask_client):
    """The tiny sweep with every cluster stored, and its summary."""
    ds = dla.run_sweep(parse_spec(TINY_SPEC), client=dask_client, out=tmp_path_factory.mktemp("all") / "all.nc")
    yield ds, dla.summarise(ds)
    ds.close()


@pytest.mark.parametrize("value, kept", [('"none"', 0), ("1", 1), ("2", 2), ("5", 3)])
def test_positions_of_the_first_k_seeds_only_and_every_curve(value, kept, every, dask_client, tmp_path):
    full, summary = every
    ds = dla.run_sweep(spec_storing(value), client=dask_client, out=tmp_path / "k.nc")
    xr.testing.assert_identical(curves(ds), curves(full))
    assert ds.sizes["cluster"] == 4 * kept and set(ds["cluster_seed"].values) == set(range(kept))
    mine, all_of_them = clusters_of(ds), clusters_of(full)
    assert len(mine) == 4 * kept
    for key, (points, times) in mine.items():
        np.testing.assert_array_equal(points, all_of_them[key][0])
        np.testing.assert_array_equal(times, all_of_them[key][1])
    # The headline, the per-cluster fits and the curves do not depend on what is stored.
    s = dla.summarise(ds)
    xr.testing.assert_identical(s.drop_vars(NOT_CURVES, errors="ignore"), summary.drop_vars(NOT_CURVES))
    assert ("bifurcation_ratio" in s) == (kept > 0)
    assert np.isfinite(s["diffusion_density"].values).any() == (kept > 0)
    # In memory, the same.
    in_memory = dla.run_sweep(spec_storing(value), client=dask_client)
    xr.testing.assert_identical(in_memory[list(PER_PARTICLE)].drop_attrs(deep=False),
                                ds[list(PER_PARTICLE)].drop_attrs(deep=False).load())
    ds.close()


def test_unstored_clusters_leave_no_positions_in_the_parts(dask_client, tmp_path, monkeypatch):
    out = tmp_path / "k.nc"
    def killed(*args):
        raise Interrupt

    monkeypatch.setattr(store.ParticleWriter, "finish", killed)  # every cluster finished, the file not written
    with pytest.raises(Interrupt):
        dla.run_sweep(spec_storing(1), client=dask_client, out=out)
    parts = Parts(Path(f"{out}.parts"))
    keys = list(parts.where)
    for key, result in zip(keys, parts.results(keys, ("points.shape", "diffusion_time.shape"))):
        stored = key.endswith("-0")  # replicate 0
        assert (result["points.shape"][0] > 0) == stored and (result["diffusion_time.shape"][0] > 0) == stored


def test_a_killed_run_resumes_to_the_uninterrupted_file(dask_client, tmp_path, monkeypatch):
    spec = spec_storing(2)
    whole = dla.run_sweep(spec, client=dask_client, out=tmp_path / "whole.nc")
    out = tmp_path / "killed.nc"
    batches_of(monkeypatch, 2)
    interrupt_after(monkeypatch, 5)
    with pytest.raises(Interrupt):
        dla.run_sweep(spec, client=dask_client, out=out)
    monkeypatch.undo()
    with pytest.raises(ResumeError, match=r"run.store_clusters: 2 -> 1"):
        dla.run_sweep(spec_storing(1), client=dask_client, out=out, resume=True)
    resumed = dla.run_sweep(spec, client=dask_client, out=out, resume=True)
    science = [name for name in whole.variables if name != "wall_time"]
    xr.testing.assert_identical(resumed[science].drop_attrs().load(), whole[science].drop_attrs().load())
    resumed.close()
    whole.close()


def test_the_growth_history_is_every_prefix_s_rg(every):
    full, summary = every
    growth = growth_counts(full["n_particles"].values)
    np.testing.assert_array_equal(full["history"].values, growth)
    spec = parse_spec(TINY_SPEC)
    for i, task in enumerate(spec.tasks()):
        rg = radius_of_gyration(ragged.cluster_points(full, i))
        row = full["radius_gyration_history"][dict(zip(["stickiness", "size", "seed"], task.index))].values
        grown = growth <= len(rg)
        np.testing.assert_array_equal(row[grown], rg[growth[grown] - 1])
        assert np.isnan(row[~grown]).all()
        # A cluster's own D at a count it reached is the fit on every prefix.
        for k, n in enumerate(spec.counts):
            if n <= len(rg):
                D = summary["D_cluster"][dict(zip(["stickiness", "size", "seed"], task.index))].values[k]
                np.testing.assert_equal(D, fit_mass_radius(rg[:n]).D)


def test_diffusion_statistics_equal_the_pooled_particles(every):
    # The slow, obvious reference: every stored particle in memory, numpy's histogram and median.
    full, summary = every
    edges = np.r_[0.5, np.unique(np.round(np.logspace(0, np.log10(max(int(full["diffusion_time"].max()), 10)),
                                                       40))) + 0.5]
    depth_edges = np.linspace(0.0, 1.0, 11)
    ends = np.cumsum(full["cluster_particles"].values)
    for config in np.ndindex(2, 2):
        times, depths = [], []
        for i in np.flatnonzero((full["cluster_stickiness"].values == full["stickiness"].values[config[0]])
                                & (full["cluster_size"].values == full["size"].values[config[1]])):
            points = ragged.cluster_points(full, i).astype(float)
            distance = np.sqrt(((points - points[0]) ** 2).sum(axis=1))
            depths.append(distance[1:] / max(distance.max(), 1.0))
            times.append(full["diffusion_time"].values[ends[i] - len(points):ends[i]][1:])
        times, depths = np.concatenate(times).astype(float), np.concatenate(depths)
        at = summary.isel(stickiness=config[0], size=config[1])
        np.testing.assert_array_equal(at["diffusion_density"].values, np.histogram(times, edges, density=True)[0])
        slot = np.clip(np.digitize(depths, depth_edges) - 1, 0, 9)
        expected = [np.median(times[slot == b]) if (slot == b).any() else np.nan for b in range(10)]
        np.testing.assert_array_equal(at["diffusion_median"].values, expected)


def test_the_report_of_a_sweep_storing_none(dask_client, tmp_path):
    ds = dla.run_sweep(spec_storing('"none"'), client=dask_client, out=tmp_path / "none.nc")
    written = {p.name for p in report(ds, tmp_path / "report")}
    assert "gallery.png" not in written and "diffusion_times.png" not in written
    assert {"dimension_vs_n.png", "mass_radius.png", "box_counts.png"} <= written
    text = (tmp_path / "report" / "report.md").read_text()
    assert "12 clusters, none stored with its positions" in text
    ds.close()
