"""The wheel's build: setuptools (configured in pyproject.toml), and the kernels compiled into the package.

After the package's files are copied into the build, ``dlasweep.sweep.precompile`` grows and measures a
small cluster of each model there, so that numba's cache beside the modules (their ``__pycache__``) holds
the compiled kernels, and the lattice's exit tables their computed file, both shipped in the wheel: a
user's first grow loads them instead of compiling for tens of seconds. numba keys that cache by the
content of each module, the numba version and the processor, so an install on the machine that built the
wheel (``pip install .``) loads it, and any other compiles as before. ``DLASWEEP_PRECOMPILE`` names the
models compiled (``precompile.build``): unset or ``all``, every one; a comma-separated list of names
(``lattice-2d,offlattice-2d``); ``none``. An editable install compiles nothing here: its first run
compiles into the tree, as a contributor's does.
"""

import os
import pathlib
import shutil
import subprocess
import sys

from setuptools import setup
from setuptools.command.build_py import build_py


class BuildWithKernels(build_py):
    """``build_py`` that then compiles the kernels into the built package (the module's docstring)."""

    def run(self):
        super().run()
        if self.editable_mode or self.dry_run:
            return
        for stale in pathlib.Path(self.build_lib, "dlasweep").rglob("__pycache__"):  # an earlier build's
            shutil.rmtree(stale)
        env = {key: value for key, value in os.environ.items() if key != "NUMBA_CACHE_DIR"}
        env["PYTHONDONTWRITEBYTECODE"] = "1"
        subprocess.run([sys.executable, "-c", "import os; from dlasweep.sweep.precompile import build; "
                        "build(os.environ.get('DLASWEEP_PRECOMPILE', 'all'))"], env=env, cwd=self.build_lib, check=True)


setup(cmdclass={"build_py": BuildWithKernels})
