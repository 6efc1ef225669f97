"""What users install is the wheel: it is built from this tree, holds every module of the package and the
kernels compiled by its build, and, installed into a fresh venv outside the tree, grows its first cluster
without compiling and runs every documented command.

The fresh venv takes its dependencies from the package registry, as a user's ``pip install`` would
(about a minute here). The build compiles the kernels of the one model the commands grow
(``DLASWEEP_PRECOMPILE``, setup.py): each model adds about a minute to the build, and the tree's tests
compile every model.
"""

import os
import subprocess
import sys
import tarfile
import venv
import zipfile

import pytest

from conftest import ROOT, TINY_SPEC

pytestmark = pytest.mark.slow

PACKAGE = ROOT / "dlasweep"
COMPILED = ("lattice-2d",)
"""The models whose kernels the wheel built here carries (``DLASWEEP_PRECOMPILE``)."""


def _sources() -> set:
    """Every file of the package in the tree, as paths relative to the tree's root."""
    return {str(p.relative_to(ROOT)) for p in PACKAGE.rglob("*")
            if p.is_file() and "__pycache__" not in p.parts and p.suffix not in (".pyc", ".nbi", ".nbc")}


@pytest.fixture(scope="module")
def dists(tmp_path_factory):
    """The wheel and the sdist built from this tree (``python -m build``, isolated as pip would)."""
    out = tmp_path_factory.mktemp("dist")
    done = subprocess.run([sys.executable, "-m", "build", "--wheel", "--sdist", "--outdir", str(out), str(ROOT)],
                          capture_output=True, text=True, timeout=600,
                          env={**os.environ, "DLASWEEP_PRECOMPILE": ",".join(COMPILED)})
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]
    (wheel,) = out.glob("dlasweep-*.whl")
    (sdist,) = out.glob("dlasweep-*.tar.gz")
    return wheel, sdist


def test_the_wheel_holds_every_file_of_the_package_and_its_compiled_kernels(dists):
    wheel, _ = dists
    with zipfile.ZipFile(wheel) as archive:
        shipped = {name for name in archive.namelist() if name.startswith("dlasweep/")}
    compiled = {name for name in shipped if "/__pycache__/" in name}
    assert shipped - compiled == _sources()
    # numba's cache beside the modules: the lattice growth kernel's index and code, and the measures'; the
    # lattice's exit tables as computed (``kernels.lattice.exits``)
    names = " ".join(compiled)
    assert all(f"/__pycache__/{name}" in names for name in ("lattice_growth._grow-", "shape.", "exits.exit_tables"))
    assert {name.rsplit(".", 1)[1] for name in compiled} == {"nbi", "nbc", "npz"}


def test_the_sdist_holds_every_file_of_the_package_and_its_tests(dists):
    _, sdist = dists
    with tarfile.open(sdist) as archive:
        shipped = {name.split("/", 1)[1] for name in archive.getnames() if "/" in name}
    assert _sources() <= shipped
    assert {"pyproject.toml", "setup.py", "README.md"} <= shipped  # setup.py: the build compiles the kernels


@pytest.fixture(scope="module")
def installed(dists, tmp_path_factory):
    """A fresh venv, outside the tree, with the wheel and its ``slurm`` extra installed: its ``dlasweep``."""
    wheel, _ = dists
    home = tmp_path_factory.mktemp("user")
    venv.create(home / "venv", with_pip=True)
    python = home / "venv" / "bin" / "python"
    done = subprocess.run([str(python), "-m", "pip", "install", "-q", f"{wheel}[slurm]"],
                          capture_output=True, text=True, timeout=900)
    assert done.returncode == 0, done.stderr[-3000:]
    return home / "venv" / "bin" / "dlasweep", home


def _run(installed, *argv):
    command, home = installed
    done = subprocess.run([str(command), *map(str, argv)], cwd=home, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, f"{argv}: {done.stdout[-2000:]}{done.stderr[-3000:]}"
    return done.stdout


def test_the_installed_wheel_imports_from_site_packages_not_the_tree(installed):
    command, home = installed
    python = command.with_name("python")
    where = subprocess.run([str(python), "-c", "import dlasweep.kernels.lattice, dlasweep.kernels.offlattice, "
                            "dlasweep; print(dlasweep.__file__)"], cwd=home, capture_output=True, text=True)
    assert where.returncode == 0, where.stderr
    assert "site-packages" in where.stdout and str(ROOT) not in where.stdout


def test_the_installed_wheel_grows_and_measures_its_first_cluster_without_compiling(installed):
    # numba reports each function it compiles (not those it loads from its cache); the first grow and a
    # sweep's first task (``precompile`` runs one) of the model the wheel carries compile none
    command, home = installed
    count = """
from numba.core import event
import dlasweep as dla
from dlasweep.sweep.precompile import precompile
compiled = []
class Compiles(event.Listener):
    def on_start(self, ev):
        pass
    def on_end(self, ev):
        compiled.append(ev.data["dispatcher"].py_func.__qualname__)
event.register("numba:compile", Compiles())
dla.grow(1000, seed=3)
grown = list(compiled)
precompile("lattice-2d")
print(grown, compiled[len(grown):])
"""
    env = {key: value for key, value in os.environ.items() if key != "NUMBA_CACHE_DIR"}
    done = subprocess.run([str(command.with_name("python")), "-c", count], cwd=home, capture_output=True,
                          text=True, env=env, timeout=600)
    assert done.returncode == 0, done.stderr[-3000:]
    assert done.stdout.split() == ["[]", "[]"], done.stdout[-2000:]


def test_the_installed_wheel_runs_every_documented_command(installed):
    _, home = installed
    assert "grow" in _run(installed, "--help")
    assert "1,000 particles" in _run(installed, "grow", "-n", "1000", "-o", "one.nc")
    assert "300 particles" in _run(installed, "grow", "-n", "300", "-o", "one.png")
    assert "particles: 1000" in _run(installed, "info", "one.nc")
    (home / "tiny.toml").write_text(TINY_SPEC)
    assert "12 clusters" in _run(installed, "sweep", "tiny.toml", "-o", "tiny.nc")
    assert "report written" in _run(installed, "report", "tiny.nc", "-o", "report")
    assert (home / "report" / "dimension_vs_n.png").is_file()
    assert "headline D" in _run(installed, "info", "tiny.nc")
    # the newcomer's path: an example spec from the wheel itself, no clone
    assert "quick" in _run(installed, "init", "--list")
    _run(installed, "init", "quick", "-o", "q.toml")
    assert (home / "q.toml").read_text() == (PACKAGE / "sweep" / "specs" / "quick.toml").read_text()
    assert "16 clusters" in _run(installed, "sweep", "q.toml", "-o", "q.nc")
    # the one model the commands above compiled: each other kernel would add one to three minutes of compiling
    # to the longest test of the suite; their files are imported above, and the tree's tests grow every model
    _run(installed, "bench", "--quick", "--model", "lattice-2d", "-o", "bench")
    assert (home / "bench" / "bench.nc").is_file()
    assert "#SBATCH" in _run(installed, "slurm", "tiny.toml", "-o", "cluster.nc", "--dry-run")
