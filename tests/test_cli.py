"""The command line: bad input exits 2 with one line and writes nothing; sweeps end to end."""

import contextlib
import io
import shutil
import subprocess

import dask
import netCDF4
import numpy as np
import pytest
import xarray as xr
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

import dlasweep as dla
from conftest import TINY_SPEC, files_under, science
from dlasweep import store

BAD_SPEC = TINY_SPEC.replace("stickiness = [1.0, 0.5]", "stickiness = [1.0, 0.0]")


@pytest.mark.parametrize("argv, named", [
    ([], "required"),
    (["frobnicate"], "invalid choice"),
    (["grow", "-o", "a.nc"], "-n"),
    (["grow", "-n", "ten", "-o", "a.nc"], "-n"),
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
    (["sweep", "spec.toml", "-o", "missing/out.nc"], "missing"),
    (["sweep", "spec.toml", "-o", "out.csv"], "out.csv"),
    (["sweep", "spec.toml", "-o", "/proc/out.nc"], "not writable"),
    (["sweep", "spec.toml", "--workers", "0"], "--workers"),
    (["sweep", "spec.toml", "--workers", "two"], "--workers"),
    (["sweep", "spec.toml", "--scheduler", "tcp://127.0.0.1:1", "--workers", "2"], "--workers"),
    (["sweep", "spec.toml", "--scheduler", "x", "--scheduler-file", "s.json"], "--scheduler"),
    (["sweep", "spec.toml", "--scheduler-file", "absent.json"], "--scheduler-file"),
    (["report", "absent.nc"], "absent.nc"),
    (["report", "spec.toml"], "not a readable netCDF"),
    (["report", "spec.toml", "-o", "missing/report"], "missing"),
    (["report", "one.nc"], "one cluster"),
])
def test_bad_input_exits_2_with_one_line_and_writes_nothing(argv, named, run_cli, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "spec.toml").write_text(TINY_SPEC)
    (tmp_path / "bad.toml").write_text(BAD_SPEC)
    store.save(store.cluster_dataset(dla.grow(5, 0), seed=0), tmp_path / "one.nc")
    before = files_under(tmp_path)
    status, out, err = run_cli(*argv)
    assert status == 2, err
    assert len(err.strip().splitlines()) == 1 and named in err, err
    assert "Traceback" not in err and out == ""
    assert files_under(tmp_path) == before


def test_grow_writes_the_cluster(run_cli, tmp_path):
    out = tmp_path / "one.nc"
    status, _, err = run_cli("grow", "-n", "80", "--seed", "3", "--stickiness", "0.5", "--seed-shape", "point",
                             "-o", out)
    assert status == 0, err
    expected = dla.grow(80, 3, stickiness=0.5)
    with store.open_sweep(out) as ds:
        np.testing.assert_array_equal(store.cluster_points(ds, 0), expected.points)
        np.testing.assert_array_equal(ds["diffusion_time"], expected.steps)
        assert float(ds["stickiness"]) == 0.5 and ds.attrs["seed"] == 3


def check_design(ds, spec_text):
    """The dataset as DESIGN.md names it, for the tiny spec."""
    assert ds["box_count"].dims == ("stickiness", "size", "n_particles", "seed", "scale")
    for name in ("n_grown", "status", "radius_gyration", "max_radius", "wall_time", "walk_steps"):
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
        assert var.attrs.get("units") and var.attrs.get("long_name"), name
    assert ds.attrs["Conventions"] == "CF-1.8" and ds.attrs["source"] == f"dlasweep {dla.__version__}"
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


def test_sweep_end_to_end_on_a_running_scheduler(tiny_sweep):
    status, stdout, err, folder = tiny_sweep
    assert status == 0, err
    assert "12 clusters" in stdout
    assert sorted(p.name for p in folder.iterdir()) == ["spec.toml", "tiny.nc"]
    out = folder / "tiny.nc"
    with store.open_sweep(out) as ds:
        check_design(ds, TINY_SPEC)
    with netCDF4.Dataset(out) as nc:
        assert nc["cluster_particles"].sample_dimension == "particle"
    if shutil.which("ncdump"):
        subprocess.run(["ncdump", "-h", str(out)], check=True, capture_output=True)


def test_report_of_the_sweep(tiny_sweep, run_cli, tmp_path):
    status, _, err = run_cli("report", tiny_sweep[3] / "tiny.nc", "-o", tmp_path / "report")
    assert status == 0, err
    assert any((tmp_path / "report").glob("*.png"))


@pytest.mark.parametrize("suffix", [".png", ".svg"])
def test_grow_draws_the_cluster(suffix, run_cli, tmp_path):
    out = tmp_path / f"cluster{suffix}"
    status, _, err = run_cli("grow", "-n", "50", "-o", out)
    assert status == 0, err
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" if suffix == ".png" else b"<svg" in out.read_bytes()


@pytest.mark.slow
def test_sweep_with_the_embedded_cluster_matches(run_cli, write_spec, tmp_path, dask_client):
    out = tmp_path / "tiny.nc"
    status, _, err = run_cli("sweep", write_spec(), "-o", out, "--workers", "2")
    assert status == 0, err
    reference = dla.run_sweep(dla.load_spec(write_spec()), client=dask_client)
    with store.open_sweep(out) as ds:
        xr.testing.assert_identical(science(ds), science(reference))


def test_failed_tasks_exit_1_naming_them(run_cli, write_spec, tmp_path, dask_cluster, monkeypatch):
    from dlasweep import sweep

    def broken(n, seed, **kwargs):
        raise MemoryError("no room")

    monkeypatch.setattr(sweep, "grow", broken)
    out = tmp_path / "tiny.nc"
    status, _, err = run_cli("sweep", write_spec(), "-o", out, "--scheduler", dask_cluster.scheduler_address)
    assert status == 1
    assert "task-0-0-0: MemoryError: no room" in err and len(err.strip().splitlines()) == 1
    with store.open_sweep(out) as ds:
        assert (ds["status"] == store.STATUS_FLAGS.index("error")).all()


def test_resume_with_changed_spec_exits_2(run_cli, write_spec, tmp_path, dask_cluster):
    out = tmp_path / "tiny.nc"
    parts = tmp_path / "tiny.nc.parts"
    parts.mkdir()
    (parts / "manifest.json").write_text('{"digest": "old", "identity": {"grid.seeds": [0]}}')
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
@given(n=mostly_valid(["1", "40"], ["0", "-3", "x", "1e3"]),
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
