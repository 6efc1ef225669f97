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

from dlasweep.kernels import maps
from dlasweep.kernels.lattice import lattice_growth as lattice_grow
from dlasweep.kernels.lattice import walker as lattice_walker
from dlasweep.kernels.lattice.exits import unit_moves
from dlasweep.kernels.lattice.words import rebuild
from dlasweep.kernels.model import drift_flag, sticks_xo
from dlasweep.kernels.offlattice import grid
from dlasweep.kernels.offlattice import walker as offlattice_walker


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


def copies(function, name):
    """Every run of lines of ``function`` between ``# >>> name`` and ``# <<< name``,
    dedented, the comment lines at the first mark left out."""
    lines = inspect.getsource(function.py_func).split("\n")
    found = []
    for start, line in enumerate(lines):
        if not line.strip().startswith(f"# >>> {name}"):
            continue
        while lines[start + 1].strip().startswith("#"):
            start += 1
        end = next(i for i in range(start, len(lines)) if lines[i].strip() == f"# <<< {name}")
        found.append([line.rstrip() for line in textwrap.dedent("\n".join(lines[start + 1:end])).split("\n")])
    return found


def copy(function, name):
    """The one run of lines of ``function`` that ``copies`` finds."""
    (found,) = copies(function, name)
    return found


def test_the_walks_two_jumps_are_one_text():
    """The off-lattice walk's walk-on-spheres jump, spelled out for the
    exact end game and again for Gaussian steps."""
    first, second = copies(offlattice_walker.walk_to_contact, "jump")
    assert first == second and len(first) == 6


def test_the_walks_map_bound_is_walk_bound_spelled_out():
    assert copy(offlattice_walker.walk_to_contact, "walk_bound") == body(grid.walk_bound)


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
    open) equals ``map_dist``'s full search, and wraps periodic coordinates;
    where the centre pyramid gives it, the ball it returns holds no particle
    centre, holds w, and the bound is w's way to its sphere."""
    rng = np.random.default_rng(3 + dim + 10 * line)
    size = 48 if line else 0
    n = 600 if dim == 2 else 1500
    pts = _clustered(rng, dim, line, size, n)
    need = pts[:, -1].max() if line else np.abs(pts).max()
    gi, _, words, start, blocks, cellz, _, _, field = grid.build_grid(
        dim, line, size, need, pts, n, np.full(n, -1, np.int32), 0)
    per, m0, m1, m2, W, fw, flo, ftop = grid.walk_geometry(gi, cellz, dim)
    pstart = grid.level_starts(gi, dim)
    assert per == line
    scale = rng.choice([0.5, 3.0, 15.0, 60.0, 200.0], 20000)
    q = pts[rng.integers(0, n, 20000)] + rng.normal(0, 1, (20000, dim)) * scale[:, None]
    if line:
        q[:, -1] = np.abs(q[:, -1])
    seen = set()
    balls = 0
    for x in q:
        w = np.r_[x, np.zeros(3 - dim)]
        want = grid.map_dist(w, dim, size, gi, words, start, blocks, cellz, field)
        moved = w.copy()
        got, ball, gap, shift = grid.walk_bound(moved, dim, size, per, m0, m1, m2, W, words, start, blocks, field,
                                                 fw, flo, ftop, pstart, False)
        assert got == want, (x, got, want)
        # a walker from far reads the pyramid first: the same bound and ball
        assert grid.walk_bound(w.copy(), dim, size, per, m0, m1, m2, W, words, start, blocks, field, fw, flo, ftop,
                                pstart, True)[:2] == (got, ball), x
        if ball > 0.0:
            at = moved[:dim] + np.array([m0, m1, m2][:dim])
            centre = ((at.astype(np.int64) >> shift) << shift) + (1 << (shift - 1)) - np.array([m0, m1, m2][:dim])
            assert np.sqrt(((pts - centre) ** 2).sum(1)).min() >= ball - 1e-9
            assert abs(np.sqrt(((moved[:dim] - centre) ** 2).sum()) - gap) < 1e-9
            assert got == ball - gap
            balls += 1
        if line:
            wrapped = w[: dim - 1] - size * np.floor(w[: dim - 1] / size)
            np.testing.assert_array_equal(moved[: dim - 1], wrapped)
        else:
            np.testing.assert_array_equal(moved, w)
        seen.add(np.sign(want))
    assert seen == {-1.0, 0.0, 1.0} if not line else seen >= {0.0, 1.0}
    assert balls > 500 if not line else balls == 0  # substrates have no pyramid above the field


