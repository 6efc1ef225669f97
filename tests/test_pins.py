"""Hot-loop copies that stay spelled out for speed, each held to its twin.

numba wraps a call that passes arrays in reference counting, and its own
inlining made these loops slower, so a few helpers stand a second time inside
a kernel's hot loop. Each copy is marked ``# >>> name`` ... ``# <<< name`` in
the kernel; a test here holds its text to the twin's body, and another holds
the twin to the general function on many random inputs.
"""

import ast
import inspect
import textwrap

import numpy as np
import pytest

from dlasweep.kernels.offlattice import cells
from dlasweep.kernels.offlattice import grow as offlattice_grow


def body(function):
    """The lines of a function after its docstring and before its final ``return``, dedented."""
    lines = textwrap.dedent(inspect.getsource(function.py_func)).split("\n")
    statements = ast.parse("\n".join(lines)).body[0].body
    if isinstance(statements[0], ast.Expr) and isinstance(statements[0].value, ast.Constant):
        statements = statements[1:]
    if isinstance(statements[-1], ast.Return):
        statements = statements[:-1]
    text = "\n".join(lines[statements[0].lineno - 1:statements[-1].end_lineno])
    return [line.rstrip() for line in textwrap.dedent(text).split("\n")]


def copy(function, name):
    """The lines of ``function`` between ``# >>> name`` and ``# <<< name``, dedented, comments at the mark left out."""
    lines = inspect.getsource(function.py_func).split("\n")
    start = next(i for i, line in enumerate(lines) if line.strip().startswith(f"# >>> {name}"))
    while lines[start + 1].strip().startswith("#"):
        start += 1
    end = next(i for i, line in enumerate(lines) if line.strip() == f"# <<< {name}")
    return [line.rstrip() for line in textwrap.dedent("\n".join(lines[start + 1:end])).split("\n")]


def test_the_walks_map_bound_is_walk_bound_spelled_out():
    assert copy(offlattice_grow._walk, "walk_bound") == body(cells.walk_bound)


def _clustered(rng, dim, line, size, n):
    hub = rng.uniform(0, size, (6, dim)) if line else rng.normal(0, 25, (6, dim))
    pts = hub[rng.integers(0, 6, n)] + rng.normal(0, 6, (n, dim))
    if line:
        pts[:, :-1] %= size
        pts[:, -1] = np.abs(pts[:, -1])
    return pts


@pytest.mark.parametrize("dim, line", [(2, False), (3, False), (2, True), (3, True)])
def test_walk_bound_is_map_dist(dim, line):
    """The walk's bound (levels searched only where the field leaves them
    open) equals ``map_dist``'s full search, and wraps periodic coordinates."""
    rng = np.random.default_rng(3 + dim + 10 * line)
    size = 48 if line else 0
    n = 600 if dim == 2 else 1500
    pts = _clustered(rng, dim, line, size, n)
    need = pts[:, -1].max() if line else np.abs(pts).max()
    gi, _, words, start, blocks, cellz, _, _, field = cells.build_grid(
        dim, line, size, need, pts, n, np.full(n, -1, np.int32), 0)
    per, m0, m1, m2, W, fw, fcap, flo, ftop = cells.walk_geometry(gi, cellz, dim)
    assert per == line
    scale = rng.choice([0.5, 3.0, 15.0, 60.0, 200.0], 20000)
    q = pts[rng.integers(0, n, 20000)] + rng.normal(0, 1, (20000, dim)) * scale[:, None]
    if line:
        q[:, -1] = np.abs(q[:, -1])
    seen = set()
    for x in q:
        w = np.r_[x, np.zeros(3 - dim)]
        want = cells.map_dist(w, dim, size, gi, words, start, blocks, cellz, field)
        moved = w.copy()
        got = cells.walk_bound(moved, dim, size, per, m0, m1, m2, W, words, start, blocks, field, fw, fcap, flo, ftop)
        assert got == want, (x, got, want)
        if line:
            wrapped = w[: dim - 1] - size * np.floor(w[: dim - 1] / size)
            np.testing.assert_array_equal(moved[: dim - 1], wrapped)
        else:
            np.testing.assert_array_equal(moved, w)
        seen.add(np.sign(want))
    assert seen == {-1.0, 0.0, 1.0} if not line else seen >= {0.0, 1.0}
