"""The import contracts of pyproject.toml hold (import-linter), and an import against the flow breaks them.

The contracts are the layers of docs/architecture.md: each subpackage imports only those below it, the
kernels nothing but their jit settings and the parameter table, and each heavy library only through the
layer that owns it. ``lint-imports`` reads them from pyproject.toml; here it runs on the tree, then on a
copy of it with one import added against the flow, which must fail.
"""

import ast
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from conftest import ROOT

LINT_IMPORTS = Path(sys.executable).with_name("lint-imports")


def lint_imports(where: Path) -> subprocess.CompletedProcess:
    """``lint-imports`` on the package under ``where`` (found first on the path: the copy, not the installed tree)."""
    return subprocess.run([str(LINT_IMPORTS), "--no-cache"], cwd=where, capture_output=True, text=True,
                          env={"PYTHONPATH": str(where), "PATH": "/usr/bin:/bin"})


def test_the_tree_keeps_every_contract():
    run = lint_imports(ROOT)
    assert run.returncode == 0, run.stdout + run.stderr
    assert " 0 broken" in run.stdout and "BROKEN" not in run.stdout


@pytest.mark.parametrize("module, line, broken", [
    ("stats/fit.py", "from ..sweep import spec", "dlasweep.stats is not allowed to import dlasweep.sweep"),
    ("kernels/walk.py", "from ..growth import cluster", "dlasweep.kernels is not allowed to import dlasweep.growth"),
    ("data/ragged.py", "import matplotlib", "dlasweep.data is not allowed to import matplotlib"),
    ("reporting/text.py", "import dask", "dlasweep.reporting is not allowed to import dask"),
    ("sweep/spec.py", "import argparse", "dlasweep.sweep is not allowed to import argparse"),
    ("stats/summary.py", "from ..data import netcdf", "dlasweep.stats is not allowed to import dlasweep.data.netcdf"),
])
def test_an_import_against_the_flow_breaks_them(tmp_path, module, line, broken):
    shutil.copytree(ROOT / "dlasweep", tmp_path / "dlasweep", ignore=shutil.ignore_patterns("__pycache__"))
    shutil.copy(ROOT / "pyproject.toml", tmp_path)
    with open(tmp_path / "dlasweep" / module, "a") as source:
        source.write(f"\n{line}  # against the flow\n")
    run = lint_imports(tmp_path)
    assert run.returncode != 0 and broken in run.stdout, run.stdout + run.stderr


def netcdf_calls(path: Path) -> list:
    """Lines of ``path`` that call xarray's netCDF I/O: ``xr.open_dataset`` and its kin, or ``.to_netcdf``."""
    return [f"{path.relative_to(ROOT)}:{node.lineno}" for node in ast.walk(ast.parse(path.read_text()))
            if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute)
            and (node.func.attr == "to_netcdf" or node.func.attr in XARRAY_READS
                 and isinstance(node.func.value, ast.Name) and node.func.value.id in ("xr", "xarray"))]


XARRAY_READS = ("open_dataset", "open_mfdataset", "load_dataset", "open_dataarray", "load_dataarray")


def test_only_data_reads_and_writes_netcdf():
    # xarray's own netCDF I/O is a method call, not an import: import-linter cannot see it, this does.
    package = ROOT / "dlasweep"
    outside = [call for path in package.rglob("*.py") if path.relative_to(package).parts[0] != "data"
               for call in netcdf_calls(path)]
    assert outside == []
    assert len([call for path in (package / "data").rglob("*.py") for call in netcdf_calls(path)]) >= 2
