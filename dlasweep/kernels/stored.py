"""Tables that kernels read, computed once per installation and kept on disk, as numba keeps its machine code."""

from __future__ import annotations

import contextlib
import functools
import hashlib
import inspect
import os
import zipfile
from pathlib import Path

import numpy as np


def kept_on_disk(func):
    """``func`` (arrays from a few hashable arguments), its results kept in ``__pycache__`` beside its module.

    The key is the arguments, the module's source and numpy's version: an
    edit of the module or a new numpy computes the tables again, so a kept
    table is always the one ``func`` would return here. Where the folder
    cannot be written (a read-only install) they are computed in each
    process, as without this. Computed in every process, the lattice's exit
    tables would take longer than a sweep's small clusters take to grow
    (docs/performance.md).
    """
    module = Path(inspect.getsourcefile(func))

    @functools.cache
    @functools.wraps(func)
    def kept(*args):
        key = hashlib.sha256(module.read_bytes() + repr((args, np.__version__)).encode()).hexdigest()[:20]
        path = module.parent / "__pycache__" / f"{module.stem}.{func.__name__}.{key}.npz"
        with contextlib.suppress(OSError, ValueError, KeyError, zipfile.BadZipFile), np.load(path) as stored:
            return tuple(stored[f"{i}"] for i in range(len(stored.files)))
        tables = func(*args)
        with contextlib.suppress(OSError):
            path.parent.mkdir(exist_ok=True)
            part = path.with_name(f".{path.name}.{os.getpid()}")
            try:
                with open(part, "wb") as f:
                    np.savez(f, **{f"{i}": table for i, table in enumerate(tables)})
                os.replace(part, path)  # whole or absent, when processes race
            finally:
                part.unlink(missing_ok=True)
        return tables

    return kept
