"""The command line: bad input exits 2 with one line and writes nothing; help from the parameter table;
sweeps end to end; what ``info`` tells of a file."""

import argparse
import contextlib
import importlib
import io
import re
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import dask
import netCDF4
import numpy as np
import pytest
import xarray as xr
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

import dlasweep as dla
from conftest import ROOT, TINY_SPEC, colours_shown, files_under, science
from dlasweep import cli
from dlasweep._version import FORMAT
from dlasweep.data import netcdf as store
from dlasweep.data import ragged, schema
from dlasweep.params import PARAMETERS
from dlasweep.reporting.folder import files as report_files
from dlasweep.sweep.parts import Parts

BAD_SPEC = TINY_SPEC.replace("stickiness = [1.0, 0.5]", "stickiness = [1.0, 0.0]")


@pytest.mark.parametrize("argv, named", [
    (["frobnicate"], "invalid choice"),
    (["grow", "-o", "a.nc"], "-n"),
    (["grow", "-n", "ten", "-o", "a.nc"], "-n"),
    (["grow", "-n", "2.5", "-o", "a.nc"], "-n"),
    (["grow", "-n", "1e5.5", "-o", "a.nc"], "-n"),
    (["grow", "-n", "1e9", "-o", "a.nc"], "-n"),
    (["grow", "-n", "10", "--max-steps", "1.5", "-o", "a.nc"], "--max-steps"),
    (["grow", "-n", "0", "-o", "a.nc"], "-n"),
    (["grow", "-n", "10", "-o", "a.txt"], "a.txt"),
    (["grow", "-n", "10", "-o", "missing/a.nc"], "missing"),
    (["grow", "-n", "10", "-o", "."], "-o"),
    (["grow", "-n", "10", "--seed", "-1", "-o", "a.nc"], "--seed"),
    (["grow", "-n", "10", "--stickiness", "2", "-o", "a.nc"], "--stickiness"),
    (["grow", "-n", "10", "--stickiness", "sticky", "-o", "a.nc"], "--stickiness"),
    (["grow", "-n", "10", "--launch", "box", "-o", "a.nc"], "--launch"),
    (["grow", "-n", "10", "--dim", "4", "-o", "a.nc"], "--dim"),
    (["grow", "-n", "10", "--colour", "red", "-o", "a.nc"], "--colour"),
    (["sweep", "absent.toml"], "absent.toml"),
    (["sweep", "bad.toml"], "model.stickiness"),
    (["sweep", "store.toml"], "run.store_clusters"),
    (["sweep", "spec.toml", "-o", "missing/out.nc"], "missing"),
    (["sweep", "spec.toml", "-o", "out.csv"], "out.csv"),
    (["sweep", "spec.toml", "-o", "/proc/out.nc"], "not writable"),
    (["sweep", "spec.toml", "--workers", "0"], "--workers"),
    (["sweep", "spec.toml", "--workers", "two"], "--workers"),
    (["sweep", "spec.toml", "--scheduler", "tcp://127.0.0.1:1", "--workers", "2"], "--workers"),
    (["sweep", "spec.toml", "--scheduler", "x", "--scheduler-file", "s.json"], "--scheduler"),
    (["sweep", "spec.toml", "--scheduler-file", "absent.json"], "--scheduler-file"),
    (["sweep", "spec.toml", "--scheduler", "notanaddress"], "--scheduler: 'notanaddress' is not a scheduler address"),
    (["sweep", "spec.toml", "--scheduler", "tcp://host:99999"], "--scheduler: 'tcp://host:99999' is not"),
    (["sweep", "spec.toml", "--scheduler", "inproc://x"], "--scheduler: 'inproc://x' is not a scheduler address"),
    (["sweep", "spec.toml", "--scheduler", "inproc://h/1/1"], "names a scheduler inside process 1, not this one"),
    (["sweep", "spec.toml", "--scheduler-file", "empty.json"], "--scheduler-file empty.json: not a dask scheduler"),
    (["sweep", "spec.toml", "--scheduler-file", "garbage.json"], "--scheduler-file garbage.json: not a dask"),
    (["sweep", "spec.toml", "--workers", "1e6"], "--workers: 1000000 is not in [1, 1024]"),
    (["sweep", "huge.toml"], "grid.seeds: 100000000000 is not in [1, 10000000]"),
    (["sweep", "heavy.toml"], "grid.n_particles: the sweep needs about "),
    (["grow", "-n", "200", "--model", "offlattice", "--step", "1e9", "-o", "a.nc"], "--step: 1000000000.0 is above"),
    (["grow", "-n", "10", "--stickiness", "1e-300", "-o", "a.nc"], "--stickiness"),
    (["grow", "-n", "10", "--launch-factor", "1e200", "-o", "a.nc"], "--launch-factor: 1e+200 is above 100"),
    (["grow", "-n", "10", "--max-steps", "1e25", "-o", "a.nc"], "--max-steps"),
    (["grow", "-n", "10", "--seed", "1e30", "-o", "a.nc"], "--seed"),
    (["grow", "-n", "1e400", "-o", "a.nc"], "-n"),
    (["report", "absent.nc"], "absent.nc"),
    (["report", "spec.toml"], "not a readable netCDF"),
    (["report", "spec.toml", "-o", "missing/report"], "missing"),
    (["report", "one.nc"], "one cluster"),
    (["info", "absent.nc"], "absent.nc"),
    (["info", "/dev/null"], "/dev/null: not a regular file"),
    (["grow", "-n", "10", "--seed", "1.5", "-o", "a.nc"], "dlasweep grow: argument --seed"),
    (["info", "spec.toml"], "not a readable netCDF"),
])
def test_bad_input_exits_2_with_one_line_and_writes_nothing(argv, named, run_cli, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "spec.toml").write_text(TINY_SPEC)
    (tmp_path / "bad.toml").write_text(BAD_SPEC)
    (tmp_path / "store.toml").write_text(TINY_SPEC.replace("root_seed = 12345",
                                                           'root_seed = 1\nstore_clusters = "few"'))
    (tmp_path / "huge.toml").write_text(TINY_SPEC.replace("seeds = 3", "seeds = 100000000000"))
    (tmp_path / "heavy.toml").write_text("[grid]\nn_particles = 1e8\nseeds = 64\n[model]\ndim = 3\n[run]\n"
                                         "workers = 64\n")  # 64 clusters of 10^8 in 3D at once
    (tmp_path / "empty.json").write_text("{}")
    (tmp_path / "garbage.json").write_text("garbage")
    store.save(store.cluster_dataset(dla.grow(5, 0), seed=0), tmp_path / "one.nc")
    before = files_under(tmp_path)
    status, out, err = run_cli(*argv)
    assert status == 2, err
    assert len(err.strip().splitlines()) == 1 and named in err, err
    assert "Traceback" not in err and out == ""
    assert files_under(tmp_path) == before


