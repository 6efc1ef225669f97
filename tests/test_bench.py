"""The benchmark runs end to end (its numbers are for people, not for asserts)."""

import numpy as np
import pytest
import xarray as xr

from dlasweep.cli import main


def test_bench_quick_writes_its_outputs(tmp_path):
    from matplotlib.image import imread

    from dlasweep.bench.benchmark import BENCH_SCHEMA
    from dlasweep.bench.host import WORKING_SETS
    from dlasweep.data.schema import attributes

    out = tmp_path / "bench"
    assert main(["bench", "--quick", "-o", str(out)]) == 0
    with xr.open_dataset(out / "bench.nc") as ds:
        assert set(ds.model.values) == {"lattice-2d", "offlattice-2d", "lattice-3d", "offlattice-3d"}
        assert (ds.seconds > 0).all() and (ds.n_grown > 0).all()
        assert "naive" in set(ds.method.values)
        assert {"noise_reduction=4", "neighbour_alpha=0.2", "contact_distance=0.5"} <= set(ds.method.values)
        methods = set(ds.method.values)
        for name in BENCH_SCHEMA:
            assert {k: ds[name].attrs[k] for k in attributes(name, schema=BENCH_SCHEMA)} == attributes(
                name, schema=BENCH_SCHEMA), name
        runs = ds.sizes["run"]
        assert list(ds.attrs["host_read_mib"]) == list(WORKING_SETS) and (ds.attrs["host_read_ns"] > 0).all()
        # each run beside the host's read time just before and after it, as its line prints them
        printed = []
        for reads in ("host_read", "memory_read"):
            before, after = ds[reads + "_before"].values, ds[reads + "_after"].values
            assert ((before > 0) & (before < 1e4) & (after > 0) & (after < 1e4)).all()
            printed.append([f"{b:.0f}>{a:.0f}" for b, a in zip(before, after)])
    # The log: the command, a header, then one line per run: model, method, N.
    lines = (out / "bench.txt").read_text().splitlines()
    assert lines[0].startswith("$ dlasweep bench")
    assert lines[1].split()[:3] == ["model", "method", "N"]
    rows = [line for line in lines[2:] if line.split()[1:2] and line.split()[1] in methods]
    assert len(rows) == runs
    assert lines[1].split()[-4:] == ["host", "ns", "memory", "ns"]
    assert [row.split()[-2:] for row in rows] == [list(pair) for pair in zip(*printed)]
    picture = imread(out / "bench.png")
    assert picture.shape[0] > 300 and picture.shape[1] > 500 and picture[..., :3].std() > 0  # drawn, not blank


def test_bench_refuses_an_output_that_is_a_file(tmp_path, capsys):
    target = tmp_path / "taken"
    target.write_text("x")
    assert main(["bench", "--quick", "-o", str(target)]) == 2
    assert "-o" in capsys.readouterr().err


def test_target_table_compares_each_figure_with_its_target():
    from dlasweep.bench.benchmark import _to_dataset
    from dlasweep.bench.targets import target_table, verdict

    # time as N^1.2, steps per particle 10, 12, 14.4, 2**20 bytes per 1e5 particles added
    rows = [{"model": "lattice-2d", "method": "exact", "n": n, "seconds": 2e-6 * n**1.2, "n_grown": n,
             "steps": int(n * 10 * 1.2 ** k), "status": "ok", "peak_mb": 200.0 + n / 1e5, "added_mb": n / 1e5}
            for k, n in enumerate((10**5, 10**6, 10**7))]
    rows.append({"model": "offlattice-3d", "method": "exact", "n": 10**7, "seconds": 250.0, "n_grown": 10**7,
                 "steps": 10**9, "status": "ok", "peak_mb": 500.0, "added_mb": 300.0})
    lines = target_table(_to_dataset(rows))
    assert lines[0] == ("| model | 1e7 s | 1e8 s | bytes/particle at 1e7 | bytes/particle at 1e8 "
                        "| cost exponent 1e5 to 1e7 | steps/particle 1e7 over 1e5 |")
    table = {line.split(" | ")[0].strip("| "): [c.strip(" |") for c in line.split(" | ")] for line in lines[2:]}
    lattice = table["lattice-2d"]
    assert lattice[1] == "502.4 (<= 60: 737% over)"
    assert lattice[2] == ""  # no 1e8 run
    assert lattice[3] == "10.5 (<= 24: met)"
    assert lattice[5] == "1.20 [1.20, 1.20] (<= 1.06: 13% over)"  # one run each: no range
    assert lattice[6] == "1.44 (<= 1.4: 3% over)"
    assert verdict(130.6, 130) == " (<= 130: 0.5% over)" and verdict(130, 130) == " (<= 130: met)"
    assert table["offlattice-3d"][1] == "250.0 (<= 300: met)"
    assert table["offlattice-3d"][3] == "31.5 (<= 52: met)"
    assert table["offlattice-3d"][5:] == ["", ""]  # no 1e5 run: no exponent, no growth
    assert set(table) == {"lattice-2d", "offlattice-3d"}  # a model not benched has no row