def test_the_lattice_walks_single_step_is_touches_and_step_to_spelled_out():
    assert copy(lattice_grow._grow, "touches") == body(lattice_walker.touches)
    assert copy(lattice_grow._grow, "step_to") == body(lattice_walker.step_to)


def test_the_lattice_walks_distance_bound_is_distance_bound_spelled_out():
    assert copy(lattice_grow._grow, "distance_bound") == body(lattice_walker.distance_bound)


@pytest.mark.parametrize("drift", [0.0, 0.4])
@pytest.mark.parametrize("dim, moore, line", [(2, False, False), (2, True, False), (3, False, False),
                                              (3, True, False), (2, False, True), (3, False, True)])
def test_touches_and_step_to_are_near_step(dim, moore, line, drift):
    """The single walker's step as ``_grow`` spells it out (``touches``,
    the sticking rule, ``step_to``: the stream in registers) sticks and
    moves as ``near_step`` does from the same sites and stream states, on
    random clusters, where the walk takes it: near the cluster or the
    substrate; without and with a drift."""
    rng = np.random.default_rng(5 + dim + 10 * moore + 100 * line)
    mu = tuple(drift * c for c in (0.6, -0.48, 0.64 if dim == 3 else 0.0))
    size = 24 if line else 0
    period = size if line else 0
    width, off = (4 * size, size) if line else (128, 64)
    hubs = rng.integers(0, size, (4, dim)) if line else rng.integers(-30, 31, (4, dim))
    sites = hubs[rng.integers(0, 4, 400)] + np.rint(rng.normal(0, 4, (400, dim))).astype(np.int64)
    if line:
        sites[:, :-1] %= size
        sites[:, -1] = np.abs(sites[:, -1]) % 20
    sites = np.unique(sites, axis=0)
    points = np.zeros((len(sites), dim), np.int32)
    points[:] = sites
    words, start, blocks, _, _ = rebuild(points, len(points), dim, width, off, period)
    moves = unit_moves(dim, moore)
    nm = len(moves)
    occupied = {tuple(p) for p in sites}
    stream = rng.integers(1, 2**63, 4, dtype=np.uint64)
    outcomes = set()
    tried = 0
    while tried < 3000:
        q = np.zeros(3, np.int64)
        q[:dim] = sites[rng.integers(len(sites))] + rng.integers(-3, 4, dim)
        if line:
            q[:dim - 1] %= size
            if q[dim - 1] < 0:
                continue
        if tuple(q[:dim]) in occupied:
            continue
        i, j, k = q + off
        near = bool(maps.test(words, dim, start, blocks, 1, i >> 1, j >> 1, k >> 1))
        if not (near or (line and q[dim - 1] <= 1)):
            continue
        tried += 1
        stickiness = (1.0, 0.4)[tried % 2]
        want_q, want_rs = q.copy(), stream.copy()
        want = lattice_walker.near_step(words, dim, start, blocks, width, off, want_q, moves, period, stickiness,
                                          want_rs, near, 1.0, *mu)
        pos = q.astype(np.float64)
        got_rs = tuple(stream)
        got = lattice_walker.touches(words, dim, blocks[0], width, off, q, moves, nm, line, period)
        if got:
            got, *got_rs = sticks_xo(stickiness, *got_rs)
            got_rs = np.array(got_rs, np.uint64)  # numba returns Python ints, which it would type by value
        if not got:
            got_rs = lattice_walker.step_to(words, dim, blocks[0], width, off, q, pos, moves, nm, line, period,
                                            drift_flag(drift), *mu, *got_rs)
        assert got == want
        np.testing.assert_array_equal(pos, want_q)
        np.testing.assert_array_equal(np.array(got_rs, np.uint64), want_rs)
        outcomes.add((bool(got), bool((pos != q).any())))
        stream = want_rs
    assert outcomes == {(True, False), (False, True), (False, False)}