HEAVY = ("numba", "xarray", "dask", "distributed", "matplotlib", "pandas", "scipy", "netCDF4")
"""What the commands' work loads (about 1.5 s), and the help and the parser's refusals must not."""


@pytest.mark.parametrize("argv, status", [
    (["--help"], 0), (["grow", "--help"], 0), (["bench", "--help"], 0), (["slurm", "--help"], 0),
    (["grow", "-n", "ten", "-o", "a.nc"], 2), (["bench", "--model", "nope"], 2), (["frobnicate"], 2),
])
def test_help_and_bad_options_load_no_numerics(argv, status, tmp_path):
    script = ("import sys\nfrom dlasweep.cli import main\ncode = main(sys.argv[1:])\n"
              f"print(sorted(m for m in {HEAVY!r} if m in sys.modules), code)")
    done = subprocess.run([sys.executable, "-c", script, *argv], capture_output=True, text=True, cwd=tmp_path)
    assert done.stdout.splitlines()[-1] == f"[] {status}", done.stdout + done.stderr
    assert status == 0 or len(done.stderr.strip().splitlines()) == 1


def test_no_command_prints_usage_and_exits_2(run_cli):
    status, out, err = run_cli()
    assert status == 2 and out == ""
    assert err.startswith("usage: dlasweep") and all(c in err for c in ("grow", "sweep", "report", "info", "bench"))


def test_grow_help_comes_from_the_parameter_table(run_cli):
    status, out, _ = run_cli("grow", "--help")
    assert status == 0
    text = " ".join(out.split())  # argparse wraps lines
    assert "model parameter" not in text
    for name, param in PARAMETERS.items():
        assert f"--{name.replace('_', '-')}" in text and " ".join(param.meaning.split()) in text, name
    choices = {"model": "lattice,offlattice", "seed_shape": "point,block,line", "launch": "circle,box"}
    for name, values in choices.items():
        assert f"--{name.replace('_', '-')} {{{values}}}" in text
    assert "Default: 2*dim." in text and "Allowed: [0.0001, 1]." in text


@pytest.mark.parametrize("text, n", [("1e5", 100_000), ("1.5e3", 1500), ("100000", 100_000), ("2E3", 2000)])
def test_n_is_any_integral_number(text, n, run_cli, tmp_path, monkeypatch):
    asked = []
    module = importlib.import_module("dlasweep.growth.cluster")
    grow = module.grow

    def small(n, seed, **params):
        asked.append(n)
        return grow(5, seed, **params)

    monkeypatch.setattr(module, "grow", small)
    status, _, err = run_cli("grow", "-n", text, "--max-steps", "1e6", "-o", tmp_path / "c.nc")
    assert status == 0, err
    assert asked == [n]
    with store.open_sweep(tmp_path / "c.nc") as ds:
        assert int(ds["max_steps"]) == 1_000_000


def test_grow_writes_the_cluster(run_cli, tmp_path):
    out = tmp_path / "one.nc"
    status, _, err = run_cli("grow", "-n", "80", "--seed", "3", "--stickiness", "0.5", "--seed-shape", "point",
                             "-o", out)
    assert status == 0, err
    expected = dla.grow(80, 3, stickiness=0.5)
    with store.open_sweep(out) as ds:
        np.testing.assert_array_equal(ragged.cluster_points(ds, 0), expected.points)
        np.testing.assert_array_equal(ds["diffusion_time"], expected.steps)
        np.testing.assert_array_equal(dla.cluster_parents(ds, 0), expected.parents)
        assert float(ds["stickiness"]) == 0.5 and ds.attrs["seed"] == 3


