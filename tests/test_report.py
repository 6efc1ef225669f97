"""The report writes its table, plots and write-up from a sweep dataset."""

from __future__ import annotations

import csv
import itertools
import time

import numpy as np
import pytest
import xarray as xr

import dlasweep as dla
from conftest import colours_shown
from dlasweep.data import schema
from dlasweep.measures.boxes import box_counts, default_scales
from dlasweep.measures.shape import anisotropy, max_radius, radius_of_gyration
from dlasweep.params import STATUSES
from dlasweep.reporting.folder import report
from dlasweep.reporting.readout import Readout
from dlasweep.stats.constants import MIN_CI_SEEDS


def synthetic_sweep(axes, sizes=(0,), counts=(100, 300, 800), seeds=3, parents=False):
    """A dataset with the layout of README, "The dataset", grown and measured here, not by run_sweep
    (``parents``: with the clusters' parents, as files have them since they were stored)."""
    scales = default_scales(counts[-1])
    shape = (*(len(v) for v in axes.values()), len(sizes), len(counts), seeds)
    # Every variable but the growth history (a file from before it was recorded).
    science = {name: schema.blank(name, (*shape, len(scales)) if name == "box_count" else shape)
               for name in (*schema.SCIENCE, "wall_time") if name != "radius_gyration_history"}
    ragged = {a: [] for a in ("x", "y", "diffusion_time", *(["parent"] if parents else []))}
    cluster = {f"cluster_{a}": [] for a in (*axes, "size", "seed")}
    particles = []
    for where in itertools.product(*(range(len(v)) for v in axes.values()), range(len(sizes)), range(seeds)):
        params = {name: values[i] for (name, values), i in zip(axes.items(), where)}
        size, seed = sizes[where[-2]], where[-1]
        start = time.perf_counter()
        c = dla.grow(counts[-1], seed=seed, size=size, **params)
        elapsed = time.perf_counter() - start
        rg, rmax = radius_of_gyration(c.points), max_radius(c.points)
        for k, n in enumerate(counts):
            m = min(n, len(c.points))
            index = (*where[:-1], k, seed)
            science["box_count"][index] = box_counts(c.points[:m], scales=scales)[1]
            science["n_grown"][index] = m
            science["status"][index] = 0 if m == n else STATUSES.index(c.status)
            science["radius_gyration"][index], science["max_radius"][index] = rg[m - 1], rmax[m - 1]
            science["anisotropy"][index] = anisotropy(c.points, [m])[0]
            science["wall_time"][index] = elapsed * m / len(c.points)
            science["walk_steps"][index] = c.steps[:m].sum()
        ragged["x"].append(c.points[:, 0])
        ragged["y"].append(c.points[:, 1])
        ragged["diffusion_time"].append(c.steps)
        if parents:
            ragged["parent"].append(c.parents)
        particles.append(len(c.points))
        for name, value in (*params.items(), ("size", size), ("seed", seed)):
            cluster[f"cluster_{name}"].append(value)
    ds = xr.Dataset(
        {
            **{name: (schema.dims(name, tuple(axes)), values) for name, values in science.items()},
            "cluster_particles": ("cluster", np.array(particles), {"sample_dimension": "particle"}),
            **{name: ("particle", np.concatenate(values)) for name, values in ragged.items()},
        },
        coords={
            **{name: (name, list(values)) for name, values in axes.items()},
            "size": ("size", list(sizes)),
            "n_particles": ("n_particles", list(counts)),
            "seed": ("seed", list(range(seeds))),
            "scale": ("scale", scales),
            **{name: ("cluster", values) for name, values in cluster.items()},
            "model": "lattice",
            "dim": 2,
        },
        attrs={"title": "synthetic sweep", "spec": 'name = "synthetic"', "root_seed": 1, "source": "dlasweep test"},
    )
    for name, var in ds.variables.items():
        var.attrs.update(schema.attributes(name, var.dtype))
    return ds


ALWAYS = {"summary.csv", "summary.md", "report.md", "gallery.png", "box_counts.png", "box_local_slopes.png",
          "mass_radius.png", "anisotropy.png", "dimension_vs_n.png", "dimension_spread.png", "diffusion_times.png"}