def test_the_cost_exponent_is_fitted_where_the_targets_are_set():
    # one fit for the table, the file's attribute, the printed line and the chart: runs below 1e5 (here
    # 1e3 and 1e4, at a tenth of the time the N^1.2 law gives) would pull an all-N fit to 1.25
    from dlasweep.bench.benchmark import _to_dataset
    from dlasweep.bench.targets import cost_exponent, target_table

    rows = [{"model": "lattice-2d", "method": "exact", "n": n, "seconds": 2e-6 * n**1.2 * (0.1 if n < 10**5 else 1),
             "n_grown": n, "steps": 10 * n, "status": "ok", "peak_mb": 200.0, "added_mb": 1.0}
            for n in (10**3, 10**4, 10**5, 10**6, 10**7)]
    ds = _to_dataset(rows)
    slope, lo, hi = cost_exponent(ds)
    assert (round(slope, 6), lo, hi) == (1.2, 10**5, 10**7)
    assert target_table(ds)[2].split(" | ")[5] == "1.20 [1.20, 1.20] (<= 1.06: 13% over)"
    assert cost_exponent(_to_dataset(rows[:3])) is None  # one N in range: no slope


def test_the_cost_exponent_splits_into_steps_and_the_cost_of_a_step():
    # steps a particle as N^0.05 (with noise a log-log fit must carry through) and the whole time as
    # N^1.2: the parts are 0.05 and 0.15 where the fit is exact, and add up to the slope less one always
    from dlasweep.bench.benchmark import _exponent_line, _to_dataset
    from dlasweep.bench.targets import cost_exponent, exponent_parts

    def rows(wobble):
        return [{"model": "offlattice-3d", "method": "exact", "n": n, "seconds": 3e-6 * n**1.2 * w,
                 "n_grown": n, "steps": int(40 * n * n**0.05), "status": "ok", "peak_mb": 200.0, "added_mb": 1.0}
                for n, w in zip((10**4, 10**5, 10**6, 10**7), wobble)]

    parts = exponent_parts(_to_dataset(rows([1.0] * 4)))
    assert (round(parts["steps"], 4), round(parts["step_cost"], 4)) == (0.05, 0.15)
    ds = _to_dataset(rows([0.3, 1.0, 1.3, 0.9]))  # 1e4 (outside the fit) and the rest off the law
    slope, lo, hi = cost_exponent(ds)
    parts = exponent_parts(ds)
    assert abs(1 + parts["steps"] + parts["step_cost"] - slope) < 1e-9 and abs(parts["step_cost"] - 0.15) > 0.01
    assert _exponent_line("offlattice-3d", slope, lo, hi, parts, {"low": 1.1, "high": 1.3}) == (
        f"offlattice-3d: time grows as N^{slope:.2f} [1.10, 1.30] from 1e5 to 1e7: N particles x N^0.050 steps "
        f"a particle x N^{parts['step_cost']:.3f} ns a step")


def test_the_cost_exponents_range_takes_the_fastest_and_slowest_runs():
    # time as N^1.2; the runs of 1e5 from 0.9 to 1.1 of it, of 1e6 from 0.8 to 1.25 (its weight in the
    # fit of 1e5, 1e6 and 1e7 is zero), one run of 1e7: the range is the slopes through 1e5's ends
    from dlasweep.bench.benchmark import _to_dataset
    from dlasweep.bench.targets import cost_exponent, cost_exponent_range, target_table

    spread = {10**5: (0.9, 1.1), 10**6: (0.8, 1.25), 10**7: (1.0, 1.0)}
    rows = [{"model": "lattice-2d", "method": "exact", "n": n, "seconds": 2e-6 * n**1.2, "n_grown": n,
             "seconds_low": 2e-6 * n**1.2 * spread[n][0], "seconds_high": 2e-6 * n**1.2 * spread[n][1],
             "steps": 10 * n, "status": "ok", "peak_mb": 200.0, "added_mb": 1.0} for n in spread]
    ds = _to_dataset(rows)
    low, high = cost_exponent_range(ds)
    assert low == pytest.approx(1.2 - np.log(1.1) / np.log(100))
    assert high == pytest.approx(1.2 - np.log(0.9) / np.log(100))
    assert low < cost_exponent(ds)[0] < high
    assert target_table(ds)[2].split(" | ")[5] == "1.20 [1.18, 1.22] (<= 1.06: 13% over)"
    single = _to_dataset([{k: v for k, v in row.items() if not k.startswith("seconds_")} for row in rows])
    assert cost_exponent_range(single) == pytest.approx((1.2, 1.2))  # one run each: no range