def check_design(ds, spec_text):
    """The dataset as docs/dataset.md names it, for the tiny spec."""
    assert ds["box_count"].dims == ("stickiness", "size", "n_particles", "seed", "scale")
    for name in ("n_grown", "status", "radius_gyration", "max_radius", "anisotropy", "wall_time", "walk_steps"):
        assert ds[name].dims == ("stickiness", "size", "n_particles", "seed"), name
    assert list(ds["n_particles"].values) == [20, 60, 150] and list(ds["size"].values) == [0, 24]
    for name in ("x", "y", "diffusion_time"):
        assert ds[name].dims == ("particle",)
    assert "z" not in ds
    assert ds["cluster_particles"].attrs["sample_dimension"] == "particle"
    assert int(ds["cluster_particles"].sum()) == ds.sizes["particle"]
    # The cluster holds every particle grown at the largest count.
    last = ds["n_grown"].isel(n_particles=-1).values.ravel()
    np.testing.assert_array_equal(ds["cluster_particles"].values, last)
    for name in ("cluster_stickiness", "cluster_size", "cluster_seed"):
        assert name in ds.coords and ds[name].dims == ("cluster",)
    for name, var in ds.variables.items():
        assert var.attrs.get("long_name") and ("units" in var.attrs) == (var.dtype.kind not in "OU"), name
    assert ds.attrs["Conventions"] == "CF-1.8" and ds.attrs["featureType"] == "trajectory"
    assert ds.attrs["source"] == f"dlasweep {dla.__version__}"
    assert ds.attrs["title"] and ds.attrs["history"]
    assert ds.attrs["spec"] == spec_text and ds.attrs["root_seed"] == 12345
    assert ds["status"].attrs["flag_meanings"] == "ok boundary step_limit exhausted error"
    assert (ds["wall_time"] > 0).all() and (ds["box_count"] >= 1).all()


@pytest.fixture(scope="module")
def tiny_sweep(tmp_path_factory, dask_cluster):
    """The tiny spec swept through the command line; (status, stdout, stderr, folder)."""
    from dlasweep.cli import main

    folder = tmp_path_factory.mktemp("cli")
    (folder / "spec.toml").write_text(TINY_SPEC)
    with contextlib.redirect_stdout(io.StringIO()) as out, contextlib.redirect_stderr(io.StringIO()) as err:
        status = main(["sweep", str(folder / "spec.toml"), "-o", str(folder / "tiny.nc"),
                       "--scheduler", dask_cluster.scheduler_address])
    return status, out.getvalue(), err.getvalue(), folder


def test_sweep_end_to_end_on_a_running_scheduler(tiny_sweep, ncdump):
    status, stdout, err, folder = tiny_sweep
    assert status == 0, err
    assert "12 clusters" in stdout
    assert sorted(p.name for p in folder.iterdir()) == ["spec.toml", "tiny.nc"]
    out = folder / "tiny.nc"
    with store.open_sweep(out) as ds:
        check_design(ds, TINY_SPEC)
    with netCDF4.Dataset(out) as nc:
        assert nc["cluster_particles"].sample_dimension == "particle"
    subprocess.run([ncdump, "-h", str(out)], check=True, capture_output=True)


def test_report_of_the_sweep(tiny_sweep, run_cli, tmp_path):
    status, _, err = run_cli("report", tiny_sweep[3] / "tiny.nc", "-o", tmp_path / "report")
    assert status == 0, err
    assert any((tmp_path / "report").glob("*.png"))


def test_report_shows_progress_on_a_terminal_only(tiny_sweep, run_cli, tmp_path, monkeypatch):
    from dlasweep import cli

    bars = []
    real_bar = cli.steps_bar
    monkeypatch.setattr(cli, "steps_bar", lambda desc: bars.append(real_bar(desc)) or bars[-1])
    status, _, err = run_cli("report", tiny_sweep[3] / "tiny.nc", "-o", tmp_path / "piped")
    assert status == 0 and err == "" and bars[-1].__class__.__name__ == "nullcontext"
    monkeypatch.setattr(sys.stderr, "isatty", lambda: True)
    status, _, err = run_cli("report", tiny_sweep[3] / "tiny.nc", "-o", tmp_path / "shown")
    assert status == 0 and bars[-1].n == bars[-1].total > 10  # followed every step to the end


def test_info_of_a_sweep(tiny_sweep, run_cli):
    path = tiny_sweep[3] / "tiny.nc"
    status, out, err = run_cli("info", path)
    assert status == 0 and err == ""
    lines = out.splitlines()
    assert lines[0] == f"{path}: dlasweep parameter sweep 'tiny': diffusion-limited aggregation clusters"
    assert all(f"  {line}".rstrip() in lines for line in TINY_SPEC.splitlines())
    assert "  n_particles     3: 20, 60, 150" in lines and "  seed            3: 0, 1, 2" in lines
    assert "clusters: 12 stored" in out and "failed tasks: none" in lines and "stopped:" not in out
    # Every count accounts for the 12 clusters by status.
    status_lines = lines[lines.index("status (clusters at each count):") + 1:][:3]
    assert [line.split(":")[0].strip() for line in status_lines] == ["20", "60", "150"]
    assert all(sum(int(part.split()[-1]) for part in line.split(":")[1].split(",")) == 12 for line in status_lines)
    # The headline D of each configuration at the largest N, as summarise gives it.
    table = lines[lines.index("headline D at the largest N (ensemble mass-radius, 95% CI over seeds):") + 1:]
    assert table[0].split() == ["stickiness", "size", "N", "seeds", "D", "95%", "CI", "D_inf"]
    with store.open_sweep(path) as ds:
        summary = dla.summarise(ds).isel(n_particles=-1)
    rows = [row.split() for row in table[1:]]
    assert [(float(r[0]), int(r[1]), int(r[2])) for r in rows] == [
        (s, n, 150) for s in (1.0, 0.5) for n in (0, 24)]
    for row, d in zip(rows, summary["D"].values.ravel()):
        assert row[4] == (f"{d:.3f}" if np.isfinite(d) else "n/a")