def test_report_writes_every_file_and_skips_absent_axes(tmp_path):
    ds = synthetic_sweep({"stickiness": [1.0, 0.5]})
    written = report(ds, tmp_path / "out")
    names = {p.name for p in written}
    # stickiness is the model, not a method: no failure map, and no speed-accuracy chart.
    assert names == ALWAYS
    assert {p.name for p in (tmp_path / "out").iterdir()} == names
    for path in written:
        assert path.stat().st_size > 0
    rows = list(csv.DictReader(open(tmp_path / "out" / "summary.csv")))
    assert len(rows) == 2 * 3  # configurations x counts
    assert {r["stickiness"] for r in rows} == {"1.0", "0.5"}
    assert all(r["seeds"] == "3" and r["status"] == "ok:3" for r in rows)
    big = [r for r in rows if r["n_particles"] == "800"]
    # Three seeds give D and its interval.
    assert all(float(r["D_ci_lo"]) < float(r["D"]) < float(r["D_ci_hi"]) and r["D_ci_reason"] == "" for r in big)
    rows = list(csv.DictReader(open(report(synthetic_sweep({"stickiness": [1.0, 0.5]}, seeds=2),
                                           tmp_path / "two")[0].parent / "summary.csv")))
    big = [r for r in rows if r["n_particles"] == "800"]
    # Two seeds give D and no interval, and say why.
    assert all(1.3 < float(r["D"]) < 2.1 and r["D_ci_lo"] == "nan" and "fewer than the" in r["D_ci_reason"]
               for r in big)
    two = (tmp_path / "two" / "report.md").read_text()
    assert "no CI: 2 < 3 clusters" in two and "cannot say whether resolved" in two
    text = (tmp_path / "out" / "report.md").read_text()
    for name in names - {"report.md", "summary.csv", "summary.md"}:
        assert f"({name})" in text
    assert "speed_accuracy" not in text and "reads low" in text and "1.7100(3)" in text
    assert text.count("95% confidence interval") == 1
    # Whether the difference between the two configurations is resolved, said, not left to the reader.
    assert "- stickiness=0.5 against stickiness=1.0: " in text and "cannot say whether resolved" not in text


@pytest.mark.parametrize("not_a_sweep, error, message", [
    ("sweep.nc", TypeError, "got str"),
    (xr.Dataset({"x": ("particle", [0, 1])}), ValueError, "holds no sweep"),
])
def test_what_is_not_a_sweep_is_refused_and_an_earlier_report_stays_whole(tmp_path, not_a_sweep, error, message):
    written = report(synthetic_sweep({"stickiness": [1.0, 0.5]}), tmp_path / "out")
    before = {path.name: path.read_bytes() for path in written}
    for call in (lambda: report(not_a_sweep, tmp_path / "out"), lambda: dla.summarise(not_a_sweep)):
        with pytest.raises(error, match=f"^ds: .*{message}"):
            call()
    assert {path.name: path.read_bytes() for path in (tmp_path / "out").iterdir()} == before


def test_report_tells_its_progress_step_by_step(tmp_path):
    calls = []
    report(synthetic_sweep({"stickiness": [1.0, 0.5]}), tmp_path / "out",
           progress=lambda done, steps, name: calls.append((done, steps, name)))
    plots = [name for _, _, name in calls[2:-2]]
    assert [done for done, _, _ in calls] == list(range(len(calls)))
    assert {steps for _, steps, _ in calls} == {len(calls) - 1}
    assert [name for _, _, name in calls[:2]] == ["summary", "tables"] and calls[-2][2] == "report.md"
    assert calls[-1][2] == ""
    assert {f"{name}.png" for name in plots} >= ALWAYS - {"summary.csv", "summary.md", "report.md"}


def test_report_draws_speed_accuracy_and_marks_flagged_configurations(tmp_path):
    ds = synthetic_sweep({"kill_factor": [0.0, 2.0]}, sizes=(0, 40), counts=(200, 600), seeds=2)
    names = {p.name for p in report(ds, tmp_path)}
    assert names == ALWAYS | {"speed_accuracy.png", "failure.png"}
    rows = list(csv.DictReader(open(tmp_path / "summary.csv")))
    # A box of 40 cannot hold 600 particles: growth stops at the boundary, and the table says so.
    bounded = [r for r in rows if r["size"] == "40" and r["n_particles"] == "600"]
    assert bounded and all(r["flagged"] == "True" and "boundary" in r["status"] for r in bounded)
    assert "⚠" in (tmp_path / "summary.md").read_text()


