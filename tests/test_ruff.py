"""The code is clean under ruff as pyproject.toml configures it ([tool.ruff]: pyflakes, pycodestyle, isort,
pyupgrade, numpy; lines to 120), and the configured check does catch what it is there for."""

import subprocess
import sys
from pathlib import Path

from conftest import ROOT

RUFF = Path(sys.executable).with_name("ruff")


def ruff(*args, cwd=ROOT) -> subprocess.CompletedProcess:
    return subprocess.run([str(RUFF), "check", "--no-cache", *args], cwd=cwd, capture_output=True, text=True)


def test_the_code_is_clean():
    run = ruff("dlasweep", "tests", "workflows")
    assert run.returncode == 0, run.stdout + run.stderr


def test_the_configured_rules_catch_their_faults(tmp_path):
    source = tmp_path / "faulty.py"
    source.write_text("import os\nimport numpy as np\n\nx = np.random.rand(3)  # " + "x" * 120 + "\n"
                      "if type(x) == list:\n    pass\n")
    run = ruff("--config", str(ROOT / "pyproject.toml"), str(source), cwd=tmp_path)
    assert run.returncode != 0
    for code in ("F401", "E501", "NPY002", "E721"):
        assert code in run.stdout, (code, run.stdout)