def test_info_of_a_target_sweep_names_why_it_stopped(tiny_sweep, run_cli, tmp_path):
    with store.open_sweep(tiny_sweep[3] / "tiny.nc") as ds:
        half_width = ds["radius_gyration"].isel(n_particles=-1, seed=0, drop=True) / 100
        store.save(store.record_stop(ds.load(), half_width, 0.01, 12, "max_seeds reached"), tmp_path / "target.nc")
    status, out, err = run_cli("info", tmp_path / "target.nc")
    assert status == 0, err
    assert "stopped: max_seeds reached (target_ci 0.01, max_seeds 12)" in out.splitlines()


def test_info_of_a_grown_cluster(run_cli, tmp_path):
    path = tmp_path / "one.nc"
    assert run_cli("grow", "-n", "300", "--seed", "2", "--stickiness", "0.5", "-o", path)[0] == 0
    status, out, err = run_cli("info", path)
    assert status == 0, err
    assert "seed: 2" in out and "stickiness=0.5" in out and "neighbours=4" in out
    assert "particles: 300, status ok" in out
    assert "D of this cluster (mass-radius, 95% CI): " in out


@pytest.mark.parametrize("suffix", [".png", ".svg"])
def test_grow_draws_the_cluster(suffix, run_cli, tmp_path):
    out = tmp_path / f"cluster{suffix}"
    status, _, err = run_cli("grow", "-n", "50", "-o", out)
    assert status == 0, err
    # Coloured by attachment order, a site a block of pixels: fifty colours, each on as many pixels.
    shown = colours_shown(out)
    assert len(shown) == 50 and len(set(shown.values())) == 1, shown


@pytest.mark.slow
def test_sweep_with_the_embedded_cluster_matches(run_cli, write_spec, tmp_path, dask_client):
    out = tmp_path / "tiny.nc"
    status, _, err = run_cli("sweep", write_spec(), "-o", out, "--workers", "2")
    assert status == 0, err
    reference = dla.run_sweep(dla.load_spec(write_spec()), client=dask_client)
    with store.open_sweep(out) as ds:
        xr.testing.assert_identical(science(ds), science(reference))


def test_failed_tasks_exit_1_naming_them(run_cli, write_spec, tmp_path, dask_cluster, monkeypatch):
    from dlasweep.sweep import task as worker

    def broken(n, seed, **kwargs):
        raise MemoryError("no room")

    monkeypatch.setattr(worker, "grow", broken)
    monkeypatch.setattr(worker, "grow_many", broken)
    out = tmp_path / "tiny.nc"
    status, _, err = run_cli("sweep", write_spec(), "-o", out, "--scheduler", dask_cluster.scheduler_address)
    assert status == 1
    plan, failure = err.strip().splitlines()  # the plan, once connected, then one line of failure
    assert plan.startswith("dlasweep sweep: plan: 12 clusters, 1,800 particles")
    assert "task-0-0-0: MemoryError: no room" in failure
    with store.open_sweep(out) as ds:
        assert (ds["status"] == schema.STATUS_FLAGS.index("error")).all()
    status, info, err = run_cli("info", out)
    assert status == 0, err
    lines = info.splitlines()
    assert "  task-0-0-0: MemoryError: no room" in lines[lines.index("failed tasks: 12") + 1:]
    assert "         150: error 12" in lines


def test_resume_with_changed_spec_exits_2(run_cli, write_spec, tmp_path, dask_cluster):
    out = tmp_path / "tiny.nc"
    parts = tmp_path / "tiny.nc.parts"
    parts.mkdir()
    (parts / "manifest.json").write_text(f'{{"format": {FORMAT}, "digest": "old", "identity": {{"grid.seeds": [0]}}}}')
    status, _, err = run_cli("sweep", write_spec(), "-o", out, "--resume",
                             "--scheduler", dask_cluster.scheduler_address)
    assert status == 2 and "grid.seeds: [0] -> [0, 1, 2]" in err
    assert not out.exists() and sorted(p.name for p in parts.iterdir()) == ["manifest.json"]


def test_unreachable_scheduler_is_a_runtime_failure(run_cli, write_spec, tmp_path):
    with dask.config.set({"distributed.comm.timeouts.connect": "1s"}):
        status, _, err = run_cli("sweep", write_spec(), "-o", tmp_path / "x.nc", "--scheduler", "tcp://127.0.0.1:9")
    assert status == 1 and len(err.strip().splitlines()) == 1 and "Traceback" not in err


# Property tests: generated specs and arguments run or are refused (exit 2), nothing else.

QUICK_PROPERTY = settings(max_examples=25, deadline=None,
                          suppress_health_check=[HealthCheck.function_scoped_fixture])

def toml_value(value):
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return f'"{value}"'
    if isinstance(value, list):
        return "[" + ", ".join(map(toml_value, value)) + "]"
    return repr(value)