@pytest.mark.parametrize("suffix", [".png", ".svg"])
def test_draw_cluster_writes_a_picture(tmp_path, suffix):
    from dlasweep.reporting.pictures import draw_cluster

    c = dla.grow(300, seed=1)
    path = draw_cluster(c.points, c.params, tmp_path / f"cluster{suffix}")
    # Each site a block of as many pixels, coloured by attachment order (viridis: a colour may be two sites').
    shown = colours_shown(path)
    site = min(shown.values())
    assert all(count % site == 0 for count in shown.values())
    assert sum(shown.values()) == 300 * site and len(shown) > 200


def test_plot_bench_writes_the_time_against_n_chart(tmp_path):
    from dlasweep.bench.benchmark import _to_dataset
    from dlasweep.bench.chart import plot_bench

    runs = [("lattice-2d", "exact", n, 1e-6 * n**1.1) for n in (1_000, 10_000, 100_000)]
    runs += [("offlattice-2d", "exact", n, 2e-6 * n) for n in (1_000, 10_000)]
    runs += [("lattice-2d", "naive", 1_000, 0.5)]
    ds = _to_dataset([dict(model=m, method=k, n=n, seconds=t, n_grown=n, steps=10 * n, peak_mb=100.0, added_mb=5.0)
                      for m, k, n, t in runs])
    ds.attrs["cost_exponent_lattice_2d"] = 1.1
    path = plot_bench(ds, tmp_path / "bench")
    assert path == tmp_path / "bench" / "bench.png"
    # A line per model, in the report's first two colours (tab10 C0, C1); the naive run beside lattice-2d's.
    shown = colours_shown(path)
    assert shown.get((31, 119, 180), 0) > 500 and shown.get((255, 127, 14), 0) > 500, sorted(shown.items())[:5]


THIRTY = """
[grid]
n_particles = [60, 120]
seeds = 10
[model]
model = "offlattice"
kill_factor = [0.0, 1.2, 1.5, 2.0, 3.0]
jumps = [true, false]
step = [0.0, 0.5, 1.0]
[run]
root_seed = 3
"""


@pytest.fixture(scope="module")
def thirty_variants(dask_client):
    from dlasweep.sweep.spec import parse_spec

    return dla.run_sweep(parse_spec(THIRTY), client=dask_client)


def drawn(monkeypatch, plot, ds, tmp_path, caption=False):
    """Run one plot of the report and return its Figure (and its caption) instead of only a file."""
    from dlasweep.reporting import plots as report_plots

    figures = []
    monkeypatch.setattr(report_plots, "save_figure", lambda fig, path: figures.append(fig) or fig.savefig(path))
    said = plot(Readout(ds), tmp_path / "plot.png")
    assert said and (tmp_path / "plot.png").stat().st_size > 0
    (fig,) = figures
    fig.canvas.draw()
    return (fig, said) if caption else fig


def overlaps(a, b):
    return a.x0 < b.x1 and b.x0 < a.x1 and a.y0 < b.y1 and b.y0 < a.y1


def test_speed_accuracy_stays_readable_with_thirty_variants(thirty_variants, monkeypatch, tmp_path):
    from dlasweep.reporting.plots import _speed_accuracy

    fig = drawn(monkeypatch, _speed_accuracy, thirty_variants, tmp_path)
    panels = [ax for ax in fig.axes if ax.get_visible()]
    assert len(panels) == 2
    # Every variant is a point with an error bar in each panel, named in one legend, not by labels on the data.
    for ax in panels:
        assert len(ax.containers) == 30 and not ax.texts
    (legend,) = fig.legends
    names = [t.get_text() for t in legend.get_texts()]
    assert len([n for n in names if not n.startswith("Pareto")]) == 30 and len(set(names)) == len(names)
    box = legend.get_window_extent()
    assert not any(overlaps(box, ax.get_window_extent()) for ax in panels)
    # One marker and colour per set of shortcuts: exact, then the seven combinations.
    markers = {(c.lines[0].get_marker(), c.lines[0].get_color()) for c in panels[0].containers}
    assert len(markers) == 8