def test_a_full_bench_runs_the_first_scaling_n_again_after_the_long_runs(monkeypatch):
    # every probe a little slower than the one before (a host that slows down): 1e5's six runs,
    # three before 1e7 and three after, span the drift, and the median is one of them
    from dlasweep.bench import benchmark as bench
    from dlasweep.bench import targets as bench_targets

    calls = []

    def fake_probe(params, n, seed=1, cold=False, ahead=None):
        calls.append((params["model"], params["dim"], n))
        return {"seconds": 1e-6 * n * (1 + 0.01 * len(calls)), "n_grown": n, "steps": 10 * n, "status": "ok",
                "peak_mb": 200.0, "added_mb": 1.0}

    monkeypatch.setattr(bench, "probe", fake_probe)
    monkeypatch.setattr(bench, "read_latency", lambda reads: {1.0: 10.0})  # its own test: tests/test_host.py
    monkeypatch.setattr(bench, "harmonic_probe", fake_harmonic_probe)
    lines = []
    ds = bench.run_bench(full=True, echo=lines.append)
    lo, hi = bench_targets.SCALING
    for name, params in bench_targets.MODELS.items():
        mine = [i for i, call in enumerate(calls) if call[:2] == (params["model"], params["dim"])]
        firsts = [i for i in mine if calls[i][2] == lo]
        last = next(i for i in mine if calls[i][2] == hi)
        assert len(firsts) == 2 * bench.REPEATS and sum(i > last for i in firsts) == bench.REPEATS, name
        row = ds.where((ds.model == name) & (ds.method == "exact") & (ds.n == lo), drop=True)
        assert row.sizes["run"] == 1  # one row, of all its runs
        times = sorted(1e-6 * lo * (1 + 0.01 * (i + 1)) for i in firsts)
        assert float(row.seconds_low[0]) == times[0] and float(row.seconds_high[0]) == times[-1]
        assert float(row.seconds[0]) == times[len(times) // 2]
        assert any(line.startswith(f"{name}: {lo} again after the rest, 6 runs") for line in lines), name
        longs = [i for i in mine if calls[i][2] == hi]  # the long runs too: one would be the host's chance
        assert len(longs) == bench.REPEATS, name
        row = ds.where((ds.model == name) & (ds.method == "exact") & (ds.n == hi), drop=True)
        times = sorted(1e-6 * hi * (1 + 0.01 * (i + 1)) for i in longs)
        assert [float(row[v][0]) for v in ("seconds_low", "seconds", "seconds_high")] == times, name
        low, high = (bench_targets.exponent_attribute(name, end) for end in ("low", "high"))
        assert ds.attrs[low] < ds.attrs[high]


def test_a_huge_bench_grows_1e8_once(monkeypatch):
    from dlasweep.bench import benchmark as bench

    calls = []

    def fake_probe(params, n, seed=1, cold=False, ahead=None):
        calls.append(n)
        return {"seconds": 1e-6 * n, "n_grown": n, "steps": 10 * n, "status": "ok", "peak_mb": 200.0,
                "added_mb": 1.0}

    monkeypatch.setattr(bench, "probe", fake_probe)
    monkeypatch.setattr(bench, "read_latency", lambda reads: {1.0: 10.0})
    monkeypatch.setattr(bench, "end_to_end", lambda params, n, peak, folder: {"sweep_peak_mb": peak})
    monkeypatch.setattr(bench, "_end_to_end_line", lambda name, n, figures: f"{name} end to end")
    monkeypatch.setattr(bench, "target_table", lambda ds: [])
    bench.run_bench(huge=True, models=["lattice-2d"], echo=lambda line: None)
    assert calls.count(bench.HUGE_COUNT) == 1 and calls.count(bench.FULL_COUNT) == bench.REPEATS


def test_bench_runs_only_the_models_asked_for(tmp_path, monkeypatch, capsys):
    from dlasweep.bench import benchmark as bench

    calls = []

    def fake_probe(params, n, seed=1, cold=False, ahead=None):
        calls.append((params["model"], params["dim"], params.get("jumps", True), n))
        return {"seconds": 1e-6 * n, "n_grown": n, "steps": 10 * n, "status": "ok", "peak_mb": 200.0,
                "added_mb": 1.0}

    monkeypatch.setattr(bench, "probe", fake_probe)
    monkeypatch.setattr(bench, "read_latency", lambda reads: {1.0: 10.0})
    lines = []
    ds = bench.run_bench(full=True, models=["lattice-3d"], echo=lines.append)
    assert {call[:3] for call in calls} == {("lattice", 3, True)}
    # the model's exact runs and its growth laws' runs, nothing of another model
    assert set(ds.model.values) == {"lattice-3d"}
    assert set(ds.method.values) == {"cold", "installed", "exact", *bench.LAWS["lattice-3d"]}
    assert [line.split(" |")[0] for line in lines if line.startswith("| ")][1:] == ["| lattice-3d"]
    # the naive walk comes with lattice-2d; a model named twice runs once
    calls.clear()
    ds = bench.run_bench(quick=True, models=["lattice-2d", "lattice-2d"], echo=lines.append)
    quick = bench.QUICK_COUNT
    laws = [("lattice", 2, True, quick)] * len(bench.LAWS["lattice-2d"])  # each law beside the exact method
    assert sorted(calls) == sorted([("lattice", 2, False, quick // 4), ("lattice", 2, True, quick // 4),
                                    ("lattice", 2, True, quick), *laws])
    # from the command line, and a model it does not know: one line that names it, status 2, nothing written
    out = tmp_path / "bench"
    assert main(["bench", "--quick", "--model", "offlattice-2d", "--model", "lattice-3d", "-o", str(out)]) == 0
    with xr.open_dataset(out / "bench.nc") as ds:
        assert sorted(set(ds.model.values)) == ["lattice-3d", "offlattice-2d"]
    capsys.readouterr()
    assert main(["bench", "--quick", "--model", "lattice-4d", "-o", str(tmp_path / "never")]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "'lattice-4d'" in err
    assert not (tmp_path / "never").exists()


def test_a_bench_times_each_model_s_first_grow_cold_and_as_installed_but_a_quick_one(monkeypatch):
    from dlasweep.bench import benchmark as bench
    from dlasweep.bench.targets import COLD_COUNT, COLD_TARGET

    calls = []

    def fake_probe(params, n, seed=1, cold=False, ahead=None):
        calls.append((params["model"], params["dim"], n, cold, ahead))
        seconds = (COLD_TARGET / 4 if ahead else 3 * COLD_TARGET) if cold else 1e-6 * n
        return {"seconds": seconds, "n_grown": n, "steps": 10 * n, "status": "ok", "peak_mb": 200.0, "added_mb": 1.0}

    monkeypatch.setattr(bench, "probe", fake_probe)
    monkeypatch.setattr(bench, "read_latency", lambda reads: {1.0: 10.0})
    lines = []
    ds = bench.run_bench(models=["lattice-2d", "offlattice-3d"], echo=lines.append)
    # each model's first grow twice, in fresh interpreters: on an empty cache, and after its kernels were
    # compiled ahead as the wheel's build compiles them (the model named, so that its own are)
    assert [call[:5] for call in calls if call[3]] == [
        ("lattice", 2, COLD_COUNT, True, None), ("lattice", 2, COLD_COUNT, True, "lattice-2d"),
        ("offlattice", 3, COLD_COUNT, True, None), ("offlattice", 3, COLD_COUNT, True, "offlattice-3d")]
    for method, seconds in (("cold", 3 * COLD_TARGET), ("installed", COLD_TARGET / 4)):
        rows = ds.where(ds.method == method, drop=True)
        assert sorted(rows.model.values) == ["lattice-2d", "offlattice-3d"] and (rows.n == COLD_COUNT).all()
        assert (rows.seconds == seconds).all()
    # the target is the installed grow's; the cold one is shown beside it
    assert f"lattice-2d: first grow of {COLD_COUNT} on a cold cache 30.0 s" in lines
    assert f"lattice-2d: first grow of {COLD_COUNT} as the wheel installs it 2.5 s (<= 10: met)" in lines
    calls.clear()
    bench.run_bench(quick=True, models=["lattice-3d"], echo=lines.append)
    assert calls and not any(call[3] for call in calls)


def test_sweep_ratios_set_the_whole_process_against_its_kernels():
    from dlasweep.bench.benchmark import RATIO_TARGET, sweep_ratios

    lines = []
    figures = sweep_ratios(echo=lines.append, sweeps=[(6, [50, 200])], threads=2)
    get = {key.removeprefix("sweep_6x50_200_"): value for key, value in figures.items()}
    assert set(get) == {"process", "kernels", "ideal", "ratio", "target"}
    assert get["kernels"] > 0 and get["ideal"] == get["kernels"] / 2
    assert get["process"] > get["ideal"] and get["ratio"] == get["process"] / get["ideal"]
    assert get["target"] == RATIO_TARGET[0] * get["ideal"] + RATIO_TARGET[1]
    assert len(lines) == 2 and lines[1].split()[:3] == ["6", "x", "[50,"]


def test_end_to_end_sets_a_sweep_and_its_report_against_the_growth(tmp_path):
    # A one-cluster sweep and its report as a user runs them, their peaks over the growth's own: the
    # processes hold the imports (and the report matplotlib), so at 2000 particles both exceed it.
    from dlasweep.bench.benchmark import _end_to_end_line, end_to_end, probe

    params = {"model": "lattice", "dim": 2}
    grown = probe(params, 2000)
    figures = end_to_end(params, 2000, grown["peak_mb"], tmp_path)
    assert figures["sweep_ratio"] == figures["sweep_peak_mb"] / grown["peak_mb"] > 1.0
    assert figures["report_ratio"] == figures["report_peak_mb"] / grown["peak_mb"] > 1.0
    assert (tmp_path / "end_to_end_2000.nc").is_file() and (tmp_path / "end_to_end_2000" / "report.md").is_file()
    assert _end_to_end_line("lattice-2d", 10**8, {"sweep_peak_mb": 2600.0, "report_peak_mb": 3400.0,
                                                  "sweep_ratio": 1.04, "report_ratio": 1.36}) == (
        "lattice-2d 1e8 end to end: one-cluster sweep peak 2600 MB, 1.04x the growth's (<= 1.3: met); "
        "its report 3400 MB, 1.36x (<= 1.3: 5% over)")


@pytest.mark.parametrize("seconds, target, said", [(3.0, 3.0, "met"), (2.5, 3.0, "met"), (4.16, 3.0, "over by 1.16 s"),
                                                   (20.8416, 20.8400, "over by 2 ms")])
def test_shortfall_never_reads_over_by_nothing(seconds, target, said):
    """A sweep 1.6 ms over its target printed "over by 0.00 s" (bench --full, 2026-11-30)."""
    from dlasweep.bench.benchmark import shortfall

    assert shortfall(seconds, target) == said


def fake_harmonic_probe(params, n, walkers, seed=1):
    return {"n_grown": n, "growth_seconds": 1e-5 * n, "walkers": walkers, "seconds": 2e-5 * walkers, "status": "ok"}


@pytest.mark.parametrize("mode", ["quick", "default", "full"])
def test_the_harmonic_row_times_walkers_against_a_frozen_2d_offlattice_cluster(mode, monkeypatch):
    from dlasweep.bench import benchmark as bench

    asked = []

    def probe(params, n, walkers, seed=1):
        asked.append((params["model"], params["dim"], n, walkers))
        return fake_harmonic_probe(params, n, walkers, seed)

    monkeypatch.setattr(bench, "harmonic_probe", probe)
    lines = []
    attrs = bench.harmonic_bench(full=mode == "full", quick=mode == "quick", echo=lines.append)
    n, walkers = bench.HARMONIC_COUNTS[mode]
    assert asked == [("offlattice", 2, n, walkers)]
    assert attrs["harmonic_walkers_per_second"] == pytest.approx(1 / 2e-5)
    assert attrs["harmonic_growth_particles_per_second"] == pytest.approx(1 / 1e-5)
    assert len(lines) == 1 and "walkers/s" in lines[0]
    # the growth's rate is the bench's own median run of that N when it grew one
    grown = {("offlattice-2d", "exact", n): [{"seconds": 1e-6 * n, "n_grown": n}]}
    assert bench.harmonic_bench(full=mode == "full", quick=mode == "quick", echo=lines.append,
                                grown=grown)["harmonic_growth_particles_per_second"] == pytest.approx(1e6)


def test_the_harmonic_row_runs_for_a_real_small_cluster():
    from dlasweep.bench import benchmark as bench

    run = bench.harmonic_probe(bench.MODELS["offlattice-2d"], 300, 1000)
    assert run["n_grown"] == 300 and run["walkers"] == 1000 and run["seconds"] > 0 and run["status"] == "ok"