VALID = {
    "model": ["lattice", "offlattice"],
    "dim": [2, 3],
    "stickiness": [1.0, 0.3],
    "neighbours": [0, 8],
    "seed_shape": ["point", "block", "line"],
    "launch": ["circle", "box"],
    "launch_factor": [1.0, 1.5],
    "kill_factor": [0.0, 3.0],
    "jumps": [True, False],
    "step": [0.0, 0.5],
    "walkers": [1, 3],
    "max_steps": [0, 200],
}
INVALID = {"model": ["hex"], "dim": [1, 2.5], "stickiness": [0.0, "x"], "neighbours": [5],
           "seed_shape": ["ring"], "launch_factor": [0.5], "kill_factor": [1.0], "jumps": [1],
           "step": [-0.1], "walkers": [0], "max_steps": [-3]}


def mostly_valid(valid, invalid=()):
    """Valid values three times as often as invalid ones."""
    return st.sampled_from(list(valid) * 3 + list(invalid))


def parameter(key):
    value = mostly_valid(VALID[key], INVALID.get(key, ()))
    return st.one_of(value, st.lists(value, min_size=1, max_size=2))


specs = st.fixed_dictionaries({
    "grid": st.fixed_dictionaries({
        "size": st.lists(mostly_valid([0, 12, 16], [3, -1]), min_size=1, max_size=2),
        "n_particles": st.lists(mostly_valid([1, 5, 30], [0, 2.5]), min_size=1, max_size=2),
        "seeds": mostly_valid([1, 2, [0, 5]], [0, [-1], "two"]),
    }),
    "model": st.sets(st.sampled_from([*VALID, "colour"]), max_size=2).flatmap(
        lambda keys: st.fixed_dictionaries({
            k: parameter(k) if k in VALID else st.just("red") for k in sorted(keys)})),
    "run": st.fixed_dictionaries({"root_seed": mostly_valid([0, 7], [-1])}),
})


@QUICK_PROPERTY
@given(spec=specs)
def test_generated_specs_run_or_exit_2(spec, run_cli, tmp_path_factory, dask_cluster):
    folder = tmp_path_factory.mktemp("generated")
    text = "".join(f"[{section}]\n" + "".join(f"{k} = {toml_value(v)}\n" for k, v in table.items())
                   for section, table in spec.items())
    path = folder / "spec.toml"
    path.write_text(text)
    out = folder / "out.nc"
    status, _, err = run_cli("sweep", path, "-o", out, "--scheduler", dask_cluster.scheduler_address)
    assert status in (0, 2), f"{text}\n{err}"
    event(f"exit {status}")
    if status == 2:
        assert len(err.strip().splitlines()) == 1 and "Traceback" not in err
        assert sorted(p.name for p in folder.iterdir()) == ["spec.toml"]
    else:
        store.open_sweep(out).close()


def option_text(key):
    """A command-line value for ``--key``: mostly valid, sometimes not even of the right type."""
    valid = [str(v).lower() for v in VALID.get(key, [0, 3])]
    invalid = [str(v).lower() for v in INVALID.get(key, [-1])] + ["x"]
    return mostly_valid(valid, invalid)


@QUICK_PROPERTY
@given(n=mostly_valid(["1", "40", "4e1"], ["0", "-3", "x", "2.5"]),
       options=st.sets(st.sampled_from([*VALID, "seed", "colour"]), max_size=3).flatmap(
           lambda keys: st.fixed_dictionaries({k: option_text(k) for k in sorted(keys)})))
def test_generated_grow_arguments_run_or_exit_2(n, options, run_cli, tmp_path_factory):
    folder = tmp_path_factory.mktemp("grow")
    argv = ["grow", "-n", n, "-o", folder / "c.nc"]
    for key, value in options.items():
        argv += [f"--{key}", value]
    status, _, err = run_cli(*argv)
    assert status in (0, 2), f"{argv}\n{err}"
    event(f"exit {status}")
    assert (status == 0) == (folder / "c.nc").exists()


def test_grow_shows_progress_on_a_terminal_only_and_what_compiles_in_a_log_too(run_cli, tmp_path, monkeypatch):
    from dlasweep import cli

    bars = []
    real_bar = cli.growth_bar
    monkeypatch.setattr(cli, "growth_bar", lambda *kernel: bars.append(real_bar(*kernel)) or bars[-1])
    status, _, err = run_cli("grow", "-n", "300", "-o", tmp_path / "piped.nc")
    assert status == 0 and err == "" and bars[-1].__class__.__name__ == "nullcontext"
    monkeypatch.setattr(importlib.import_module("dlasweep.growth.cluster"), "compiled",
                        lambda params: params["model"] != "offlattice")
    notice = ("dlasweep grow: compiling the off-lattice 3D kernels, once: one to two minutes "
              "(`dlasweep compile` compiles every model ahead)\n")
    status, _, err = run_cli("grow", "-n", "30", "--model", "offlattice", "--dim", "3", "-o", tmp_path / "log.nc")
    assert status == 0 and err == notice and bars[-1].__class__.__name__ == "nullcontext"
    monkeypatch.setattr(sys.stderr, "isatty", lambda: True)
    status, _, err = run_cli("grow", "-n", "300", "--model", "offlattice", "-o", tmp_path / "shown.nc")
    assert status == 0 and err.startswith("dlasweep grow: compiling the off-lattice 2D kernels, once: about a minute "
                                          "(`dlasweep compile` compiles every model ahead)\n")
    assert bars[-1].total == 300 and bars[-1].n == 300  # the bar followed the growth to the end
    with store.open_sweep(tmp_path / "shown.nc") as ds:
        np.testing.assert_array_equal(ragged.cluster_points(ds, 0), dla.grow(300, 0, model="offlattice").points)