def test_failure_draws_the_exact_method_as_a_band_not_a_point_at_zero(thirty_variants, monkeypatch, tmp_path):
    from dlasweep.reporting.plots import _failure

    fig, caption = drawn(monkeypatch, _failure, thirty_variants, tmp_path, caption=True)
    panels = [ax for ax in fig.axes if ax.get_visible()]
    # The shortcuts, each against the exact method; jumps too, which the old map left out.
    assert [ax.get_xlabel() for ax in panels] == (["kill_factor (exact: 0.0)"] * 2 + ["jumps (exact: true)"] * 2
                                                  + ["step (exact: 0.0)"] * 2)
    for ax in panels:
        (series,) = ax.containers
        xs = series.lines[0].get_xdata()
        assert 0.0 not in xs or ax.get_xlabel().startswith("jumps")  # the non-exact values only
        assert len(xs) in (1, 2, 4) and series.has_yerr
        assert any("exact method, 95% CI" == t.get_text() for t in ax.get_legend().get_texts())
        # The bias of every point in units of the CI is written beside it.
        assert len(ax.texts) == len(xs)
    assert "numbers: bias" in fig._suptitle.get_text()
    assert "shaded band its 95% CI" in caption and "bias in units" in caption and "scene" not in caption


def test_failure_says_only_what_it_draws_and_skips_model_parameters(monkeypatch, tmp_path):
    from dlasweep.reporting.plots import _failure

    assert _failure(Readout(synthetic_sweep({"stickiness": [1.0, 0.5]}, counts=(200, 400), seeds=2)),
                    tmp_path / "none.png") is None
    # Two seeds: no CIs, so no band and no bias numbers, and neither is promised.
    ds = synthetic_sweep({"kill_factor": [0.0, 2.0], "stickiness": [1.0, 0.5]}, counts=(200, 400), seeds=2)
    fig, caption = drawn(monkeypatch, _failure, ds, tmp_path, caption=True)
    panels = [ax for ax in fig.axes if ax.get_visible()]
    assert [ax.get_xlabel() for ax in panels] == ["kill_factor (exact: 0.0)"] * 2
    assert all(len(ax.containers) == 2 and not ax.texts for ax in panels)  # one series per scene
    assert "numbers" not in fig._suptitle.get_text()
    assert "band" not in caption and "bias" not in caption and "bars" not in caption
    assert f"no CI: fewer than {MIN_CI_SEEDS} seeds" in caption and "one colour per scene" in caption


def test_dimension_against_n_is_one_panel_per_configuration(monkeypatch, tmp_path):
    from dlasweep.reporting.plots import _dimension_vs_n, _mass_radius

    ds = synthetic_sweep({"stickiness": [1.0, 0.5, 0.2]}, counts=(200, 600), seeds=MIN_CI_SEEDS - 1)
    fig, caption = drawn(monkeypatch, _dimension_vs_n, ds, tmp_path, caption=True)
    panels = [ax for ax in fig.axes if ax.get_visible()]
    assert [ax.get_title() for ax in panels] == ["stickiness=1.0", "stickiness=0.5", "stickiness=0.2"]
    # One y-axis, so that panels compare by eye; too few seeds draw no bars and say so.
    assert len({ax.get_ylim() for ax in panels}) == 1
    assert "no CI" in fig._suptitle.get_text() and "No interval is drawn" in caption and "band" not in caption
    assert all(ax.get_legend() is None for ax in panels) and len(fig.legends) == 1
    # Lattice clusters get no off-lattice reference line.
    assert not any(line.get_linestyle() == "--" for ax in panels for line in ax.get_lines())
    fig = drawn(monkeypatch, _mass_radius, ds, tmp_path)
    assert len([ax for ax in fig.axes if ax.get_visible()]) == 3


def test_box_slopes_and_diffusion_times_say_what_they_measure(monkeypatch, tmp_path):
    from dlasweep.reporting.plots import _box_local_slopes, _diffusion_times

    ds = synthetic_sweep({"jumps": [True, False]}, counts=(100, 200), seeds=2)
    fig = drawn(monkeypatch, _box_local_slopes, ds, tmp_path)
    (ax,) = [ax for ax in fig.axes if ax.get_visible()]
    assert "Box-counting" in ax.get_title() and "box-counting" in ax.get_ylabel()
    fig, caption = drawn(monkeypatch, _diffusion_times, ds, tmp_path, caption=True)
    hist, depth = [ax for ax in fig.axes if ax.get_visible()]
    assert "moves" in hist.get_xlabel() and "moves" in depth.get_ylabel()
    # Jumps on and off count different moves: kept apart by line style and said in the caption.
    assert [line.get_linestyle() for line in depth.get_lines()] == ["-", "--"]
    assert "not on one time scale" in caption


