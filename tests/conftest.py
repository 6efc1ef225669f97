"""Shared fixtures: small specs, an in-process dask cluster, a CLI runner."""

from __future__ import annotations

import os
import textwrap
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

TINY_SPEC = """\
name = "tiny"
[grid]
size = [0, 24]
n_particles = [20, 60, 150]
seeds = 3
[model]
model = "lattice"
dim = 2
stickiness = [1.0, 0.5]
[run]
root_seed = 12345
"""
"""Twelve small clusters: one swept parameter, a bounded and an unbounded box."""


@pytest.fixture
def write_spec(tmp_path):
    """Write spec text (dedented) to a TOML file and return its path."""

    def write(text=TINY_SPEC, name="spec.toml"):
        path = tmp_path / name
        path.write_text(textwrap.dedent(text))
        return path

    return write


@pytest.fixture(scope="session")
def dask_cluster():
    """Two single-threaded workers as threads of this process: quick to start."""
    from distributed import LocalCluster

    with LocalCluster(n_workers=2, threads_per_worker=1, processes=False,
                      dashboard_address=":0") as cluster:
        yield cluster


@pytest.fixture(scope="session")
def dask_client(dask_cluster):
    from distributed import Client

    with Client(dask_cluster) as client:
        yield client


@pytest.fixture
def run_cli(capsys):
    """Call ``dlasweep.cli.main``; return (exit status, stdout, stderr)."""
    from dlasweep.cli import main

    def run(*argv):
        status = main([os.fspath(a) for a in argv])
        out, err = capsys.readouterr()
        return status, out, err

    return run


def science(ds):
    """The variables that must be bit-identical between runs (timings aside), clusters included."""
    from dlasweep.store import SCIENCE

    names = [*SCIENCE, "cluster_particles", "x", "y", "diffusion_time"]
    return ds[names].drop_attrs(deep=False).load()


def files_under(path: Path) -> set:
    """Every file and folder below ``path``, relative to it."""
    return {p.relative_to(path) for p in Path(path).rglob("*")}


@pytest.fixture
def replicate_1_fails(monkeypatch):
    """Make growing replicate 1 of every configuration raise, as a bug in a kernel would."""
    from dlasweep import sweep

    real_grow, real_grow_many = sweep.grow, sweep.grow_many

    def grow(n, seed, **kwargs):
        if seed.spawn_key[-1] == 1:
            raise RuntimeError("simulated failure")
        return real_grow(n, seed, **kwargs)

    def grow_many(n, seeds, **kwargs):
        if any(seed.spawn_key[-1] == 1 for seed in seeds):
            raise RuntimeError("simulated failure")
        return real_grow_many(n, seeds, **kwargs)

    monkeypatch.setattr(sweep, "grow", grow)
    monkeypatch.setattr(sweep, "grow_many", grow_many)