def test_the_installed_command_exits_with_main_status_and_complete_output(tmp_path):
    """``run`` skips the interpreter's teardown: the status, the output and the file must survive it."""
    out = tmp_path / "c.nc"
    done = subprocess.run([sys.executable, "-m", "dlasweep", "grow", "-n", "300", "--seed", "2", "-o", str(out)],
                          capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    assert str(out) in done.stdout
    with dla.open_sweep(out) as ds:
        assert ds.sizes["particle"] == 300
    bad = subprocess.run([sys.executable, "-m", "dlasweep", "grow", "-n", "0", "-o", str(tmp_path / "d.nc")],
                         capture_output=True, text=True, timeout=600)
    assert bad.returncode == 2 and bad.stderr.count("\n") == 1 and "-n" in bad.stderr
    assert not (tmp_path / "d.nc").exists()


def test_a_reader_that_leaves_ends_the_command_quietly(tiny_sweep, monkeypatch, capsys):
    class Closed(io.StringIO):
        def write(self, text):
            raise BrokenPipeError(32, "Broken pipe")

    monkeypatch.setattr(sys, "stdout", Closed())
    assert cli.main(["info", str(tiny_sweep[3] / "tiny.nc")]) == 141
    assert capsys.readouterr().err == ""


# Nothing lost, nothing stale (issue 24, items 8-13) -------------------------

def command(*argv, cwd=None):
    """The real command in a subprocess: (exit status, stdout, stderr)."""
    done = subprocess.run([sys.executable, "-m", "dlasweep", *map(str, argv)], capture_output=True, text=True,
                          timeout=600, cwd=cwd)
    return done.returncode, done.stdout, done.stderr


def refused(status, out, err, *named) -> bool:
    """Exit 2 with one line on stderr that holds every one of ``named``, nothing on stdout."""
    lines = err.strip().splitlines()
    return status == 2 and out == "" and len(lines) == 1 and all(name in lines[0] for name in named)


@pytest.mark.parametrize("name", ["out.nc", "out.png"])
def test_grow_refuses_an_existing_output_unless_force(name, tmp_path):
    out = tmp_path / name
    out.write_text("precious")
    result = command("grow", "-n", "50", "-o", out)
    assert refused(*result, f"-o {out}: exists", "--force"), result
    assert out.read_text() == "precious" and files_under(tmp_path) == {Path(name)}
    status, _, err = command("grow", "-n", "50", "-o", out, "--force")
    assert status == 0, err
    assert out.read_bytes() != b"precious" and files_under(tmp_path) == {Path(name)}


def test_grow_refuses_a_link_to_nowhere_as_an_existing_output(run_cli, tmp_path):
    out = tmp_path / "out.nc"
    out.symlink_to(tmp_path / "elsewhere.nc")
    assert refused(*run_cli("grow", "-n", "50", "-o", out), f"-o {out}: exists")
    assert out.is_symlink() and files_under(tmp_path) == {Path("out.nc")}


@pytest.mark.parametrize("options, named", [([], "--force"), (["--resume"], "nothing left to resume"),
                                            (["--resume"], "--force")])
def test_sweep_refuses_an_existing_output(options, named, write_spec, tmp_path):
    out = tmp_path / "out.nc"
    out.write_text("precious")
    spec = write_spec()
    before = files_under(tmp_path)
    result = command("sweep", spec, "-o", out, *options)
    assert refused(*result, f"-o {out}: exists", named), result
    assert files_under(tmp_path) == before and out.read_text() == "precious"


def test_sweep_with_force_replaces_the_output(run_cli, write_spec, tmp_path, dask_cluster):
    out = tmp_path / "out.nc"
    out.write_text("precious")
    status, _, err = run_cli("sweep", write_spec(), "-o", out, "--force", "--scheduler", dask_cluster.scheduler_address)
    assert status == 0, err
    with store.open_sweep(out) as ds:
        assert ds.sizes["cluster"] == 12


def test_a_report_replaces_an_earlier_report_whole(tiny_sweep, run_cli, write_spec, tmp_path, dask_cluster):
    folder = tmp_path / "report"
    assert run_cli("report", tiny_sweep[3] / "tiny.nc", "-o", folder)[0] == 0
    first = {p.name for p in folder.iterdir()}
    bare = tmp_path / "bare.nc"  # no positions stored: no gallery, no diffusion times
    spec = write_spec(TINY_SPEC.replace("root_seed = 12345", 'root_seed = 12345\nstore_clusters = "none"'))
    assert run_cli("sweep", spec, "-o", bare, "--scheduler", dask_cluster.scheduler_address)[0] == 0
    status, out, err = command("report", bare, "-o", folder)
    assert status == 0, err
    second = {p.name for p in folder.iterdir()}
    assert {"gallery.png", "diffusion_times.png"} <= first - second and second <= report_files()
    assert "bare.nc -o " in (folder / "report.md").read_text()  # the second report's, whole


@pytest.mark.parametrize("foreign", ["notes.txt", "run2"])
def test_a_report_folder_holding_other_files_is_refused(foreign, tiny_sweep, tmp_path):
    folder = tmp_path / "report"
    folder.mkdir()
    (folder / "summary.md").write_text("mine")
    (folder / foreign).mkdir() if "." not in foreign else (folder / foreign).write_text("mine")
    before = files_under(tmp_path)
    result = command("report", tiny_sweep[3] / "tiny.nc", "-o", folder)
    assert refused(*result, f"-o {folder}: holds {foreign}", "not a report's"), result
    assert files_under(tmp_path) == before and (folder / "summary.md").read_text() == "mine"


@pytest.mark.parametrize("what", ["report", "info"])
def test_a_folder_given_as_a_dataset_is_named_a_folder(what, tmp_path):
    (tmp_path / "results").mkdir()
    result = command(what, tmp_path / "results")
    assert refused(*result, f"{tmp_path / 'results'}: is a folder, not a netCDF file"), result
    assert files_under(tmp_path) == {Path("results")}


def make_plan(target) -> list:
    """The commands the Makefile runs for ``target``, each split into words (``make -n``: nothing runs)."""
    if shutil.which("make") is None:
        pytest.skip("no make here")
    plan = subprocess.run(["make", "-n", "-C", str(ROOT), target], capture_output=True, text=True, check=True)
    return [line.split() for line in plan.stdout.splitlines() if "dlasweep" in line]


def test_make_sweep_writes_only_what_git_ignores():
    if subprocess.run(["git", "-C", str(ROOT), "rev-parse"], capture_output=True).returncode:
        pytest.skip("not a git checkout")
    outputs = [words[words.index("-o") + 1] for words in make_plan("sweep")]
    assert outputs == ["results/quick.nc", "results/quick"]  # the test knows which is the file, which the folder
    written = [outputs[0], f"{outputs[0]}.parts/manifest.json", f"{outputs[0]}.parts/part-0.npz",
               *(f"{outputs[1]}/{name}" for name in report_files())]
    for path in written:
        assert subprocess.run(["git", "-C", str(ROOT), "check-ignore", "-q", path]).returncode == 0, path
    assert subprocess.run(["git", "-C", str(ROOT), "ls-files", "--error-unmatch", "results/examples/quick/report.md"],
                          capture_output=True).returncode == 0  # the committed example


def test_make_sweep_resumes_an_interrupted_run_and_replaces_a_finished_one(run_cli, write_spec, tmp_path,
                                                                           dask_cluster, monkeypatch):
    words = next(words for words in make_plan("sweep") if "sweep" in words[1:2])
    options = [w for w in words[2:] if w.startswith("--")]  # not the spec, nor -o and its file
    out = tmp_path / "quick.nc"
    sweep_again = ["sweep", write_spec(), "-o", out, *options, "--scheduler", dask_cluster.scheduler_address]
    interrupt_after_a_part(monkeypatch)
    assert run_cli(*sweep_again)[0] == 130 and Path(f"{out}.parts").is_dir()
    monkeypatch.undo()
    status, _, err = run_cli(*sweep_again)
    assert status == 0, err
    assert not Path(f"{out}.parts").exists()
    status, _, err = run_cli(*sweep_again)
    assert status == 0, err


def interrupt_after_a_part(monkeypatch) -> list:
    """Make Ctrl-C come when a sweep would save its second part; return the keys of the clusters saved."""
    written = []
    real_write = Parts.write

    def write(self, results):
        if written:
            raise KeyboardInterrupt
        real_write(self, results)
        written.extend(results)

    monkeypatch.setattr(Parts, "write", write)
    return written


def test_an_interrupt_says_how_many_finished_clusters_are_kept(run_cli, write_spec, tmp_path, dask_cluster,
                                                               monkeypatch):
    out = tmp_path / "tiny.nc"
    written = interrupt_after_a_part(monkeypatch)
    status, _, err = run_cli("sweep", write_spec(), "-o", out, "--scheduler", dask_cluster.scheduler_address)
    assert status == 130
    kept = Parts(Path(f"{out}.parts"))
    assert written and kept.n_finished == len(written) == sum(kept.finished(key) for key in written)
    clusters = "1 finished cluster" if len(written) == 1 else f"{len(written)} finished clusters"
    assert err.strip().splitlines()[-1] == (f"dlasweep sweep: interrupted; {clusters} kept in {out}.parts, "
                                            "continue with --resume")


def test_an_interrupt_before_any_cluster_finished_says_nothing_is_kept(tmp_path):
    spec = tmp_path / "big.toml"
    spec.write_text(TINY_SPEC.replace("size = [0, 24]", "size = [0]").replace("n_particles = [20, 60, 150]",
                                                                              "n_particles = [3000000]")
                    .replace("seeds = 3", "seeds = 1").replace("stickiness = [1.0, 0.5]", "stickiness = 1.0"))
    out, parts = tmp_path / "big.nc", tmp_path / "big.nc.parts"
    # SIGINT as Ctrl-C sends it; a shell starts a background job with SIGINT ignored, which the child would inherit.
    child = subprocess.Popen([sys.executable, "-m", "dlasweep", "sweep", str(spec), "-o", str(out)], text=True,
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                             preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    try:
        start = time.monotonic()
        while not parts.exists():  # the sweep has started: its one cluster takes a minute
            assert child.poll() is None and time.monotonic() - start < 300, child.stderr.read()
            time.sleep(0.05)
        child.send_signal(signal.SIGINT)
        _, err = child.communicate(timeout=30)
    finally:
        child.kill()
    assert child.returncode == 130, err
    assert err.strip().splitlines() == ["dlasweep sweep: interrupted; no cluster had finished, nothing is kept"]
    assert files_under(tmp_path) == {Path("big.toml")}


def test_resume_of_a_complete_sweep_has_nothing_to_do(tiny_sweep, tmp_path, run_cli):
    # A job script that reruns its sweep after a preemption ends green; before, this was refused (exit 2).


    _, _, _, folder = tiny_sweep
    out = tmp_path / "tiny.nc"
    shutil.copy(folder / "tiny.nc", out)
    with store.open_sweep(out) as ds:
        assert ds.attrs["dlasweep_format"] == FORMAT
    spec = tmp_path / "spec.toml"
    spec.write_text(TINY_SPEC)
    before = files_under(tmp_path), out.stat().st_mtime_ns
    assert run_cli("sweep", spec, "-o", out, "--resume") == (0, f"{out}: complete, nothing to do\n", "")
    assert (files_under(tmp_path), out.stat().st_mtime_ns) == before
    spec.write_text(TINY_SPEC.replace("seeds = 3", "seeds = 4"))
    status, stdout, err = run_cli("sweep", spec, "-o", out, "--resume")
    assert status == 2 and stdout == "" and len(err.strip().splitlines()) == 1
    assert f"-o {out}: exists and is not this spec's complete result (grid.seeds: [0, 1, 2] -> [0, 1, 2, 3]); " \
           "nothing left to resume; pass --force to replace it" in err
    assert (files_under(tmp_path), out.stat().st_mtime_ns) == before


def test_init_writes_a_shipped_spec_and_lists_them(tmp_path, run_cli, monkeypatch):
    from dlasweep.sweep import examples
    from dlasweep.sweep.spec import load_spec

    monkeypatch.chdir(tmp_path)
    status, listed, err = run_cli("init", "--list")
    assert status == 0 and err == ""
    assert [line.split()[0] for line in listed.splitlines()] == examples.names()
    assert {"quick", "tradeoff", "dimension", "dimension3d", "branching"} <= set(examples.names())
    for name in examples.names():
        assert 20 <= len(examples.description(name)) <= 100, name  # the first line, a comment: one short line
        assert f"{name}  " in listed and examples.description(name) in listed
        assert run_cli("init", name, "-o", f"my-{name}.toml")[0] == 0
        assert (tmp_path / f"my-{name}.toml").read_text() == examples.text(name)
        load_spec(tmp_path / f"my-{name}.toml")  # each one runs as written
    assert run_cli("init", "quick")[0] == 0 and (tmp_path / "quick.toml").exists()  # default: NAME.toml
    before = files_under(tmp_path)
    for argv, message in ((["nosuch"], "dlasweep init: NAME: 'nosuch' is not a shipped spec; choose one of "
                                       + ", ".join(examples.names())),
                          (["quick", "-o", "quick.toml"], "-o quick.toml: exists; pass --force to replace it"),
                          ([], "NAME: missing; choose one of"), (["--list", "quick"], "--list: takes no NAME")):
        status, stdout, err = run_cli("init", *argv)
        assert status == 2 and stdout == "" and len(err.strip().splitlines()) == 1 and message in err, err
    assert files_under(tmp_path) == before
    (tmp_path / "quick.toml").write_text("edited")
    assert run_cli("init", "quick", "--force")[0] == 0
    assert (tmp_path / "quick.toml").read_text() == examples.text("quick")


def test_no_spec_stays_in_workflows():
    # One copy of each example: the package's. A spec added to workflows/ ships once moved (docs/spec.md).
    stray = sorted(p.name for p in (ROOT / "workflows").glob("*.toml"))
    assert stray == [], f"{stray}: git mv them into dlasweep/sweep/specs/ to ship them"


def _helps():
    """The help of ``dlasweep`` and of each of its commands, by command."""
    parser = cli._parser()
    commands = next(a.choices for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return {"": parser.format_help(), **{name: sub.format_help() for name, sub in commands.items()}}


def test_every_command_has_a_one_line_description_and_examples():
    helps = _helps()
    assert {"grow", "export", "sweep", "slurm", "init", "report", "info", "bench"} <= set(helps)
    for name, text in helps.items():
        description = text.split("\n\n")[1]
        assert description.endswith(".") and len(description.splitlines()) <= 2, (name, description)
        examples = text.partition("examples:\n")[2].splitlines()
        assert examples and all(line.startswith("  dlasweep ") for line in examples[:1]), (name, text)
        # no tracker numbers, no repository paths a pip user does not have, no generic V for a value
        assert not re.search(r"\bissues? ?\d|README|workflows/|DESIGN| V\b", text), (name, text)
    assert "docs/spec.md" in helps["sweep"] and "dlasweep init" in helps["sweep"]
    assert "[--jumps | --no-jumps]" in helps["grow"] and "--kill-factor FACTOR" in helps["grow"]


def test_a_boolean_parameter_is_a_switch(tmp_path, run_cli):
    for switch, value in (("--no-jumps", False), ("--jumps", True)):
        out = tmp_path / f"{switch}.nc"
        assert run_cli("grow", "-n", "30", switch, "-o", out)[0] == 0
        with store.open_sweep(out) as ds:
            assert bool(ds["jumps"]) is value
    status, _, err = run_cli("grow", "-n", "30", "--jumps", "false", "-o", tmp_path / "x.nc")
    assert status == 2 and "unrecognized arguments: false" in err
