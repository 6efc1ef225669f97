"""Tables kept on disk (``kernels.stored.kept_on_disk``) are the tables the function computes, and no older."""

import importlib
import shutil
import sys

import numpy as np
import pytest

from dlasweep.kernels import lattice

SOURCE = '''
import numpy as np
from dlasweep.kernels.stored import kept_on_disk
CALLS = []

@kept_on_disk
def tables(n):
    CALLS.append(n)
    return np.arange(n, dtype=np.int8), np.full(n, VALUE)
'''


@pytest.mark.parametrize("dim, moore", [(2, False), (2, True), (3, False), (3, True)])
def test_kept_exit_tables_equal_computed_ones(dim, moore):
    kept, computed = lattice.exit_tables(dim, moore), lattice.exit_tables.__wrapped__(dim, moore)
    assert len(kept) == len(computed)
    for a, b in zip(kept, computed):
        assert a.dtype == b.dtype
        np.testing.assert_array_equal(a, b)


def load(folder, value):
    (folder / "tabled.py").write_text(SOURCE.replace("VALUE", repr(value)))
    sys.modules.pop("tabled", None)
    importlib.invalidate_caches()
    return importlib.import_module("tabled")


def test_tables_are_computed_once_then_read_until_the_source_changes(tmp_path, monkeypatch):
    monkeypatch.syspath_prepend(str(tmp_path))
    first = load(tmp_path, 1.5)
    a = first.tables(3)
    assert first.CALLS == [3] and len(list((tmp_path / "__pycache__").glob("tabled.tables.*.npz"))) == 1
    again = load(tmp_path, 1.5)  # a new process, as far as the tables go
    b = again.tables(3)
    assert again.CALLS == [] and all(np.array_equal(x, y) and x.dtype == y.dtype for x, y in zip(a, b))
    edited = load(tmp_path, 2.5)
    assert edited.tables(3)[1].tolist() == [2.5] * 3 and edited.CALLS == [3]
    assert load(tmp_path, 2.5).tables(4)[0].tolist() == [0, 1, 2, 3]  # other arguments, other tables


def test_a_damaged_or_unwritable_store_only_costs_the_computation(tmp_path, monkeypatch):
    monkeypatch.syspath_prepend(str(tmp_path))
    load(tmp_path, 1.0).tables(2)
    (kept,) = (tmp_path / "__pycache__").glob("tabled.tables.*.npz")
    kept.write_bytes(b"not a zip")
    module = load(tmp_path, 1.0)
    assert module.tables(2)[1].tolist() == [1.0, 1.0] and module.CALLS == [2]
    shutil.rmtree(tmp_path / "__pycache__")
    (tmp_path / "__pycache__").write_text("a file where the folder would be: nothing can be kept")
    module = load(tmp_path, 1.0)
    assert module.tables(2)[0].tolist() == [0, 1] and module.CALLS == [2]
    assert load(tmp_path, 1.0).tables(2)[1].tolist() == [1.0, 1.0]
