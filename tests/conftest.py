"""Shared fixtures: small specs, an in-process dask cluster, a CLI runner, the CF tools."""

from __future__ import annotations

import ctypes.util
import os
import re
import shutil
import subprocess
import sys
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

FIRST_FILES = ("test_wheel.py", "test_harmonic.py", "test_measure.py", "test_docs.py", "test_slurm.py",
               "test_invariants.py", "test_laws.py")
"""Run first, longest first: the longest files (a fresh venv that compiles every kernel again, about
5 minutes; the harmonic measure's frozen-cluster kernels of every model, compiled; the box counts against
their references, 3; the documentation built twice, its lesson compiling the kernels; the SLURM cluster,
2; every variant grown to 2e4; the growth laws' variants), which ``make test``
gives one worker each while the other takes the rest; last, one ran on while the other idled. The
order holds because ``make test`` keeps it (``--no-loadscope-reorder``): by default xdist sends the
files with the most tests first, and the wheel's four went last."""


def pytest_collection_modifyitems(items):
    rank = {name: i for i, name in enumerate(FIRST_FILES)}
    items.sort(key=lambda item: rank.get(item.path.name, len(FIRST_FILES)))  # stable: each file keeps its order


def colours_shown(path) -> dict:
    """The colours a picture shows and how many pixels each covers, white and greys (text, axes) left out.

    A PNG is read as it is; an SVG by the images it embeds (a lattice cluster is one).
    """
    import base64
    import io
    import re

    import numpy as np
    from PIL import Image

    path = Path(path)
    if path.suffix == ".svg":
        embedded = re.findall(r'xlink:href="data:image/png;base64,([^"]*)"', path.read_text())
        pictures = [io.BytesIO(base64.b64decode("".join(data.split()))) for data in embedded]
    else:
        pictures = [path]
    shown = {}
    for picture in pictures:
        rgb = np.asarray(Image.open(picture).convert("RGB")).reshape(-1, 3).astype(int)
        coloured = rgb[rgb.max(axis=1) > rgb.min(axis=1)]
        for colour, count in zip(*np.unique(coloured, axis=0, return_counts=True)):
            shown[tuple(colour)] = shown.get(tuple(colour), 0) + int(count)
    return shown


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
    from dlasweep.data.schema import SCIENCE

    names = [*SCIENCE, "cluster_particles", "x", "y", "diffusion_time"]
    return ds[names].drop_attrs(deep=False).load()


def files_under(path: Path) -> set:
    """Every file and folder below ``path``, relative to it."""
    return {p.relative_to(path) for p in Path(path).rglob("*")}


@pytest.fixture(scope="session")
def reference(tmp_path_factory, dask_client):
    """The tiny sweep, run once on two in-process workers (for the sweep's and the parts' tests)."""
    import dlasweep as dla
    from dlasweep.sweep.spec import parse_spec

    out = tmp_path_factory.mktemp("reference") / "tiny.nc"
    ds = dla.run_sweep(parse_spec(TINY_SPEC), client=dask_client, out=out)
    yield ds
    ds.close()


class Interrupt(BaseException):
    """Stands for a kill: nothing in the sweep may catch it."""


def interrupt_after(monkeypatch, n_clusters):
    """Make the process die at the first part that would bring the saved clusters past n, as a kill would."""
    from dlasweep.sweep.parts import Parts

    written = []
    real_write = Parts.write

    def write(self, results):
        if len(written) + len(results) > n_clusters:
            raise Interrupt
        real_write(self, results)
        written.extend(results)

    monkeypatch.setattr(Parts, "write", write)
    return written


def finished_clusters(out):
    """The keys of the clusters finished in the parts of ``out``."""
    from dlasweep.sweep.parts import Parts

    parts = Parts(Path(f"{out}.parts"))
    return [key for key in parts.where if parts.finished(key)]


def progress_lines(text) -> list:
    """The finished counts the progress lines in ``text`` give."""
    return [int(n) for n in re.findall(r"^\w+ \d\d:\d\d:\d\d: (\d+)/\d+ clusters finished", text, re.M)]


@pytest.fixture
def replicate_1_fails(monkeypatch):
    """Make growing replicate 1 of every configuration raise, as a bug in a kernel would."""
    from dlasweep.sweep import task as worker

    real_grow, real_grow_many = worker.grow, worker.grow_many

    def grow(n, seed, **kwargs):
        if seed.spawn_key[-1] == 1:
            raise RuntimeError("simulated failure")
        return real_grow(n, seed, **kwargs)

    def grow_many(n, seeds, **kwargs):
        if any(seed.spawn_key[-1] == 1 for seed in seeds):
            raise RuntimeError("simulated failure")
        return real_grow_many(n, seeds, **kwargs)

    monkeypatch.setattr(worker, "grow", grow)
    monkeypatch.setattr(worker, "grow_many", grow_many)


_APT_UPDATED = []


def apt_install(packages, present, what):
    """Install Debian ``packages`` with apt (as root) unless ``present()``; skip the test, in one line,
    where that cannot be done. ``apt-get update`` runs once per session; another apt holding the
    lock is waited for."""
    if present():
        return
    if not sys.platform.startswith("linux") or shutil.which("apt-get") is None:
        pytest.skip(f"{what} missing and no apt-get to install {' '.join(packages)}")
    if os.geteuid() != 0:
        pytest.skip(f"{what} missing; installing {' '.join(packages)} with apt needs root")
    env = dict(os.environ, DEBIAN_FRONTEND="noninteractive")
    lock = ["-o", "DPkg::Lock::Timeout=600"]
    commands = [["apt-get", *lock, "update", "-q"]] if not _APT_UPDATED else []
    for command in [*commands, ["apt-get", *lock, "install", "-y", "-q", "--no-install-recommends", *packages]]:
        done = subprocess.run(command, check=False, env=env, capture_output=True, text=True)
        if done.returncode:
            # A mirror outage must not block the rest of the suite; the reason is shown.
            lines = [line.strip() for line in (done.stderr or done.stdout).splitlines() if line.strip()]
            pytest.skip(f"{what} missing: {' '.join(command)} failed: {lines[-1] if lines else 'no output'}")
        _APT_UPDATED.append(True)
    if not present():
        pytest.skip(f"{what} still missing after installing {' '.join(packages)}")


@pytest.fixture(scope="session")
def cfchecks():
    """cfchecker's ``cfchecks`` module, with the udunits2 C library it loads (Debian libudunits2-0)."""
    apt_install(["libudunits2-0"], lambda: ctypes.util.find_library("udunits2") is not None, "the udunits2 library")
    from cfchecker import cfchecks

    return cfchecks


@pytest.fixture(scope="session")
def ncdump():
    """The path of ``ncdump`` (Debian netcdf-bin)."""
    apt_install(["netcdf-bin"], lambda: shutil.which("ncdump") is not None, "ncdump")
    return shutil.which("ncdump")