def test_captions_promise_no_interval_a_sweep_of_few_seeds_lacks(monkeypatch, tmp_path):
    from dlasweep.reporting.plots import _anisotropy, _dimension_spread, _speed_accuracy

    ds = synthetic_sweep({"kill_factor": [0.0, 2.0]}, counts=(200, 400), seeds=2)
    for plot in (_anisotropy, _dimension_spread, _speed_accuracy):
        fig, caption = drawn(monkeypatch, plot, ds, tmp_path, caption=True)
        assert "95% CI" not in caption and f"fewer than {MIN_CI_SEEDS}" in caption, (plot.__name__, caption)
        assert not any("95% CI" in ax.get_ylabel() for ax in fig.axes if ax.get_visible()), plot.__name__


def test_the_anisotropy_figure_says_it_is_not_a_drifts_elongation(monkeypatch, tmp_path):
    """Under a drift the clusters grow up into it as cones, which <cos 4 theta> does not measure: the
    figure says so (title and caption); without a drift it says nothing of drift."""
    from dlasweep.reporting.plots import _anisotropy

    drifted = synthetic_sweep({"drift": [0.0, 0.3], "kill_factor": [2.0]}, counts=(100, 200), seeds=2)
    fig, caption = drawn(monkeypatch, _anisotropy, drifted, tmp_path, caption=True)
    (ax,) = [ax for ax in fig.axes if ax.get_visible()]
    assert "not the elongation along a drift" in ax.get_title()
    assert "not the cluster's elongation along the drift" in caption and "Rg/Rmax" in caption
    plain = synthetic_sweep({"kill_factor": [0.0, 2.0]}, counts=(100, 200), seeds=2)
    fig, caption = drawn(monkeypatch, _anisotropy, plain, tmp_path, caption=True)
    assert "drift" not in caption and "drift" not in fig.axes[0].get_title()


def test_report_says_whether_the_cis_resolve_a_difference_in_d(tmp_path):

    ds = synthetic_sweep({"stickiness": [1.0, 0.1]}, counts=(100, 300), seeds=MIN_CI_SEEDS)
    sweep = Readout(ds)
    ((low, high, value, half),) = sweep.differences(1)
    one, two = sweep.row(low, 1), sweep.row(high, 1)
    assert value == two["D"] - one["D"] and 0 < half < abs(value) + 1
    assert half == pytest.approx(np.hypot(one["D_ci_hi"] - one["D_ci_lo"], two["D_ci_hi"] - two["D_ci_lo"]) / 2)
    report(ds, tmp_path)
    line = next(text for text in (tmp_path / "report.md").read_text().splitlines()
                if text.startswith("- stickiness=0.1 against stickiness=1.0: "))
    assert line.endswith("(resolved)") == (abs(value) > half) and ("|dev| <" in line) == (abs(value) <= half)


def test_report_says_whether_d_contains_the_published_value():
    """An interval that holds 1.7100 says so, one that misses it says that, a lattice sweep says nothing."""
    from types import SimpleNamespace

    from dlasweep.reporting.text import _against_reference

    def row(lo, hi):
        return {"D_ci_lo": lo, "D_ci_hi": hi, "D_inf_ci_lo": np.nan, "D_inf_ci_hi": np.nan}

    sweep = SimpleNamespace(reference=1.71, dim=2)
    (line, blank) = _against_reference(sweep, [("a", row(1.705, 1.722)), ("b", row(1.712, 1.72))])
    assert "1.7100(3)" in line and blank == ""
    assert "a: D [1.7050, 1.7220] contains it, D_inf: no interval" in line
    assert "b: D [1.7120, 1.7200] does not contain it" in line
    assert _against_reference(SimpleNamespace(reference=None, dim=2), [("a", row(1.7, 1.8))]) == []
