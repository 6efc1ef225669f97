"""The lattice kernel's exact machinery: square/cube exit laws and their alias tables."""

import os
import sys

import numpy as np
import pytest
from scipy.stats import chi2

import dlasweep as dla
import naive
from dlasweep.kernels import centres, maps
from dlasweep.kernels.lattice import exits
from dlasweep.kernels.lattice.exits import (
    TABLE_MAX,
    exit_law,
    exit_tables,
    face_law,
    square_exit,
    symmetry,
    unit_moves,
)
from dlasweep.kernels.lattice.field import FIELD_CAP, FIELD_PACKED, field_fill, field_lower, field_value
from dlasweep.kernels.lattice.walker import distance_bound, release
from dlasweep.kernels.lattice.words import fine3, rebuild, regrow
from dlasweep.kernels.model import GRID_GROWTH
from dlasweep.kernels.walk import seed_stream


@pytest.mark.parametrize("dim, moore", [(2, False), (2, True), (3, False), (3, True)])
def test_exit_law_is_a_symmetric_law_on_the_boundary(dim, moore):
    for r in (1, 2, 5, TABLE_MAX[dim]):
        sites, probs = exit_law(dim, moore, r)
        assert abs(probs.sum() - 1) < 1e-12
        assert (np.abs(sites).max(1) == r).all()
        law = {tuple(s): p for s, p in zip(sites, probs)}
        # the square's symmetry group: axis permutations and reflections
        for s, p in law.items():
            assert law[tuple(-np.array(s))] == pytest.approx(p, rel=1e-9, abs=1e-15)
            assert law[tuple(reversed(s))] == pytest.approx(p, rel=1e-9, abs=1e-15)
        corners = [s for s in law if (np.abs(s) == r).all()]
        assert bool(corners) == moore  # NN: corners are never hit first


def test_exit_law_at_half_width_one_is_one_step():
    sites, probs = exit_law(2, False, 1)
    assert sorted(map(tuple, sites)) == sorted(map(tuple, unit_moves(2, False)[:, :2]))
    np.testing.assert_allclose(probs, 0.25)


@pytest.mark.parametrize("dim, moore, r", [(2, False, 3), (2, True, 4), (3, False, 2), (3, True, 2)])
def test_exit_law_matches_single_steps(dim, moore, r):
    """Chi-square of 40000 seeded brute-force walks against the law.

    Sites are pooled by symmetry class (sorted absolute coordinates) so every
    class expects hundreds of hits; at the 0.1% level a correct law fails
    one run in a thousand, a wrong one (e.g. the Brownian harmonic measure,
    which differs by several percent near corners) fails every time.
    """
    walks = 40_000
    x = naive.lattice_exits(unit_moves(dim, moore)[:, :dim], r, walks, np.random.default_rng(5))
    sites, probs = exit_law(dim, moore, r)

    def key(s):
        return tuple(sorted(np.abs(s)))

    classes = sorted({key(s) for s in sites})
    expected = np.array([probs[[key(s) == c for s in sites]].sum() for c in classes]) * walks
    observed = np.array([sum(key(s) == c for s in x) for c in classes])
    assert observed.sum() == walks
    stat = ((observed - expected) ** 2 / expected).sum()
    assert stat < chi2.ppf(0.999, len(classes) - 1)


@pytest.mark.parametrize("dim, moore", [(2, False), (2, True), (3, False), (3, True)])
def test_alias_tables_reproduce_the_law(dim, moore):
    """The tables' classes, spread uniformly over their orbits, give the exit law exactly."""
    start, cut, alias, offsets = exit_tables(dim, moore)
    group = 8 if dim == 2 else 48
    for r in (2, 7, TABLE_MAX[dim]):
        lo, hi = start[r], start[r + 1]
        k = hi - lo
        implied = cut[lo:hi] / k
        np.add.at(implied, alias[lo:hi], (1 - cut[lo:hi]) / k)
        law = {}
        for rep, p in zip(offsets[lo:hi], implied):
            for g in range(group):
                site = symmetry(g, dim, *rep.astype(np.int64))[:dim]
                law[site] = law.get(site, 0.0) + p / group
        sites, probs = exit_law(dim, moore, r)
        assert sorted(law) == sorted(map(tuple, sites))
        np.testing.assert_allclose([law[tuple(s)] for s in sites], probs, rtol=1e-9, atol=1e-15)


@pytest.mark.parametrize("dim", [2, 3])
def test_square_exit_is_where_brownian_motion_leaves_the_square(dim):
    """100000 draws of ``square_exit`` against 100000 Brownian paths by walk-on-spheres (``naive``):
    a two-sample chi-square over (face, |y| bin[, |z| bin]) at the 0.1% level. The face law
    holds 1 / (2 dim) of the mass. Measured against the same walks, a uniform law on the face
    scores 16678 (2D) and 31717 (3D) against limits of 72 and 136, and a law of the first mode
    alone, cos(pi y / 2) on each axis, 157 and 592."""
    assert face_law(dim).sum() == pytest.approx(1 / (2 * dim), rel=1e-12)
    cut, alias = (exits.FACE_CUT_2D, exits.FACE_ALIAS_2D) if dim == 2 else (exits.FACE_CUT_3D, exits.FACE_ALIAS_3D)
    implied = cut / len(cut)
    np.add.at(implied, alias, (1 - cut) / len(cut))
    np.testing.assert_allclose(implied, face_law(dim) * 2 * dim, rtol=1e-9)
    n, bins = 100_000, 10 if dim == 2 else 5
    state = seed_stream(np.random.default_rng(11))
    drawn = np.zeros((n, dim))
    for i in range(n):
        *words, o0, o1, o2 = square_exit(*state, dim)
        state = np.array(words, np.uint64)
        drawn[i] = (o0, o1, o2)[:dim]
    walked = naive.brownian_square_exits(dim, n, np.random.default_rng(12))

    def table(points):
        assert np.allclose(np.abs(points).max(1), 1.0)
        axis = np.abs(points).argmax(1)
        face = 2 * axis + (points[np.arange(len(points)), axis] > 0)
        rest = np.sort(np.abs(np.where(np.arange(dim) == axis[:, None], np.nan, points)), axis=1)[:, : dim - 1]
        cells = np.minimum((rest * bins).astype(int), bins - 1)
        key = face * bins ** (dim - 1) + (cells * bins ** np.arange(dim - 1)).sum(1)
        return np.bincount(key, minlength=2 * dim * bins ** (dim - 1))

    a, b = table(drawn), table(walked)
    used = a + b > 0
    stat = ((a[used] - b[used]) ** 2 / (a[used] + b[used])).sum()
    assert stat < chi2.ppf(0.999, used.sum() - 1), stat


@pytest.mark.parametrize("dim", [2, 3])
def test_symmetries_are_the_whole_group(dim):
    """Every signed permutation of the axes, each once."""
    group = 8 if dim == 2 else 48
    images = {symmetry(g, dim, 1, 2, 3)[:dim] for g in range(group)}
    assert len(images) == group
    assert all(sorted(map(abs, s)) == list(range(1, dim + 1)) for s in images)


def test_fine_distance_matches_brute_force_3d():
    """``fine3`` (word masks) against the Chebyshev distance to every particle,
    capped at 5, at sites 3 or more from every particle (where the walk asks
    it), on a grid of 3 tiles a side: its words read within one tile, across
    tiles and at the grid's faces; every answer 3, 4 and 5 is seen."""
    rng = np.random.default_rng(0)
    width = 3 * 4 << maps.TILE_BITS[3]
    seen = set()
    for density in (0.0005, 0.002, 0.005, 0.01):
        for _ in range(8):
            words, start, blocks, cells = maps.allocate(3, width)
            pts = np.argwhere(rng.random((width,) * 3) < density)
            for i, j, k in pts:
                maps.mark(words, 3, start, blocks, cells, i, j, k)
            for q in rng.integers(0, width, (200, 3)):
                d = np.abs(pts - q).max(1).min() if len(pts) else 5
                if d >= 3:
                    assert fine3(words, blocks[0], q[0], q[1], q[2]) == min(d, 5)
                    seen.add(min(d, 5))
    assert seen == {3, 4, 5}


def _random_points(rng, dim, width, density):
    pts = np.argwhere(rng.random((width,) * dim) < density)
    rng.shuffle(pts)
    return [list(p) + [0] * (3 - dim) for p in pts]


@pytest.mark.parametrize("dim, width", [(2, 150), (3, 40)])
def test_maps_match_brute_force(dim, width):
    """``maps.mark`` (which skips levels a word's earlier particle marked)
    against the dilated maps built directly."""
    rng = np.random.default_rng(3)
    start, blocks, cells = maps.layout(dim, width)
    for density in (0.0005, 0.005, 0.05):
        pts = _random_points(rng, dim, width, density)
        words = maps.allocate(dim, width)[0]
        for p in pts:
            maps.mark(words, dim, start, blocks, cells, *p)
        for s in range(1, len(cells)):
            occ = np.zeros((cells[s] + 2,) * dim, bool)  # a margin, so that rolling adds nothing
            for p in pts:
                occ[tuple(np.array(p[:dim]) >> s)] = True
            dil = np.zeros_like(occ)
            for shift in np.ndindex(*(3,) * dim):
                dil |= np.roll(occ, tuple(o - 1 for o in shift), axis=tuple(range(dim)))
            for c in np.ndindex(*(cells[s],) * dim):
                q = list(c) + [0] * (3 - dim)
                assert maps.test(words, dim, start, blocks, s, *q) == dil[c]


@pytest.mark.parametrize("n, value, dtype", [(5, 7, np.uint8), (3 << 20, -1, np.int32), (1 << 20, 2.5, np.float64)])
def test_filled_is_np_full(n, value, dtype):
    """``maps.filled`` (huge-page advice for large arrays) gives ``np.full``'s array, small or large."""
    a = maps.filled(n, value, dtype)
    assert a.dtype == dtype and a.shape == (n,)
    assert np.array_equal(a, np.full(n, value, dtype))


@pytest.mark.parametrize("n, dtype", [(3, np.uint64), (1000, np.uint8), (3 << 20, np.uint64),
                                      ((5 << 20) + 3, np.uint8)])
def test_zeroed_is_np_zeros_even_where_the_heap_held_other_values(n, dtype):
    """``maps.zeroed`` gives zeros, small or large, also in memory the
    allocator hands out again after an array of other values was freed."""
    for _ in range(3):
        junk = maps.filled(n, 7, dtype)
        del junk
        a = maps.zeroed(n, dtype)
        assert a.dtype == dtype and a.shape == (n,)
        assert not a.any()


def _resident_mb():
    with open("/proc/self/status") as f:
        return next(int(line.split()[1]) for line in f if line.startswith("VmRSS")) / 1024


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="pages handed back to the OS: Linux's madvise")
def test_zeroed_takes_memory_only_where_written():
    """256 MiB zeroed, read whole, add little to the resident memory; writing
    one word in every 16th page adds about 1/16 of it."""
    before = _resident_mb()
    a = maps.zeroed(32 << 20, np.uint64)
    assert a.sum() == 0
    read = _resident_mb() - before
    a[:: 16 * maps.PAGE // 8] = 1
    written = _resident_mb() - before
    assert read < 8
    assert 12 < written < 24


def _overcommit_strict():
    """Whether Linux counts every mapping against its limit (``vm.overcommit_memory`` 2), ``MAP_NORESERVE`` too."""
    try:
        with open("/proc/sys/vm/overcommit_memory") as f:
            return f.read().strip() == "2"
    except OSError:
        return False


UNRESERVED_HERE = maps.UNRESERVED and not _overcommit_strict()


@pytest.mark.skipif(not UNRESERVED_HERE, reason="Linux's MAP_NORESERVE, not counted unless overcommit is strict")
def test_zeroed_beyond_the_machines_memory():
    """Twice the machine's memory zeroed (numba's own allocator refuses it): zeros, written where
    asked, and only the pages written take memory."""
    memory = os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    before = _resident_mb()
    a = maps.zeroed(2 * memory // 8, np.uint64)
    stride = len(a) // 1000
    a[::stride] = 3
    assert (a[::stride] == 3).all() and not a[1::stride].any() and not a[-1]
    assert _resident_mb() - before < 64


@pytest.mark.skipif(not UNRESERVED_HERE, reason="Linux's MAP_NORESERVE, not counted unless overcommit is strict")
def test_a_3d_lattice_grid_past_the_machines_memory_holds_its_particles():
    """The grid of a 3D lattice cluster whose farthest site lies 2040 sites out (side 8192: 72 GiB of
    occupancy words: the 3D lattice cluster of 1e8, seed 1, from 9.5e7 particles on) is built, in
    little memory, and holds its particles and the field's distances about them."""
    width = 8192
    off = width // 2
    pts = np.array([[0, 0, 0], [2000, -1500, 3], [-2040, 7, 2039]], np.int32)
    before = _resident_mb()
    words, start, blocks, cells, field = rebuild(pts, len(pts), 3, width, off, 0)
    assert start[-1] * 8 > 64 << 30
    assert _resident_mb() - before < 256
    fw = width >> maps.FIELD_SHIFT
    for p in pts:
        i, j, k = (int(x) + off for x in p)
        assert maps.test(words, 3, start, blocks, 0, i, j, k)
        assert not maps.test(words, 3, start, blocks, 0, i + 1, j, k)
        c = [x >> maps.FIELD_SHIFT for x in (i, j, k)]
        for step, distance in ((0, 0), (2, 2), (FIELD_CAP[3] + 1, FIELD_CAP[3])):
            cell = maps.field_cell(3, fw, c[0] + step, c[1], c[2])
            assert FIELD_CAP[3] - field_value(field, 3, cell) == distance


def _level_distances(pts, dim, width, shift, cap):
    """Chebyshev distance, in cells of side 2**shift and capped, from every cell to the nearest holding a point."""
    fw = (width + (1 << shift) - 1) >> shift
    cells = np.array([np.array(p[:dim]) >> shift for p in pts]).reshape(-1, dim)
    grid = np.stack(np.meshgrid(*([np.arange(fw)] * dim), indexing="ij"), -1).reshape(-1, dim)
    if len(cells) == 0:
        return np.full((fw,) * dim, cap)
    far = np.abs(grid[:, None, :] - cells[None, :, :]).max(2).min(1)
    return np.minimum(far, cap).reshape((fw,) * dim)


@pytest.mark.parametrize("dim, width", [(2, 300), (3, 72)])
@pytest.mark.parametrize("fill", ["mark", "fill"])
def test_the_field_holds_capped_cell_distances(dim, width, fill):
    """The coarse distance field, marked particle by particle or seeded and
    filled, is the brute-force capped Chebyshev cell distance."""
    rng = np.random.default_rng(5)
    cap = FIELD_CAP[dim]
    shift = maps.FIELD_SHIFT
    fw = (width + (1 << shift) - 1) >> shift
    for density in (0.00002, 0.0003, 0.003):
        pts = _random_points(rng, dim, width, density)
        field = maps.zeroed(maps.field_size(dim, fw), np.uint8)
        held = np.zeros(maps.field_tile(dim, fw, fw - 1, fw - 1, fw - 1) + 1, np.uint8)
        for p in pts:
            cell = [x >> shift for x in p]
            field_lower(field, dim, fw, cap, cap if fill == "mark" else 1, *cell)
            held[maps.field_tile(dim, fw, *cell)] = 1
        if fill == "fill":
            field_fill(field, dim, fw, cap, held)
        got = naive.field_distances(field, dim, fw, cap, FIELD_PACKED[dim])
        assert (got == _level_distances(pts, dim, width, shift, cap)).all()


@pytest.mark.parametrize("dim", [2, 3])
def test_a_packed_field_takes_half_its_level(dim):
    """The field is packed (``FIELD_PACKED``) wherever its cap fits the halves' maximum
    (below 8: 3D), and there a grown cluster's field writes only the first half of its level's
    bytes, the second half never (pages that cost no memory); elsewhere the whole level."""
    pts = dla.grow(20_000, seed=3, model="lattice", dim=dim).points.astype(np.int64)
    width = 2 * (int(np.abs(pts).max()) + 8) // 16 * 16 + 32
    field = rebuild(pts, len(pts), dim, width, width // 2, 0)[4]
    level = field[:maps.pyramid_starts(dim, width, FIELD_CAP[dim])[1]]
    first, second = np.count_nonzero(level[:len(level) // 2]), np.count_nonzero(level[len(level) // 2:])
    assert first > 1000
    assert FIELD_PACKED[dim] == (FIELD_CAP[dim] < 8)
    if FIELD_PACKED[dim]:
        assert second == 0
    else:
        assert second > 1000


@pytest.mark.parametrize("dim", [2, 3])
def test_a_filled_field_skips_only_tiles_beyond_reach(dim):
    """On a grid of 6 tiles a side whose particles lie in a corner, along one
    edge and alone near the corner of an inner tile (``field_fill`` visits only
    the tiles beside a held one), the filled field equals the one marked
    particle by particle."""
    rng = np.random.default_rng(9)
    cap, shift = FIELD_CAP[dim], maps.FIELD_SHIFT
    tile = 1 << (maps.FIELD_TILE[dim] + shift)  # sites
    width = 6 * tile
    fw = (width + (1 << shift) - 1) >> shift
    corner = rng.integers(0, tile + tile // 4, (200, dim))  # across the first tile's edges
    edge = np.column_stack([rng.integers(0, width, 40)] + [np.zeros(40, int)] * (dim - 1))
    inner = np.full((1, dim), 4 * tile + 4)  # it alone reaches into the tiles before its own
    fields = []
    for reach in (cap, 1):
        field = maps.zeroed(maps.field_size(dim, fw), np.uint8)
        held = np.zeros(maps.field_tile(dim, fw, fw - 1, fw - 1, fw - 1) + 1, np.uint8)
        for p in np.concatenate([corner, edge, inner]):
            cell = [int(x) >> shift for x in p] + [0] * (3 - dim)
            field_lower(field, dim, fw, cap, reach, *cell)
            held[maps.field_tile(dim, fw, *cell)] = 1
        if reach == 1:
            assert held.sum() < len(held) - 3 ** dim  # some tiles lie beyond every held one's reach
            field_fill(field, dim, fw, cap, held)
        fields.append(naive.field_distances(field, dim, fw, cap, FIELD_PACKED[dim]))
    assert (fields[0] == fields[1]).all()
    assert (fields[0] < cap).sum() > 0


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("where", ["circle", "plane", "box", "box above a plane"])
def test_release_puts_walkers_uniformly_where_they_start(dim, where):
    """4000 walkers released with ``release``: on the launch circle
    (sphere), at the launch height above a substrate, on the box's surface
    (a substrate's box: its top), uniformly there: per axis the mean and
    the mean square of a uniform law (within about 5 standard errors), and
    for the box each face hit about equally often."""
    rng = np.random.default_rng(11)
    line, box = "plane" in where, "box" in where
    size, launch_r = 20, 37.5
    box_lo, box_hi = (0, size - 1) if line else (-(size // 2), size - 1 - size // 2)
    pos = np.zeros((4000, 3))
    for p in pos:
        release(rng, dim, line, box, size, box_lo, box_hi, launch_r, p)
    assert (pos[:, dim:] == 0).all()
    x = pos[:, :dim]
    up = dim - 1
    if box:
        assert (x == np.round(x)).all() and (x >= box_lo).all() and (x <= box_hi).all()
    if where == "circle":
        np.testing.assert_allclose(np.sqrt((x**2).sum(1)), launch_r)
        spread = launch_r / np.sqrt(dim)  # each axis: mean 0, mean square launch_r**2 / dim
        np.testing.assert_allclose(x.mean(0), 0, atol=5 * spread / np.sqrt(len(x)))
        np.testing.assert_allclose((x**2).mean(0), spread**2, rtol=0.05)
    elif line:
        assert (x[:, up] == (box_hi if box else launch_r)).all()
        across = x[:, :up]
        assert (across >= 0).all() and (across < size).all()
        np.testing.assert_allclose(across.mean(0), (size - 1 if box else size) / 2,
                                   atol=5 * size / np.sqrt(12 * len(x)))
    else:
        on = (x == box_lo) | (x == box_hi)
        assert on.any(1).all()
        faces = np.concatenate([(x == box_lo).sum(0), (x == box_hi).sum(0)])
        # its own face, or another axis's uniform site on this one
        expected = len(x) * (1 / (2 * dim) + (1 - 1 / dim) / size)
        np.testing.assert_allclose(faces, expected, rtol=0.15)


@pytest.mark.parametrize("dim, width", [(2, 512), (3, 96)])
def test_distance_bound_is_zero_near_the_cluster_and_a_lower_bound_beyond(dim, width):
    """``distance_bound`` (which ``_grow`` spells out) on random clusters,
    against the brute-force distances to the nearest particle: Chebyshev 0
    within two sites (and only within three, the level-1 cells' reach), else
    at least 3 and at most the truth, exact up to 4 sites (the words), 5 off
    the grid; Euclidean (the centre pyramid, beyond the field's reach) at most
    the truth. The pyramid's first two levels hold the distance from each
    cell's centre to the nearest held cell of the level below."""
    rng = np.random.default_rng(7 + dim)
    off = width // 2
    cap = FIELD_CAP[dim]
    levels = maps.pyramid_starts(dim, width, cap)
    fw0 = (width + (1 << maps.FIELD_SHIFT) - 1) >> maps.FIELD_SHIFT
    hubs = rng.integers(-off // 3, off // 3, (5, dim))
    sites = hubs[rng.integers(0, 5, 1500)] + np.rint(rng.normal(0, 6, (1500, dim))).astype(np.int64)
    sites = sites[(np.abs(sites) <= off - 5).all(1)]  # as in _grow, every particle 4 sites inside the grid
    points = np.unique(sites, axis=0).astype(np.int32)
    words, start, blocks, _, field = rebuild(points, len(points), dim, width, off, 0)
    step, top = maps.PYRAMID_STEP[dim], centres.LEVEL_TOP[dim]
    for level in (1, 2):
        shift = maps.FIELD_SHIFT + step * level
        pw = (width + (1 << shift) - 1) >> shift
        held = np.unique((points + off) >> (shift - step), axis=0)
        want = naive.centre_distances(held, dim, pw, 1 << step, centres.LEVEL_UNITS[dim] / (1 << step), top)
        np.testing.assert_array_equal(naive.field_distances(field[levels[level]:levels[level + 1]], dim, pw, top), want)
    scale = rng.choice([1.0, 3.0, 12.0, 60.0, 200.0], 3000)
    seen = set()
    for q in np.rint(points[rng.integers(0, len(points), 3000)] + rng.normal(0, 1, (3000, dim)) * scale[:, None]):
        truth = np.abs(points - q).max(1).min()
        ijk = [int(x) + off for x in q] + [off] * (3 - dim)
        d, far = distance_bound(words, field, levels, dim, width, blocks[0], start[1], blocks[1], fw0, cap, *ijk,
                                False)
        # a walker from a far jump reads the pyramid first: the same bounds
        assert distance_bound(words, field, levels, dim, width, blocks[0], start[1], blocks[1], fw0, cap, *ijk,
                              True) == (d, far), q
        if not all(0 <= x < width for x in ijk):
            assert d == 5 and far == 0
            seen.add("off the grid")
            continue
        if d == 0:
            assert truth <= 3, (q, truth)
            seen.add("near")
        else:
            assert truth > 2 and 3 <= d <= truth and (d == truth or truth > 4), (q, d, truth)
            seen.add("exact" if d == truth else "bound")
        assert far <= np.sqrt(((points - q) ** 2).sum(1)).min() + 1e-9
        if far > 0:
            seen.add("far")
    assert seen == {"near", "exact", "bound", "off the grid", "far"}


def test_jumps_grow_the_clusters_single_steps_grow():
    """16 square-lattice clusters of 4000 grown with the jumps (exact square exits,
    the Brownian jumps far from the cluster) against 16
    grown by single lattice steps only: mean Rg and Rg/Rmax agree.

    At 4000 particles walkers released on the launch circle start up to 60
    and more sites from the cluster, where the pyramid's coarse levels set
    the jumps. Seed-to-seed spread (measured): Rg 2-3%, Rg/Rmax 5-6%, so a
    difference of two 16-seed means has a standard error of about 0.9% and
    1.9%; asserted within 3.5 of them. A pyramid bound one cell too large,
    which lets walkers jump onto branches, made Rg 12% smaller (10 standard
    errors) and Rg/Rmax 29% smaller.
    """
    def shape(jumps):
        rg, ratio = [], []
        for seed in range(16):
            p = dla.grow(4000, seed=500 + seed, jumps=jumps).points.astype(float)
            rg.append(np.sqrt(((p - p.mean(0)) ** 2).sum(1).mean()))
            ratio.append(rg[-1] / np.sqrt((p**2).sum(1)).max())
        return np.array(rg), np.array(ratio)

    fast, slow = shape(True), shape(False)
    for a, b in zip(fast, slow):
        se = np.sqrt(a.var(ddof=1) / len(a) + b.var(ddof=1) / len(b))
        assert abs(a.mean() - b.mean()) < 3.5 * se, (a.mean(), b.mean(), se)


def test_square_jumps_keep_the_2d_clusters_of_the_circle_jumps():
    """16 square-lattice clusters of 1e5 (seeds 500-515), whose walkers jump out of squares
    (``exits.square_exit``) far from the cluster: mean Rg and Rg/Rmax as the circle jumps gave
    them before (commit a43ff7a: Rg 408.895, spread 2.15%; Rg/Rmax 0.5276, spread 4.22%), within
    3.5 standard errors of a difference of 16-seed means. Measured after: 408.632 and 0.5339;
    with the centre pyramid (``centres``) and grids grown by 2.0: 409.937 and 0.5226.
    (Single steps at this size take hours.)"""
    rg, ratio = [], []
    for seed in range(16):
        p = dla.grow(100_000, seed=500 + seed).points.astype(float)
        rg.append(np.sqrt(((p - p.mean(0)) ** 2).sum(1).mean()))
        ratio.append(rg[-1] / np.sqrt((p**2).sum(1)).max())
    for values, mean, spread in ((rg, 408.895, 0.0215), (ratio, 0.5276, 0.0422)):
        se = mean * spread * np.sqrt(2 / 16)
        assert abs(np.mean(values) - mean) < 3.5 * se, (np.mean(values), mean)


def test_the_pyramid_bound_keeps_the_3d_clusters_of_the_maps_bound():
    """16 cubic-lattice clusters of 20000 (seeds 500-515), where walkers reach
    the pyramid's coarse levels (the clusters differ from the earlier
    kernel's): mean Rg and Rg/Rmax as the kernel gave them before the
    pyramid replaced the dilated maps (commit 1454851: Rg 34.841, spread
    2.05%; Rg/Rmax 0.5195, spread 5.0%), within 3.5 standard errors of a
    difference of 16-seed means. Measured after: 34.890 and 0.5222; with the
    centre pyramid (``centres``) and grids grown by 2.0: 34.936 and 0.5188.
    (Single steps in 3D take minutes at this size.)
    """
    rg, ratio = [], []
    for seed in range(16):
        p = dla.grow(20000, seed=500 + seed, dim=3).points.astype(float)
        rg.append(np.sqrt(((p - p.mean(0)) ** 2).sum(1).mean()))
        ratio.append(rg[-1] / np.sqrt((p**2).sum(1)).max())
    for values, mean, spread in ((rg, 34.841, 0.0205), (ratio, 0.5195, 0.0504)):
        se = mean * spread * np.sqrt(2 / 16)
        assert abs(np.mean(values) - mean) < 3.5 * se, (np.mean(values), mean)


@pytest.mark.parametrize("params", [dict(dim=2), dict(dim=3), dict(dim=2, seed_shape="block"),
                                    dict(dim=2, neighbours=8), dict(dim=2, size=64, seed_shape="line")])
def test_a_regrown_grid_is_the_grid_built_anew_bit_for_bit(params):
    """``words.regrow`` (the words, the field and the pyramid's first level carried
    over from the outgrown grid) gives every array of ``rebuild``'s grid for the
    same particles, at each of a grown cluster's own regrids: its first m - 1
    particles in a grid, the m-th past its edge. The old grid's whole pages go
    back to the OS: they read zeros. A substrate's grid is built anew."""
    pts = dla.grow(20_000 if params["dim"] == 2 else 25_000, seed=5, model="lattice", **params).points
    dim, line = params["dim"], params.get("seed_shape") == "line"
    period = params.get("size", 0) if line else 0
    points = np.zeros((len(pts), 3), np.int64)
    points[:, :dim] = pts
    extent = np.abs(pts).max(1)
    width, off = (4 * period, period) if line else (64, 32)
    regrids = kept = 0
    while True:
        # ``_attach``'s rule: a particle within 4 sites of the edge (a substrate's: the top) outgrows the grid
        past = (pts[:, dim - 1] + off + 4 >= width) if line else (extent + 4 >= off)
        if not past.any():
            break
        m = int(np.argmax(past)) + 1
        old = rebuild(points, m - 1, dim, width, off, period)
        new_width = (int(width * GRID_GROWTH["lattice"]) + 15) // 16 * 16  # as _attach
        new_off = off if line else new_width // 2
        fresh = rebuild(points, m, dim, new_width, new_off, period)
        carried = regrow(points, m, dim, new_width, new_off, period, (*old, width, off))
        for name, a, b in zip(("words", "start", "blocks", "cells", "field"), fresh, carried):
            np.testing.assert_array_equal(a, b, err_msg=f"{name} at {m} particles, width {new_width}")
        for a in (old[0], old[4]):
            lo, hi = -a.ctypes.data % maps.PAGE, (a.ctypes.data + a.nbytes) // maps.PAGE * maps.PAGE - a.ctypes.data
            assert hi <= lo or not a.view(np.uint8)[lo:hi].any()  # its whole pages handed back (they read zeros)
        width, off = new_width, new_off
        regrids += 1
        kept += np.count_nonzero(carried[4])
    assert regrids >= (1 if line else 2) and kept > 1000


@pytest.mark.parametrize("dim", [2, 3])
def test_a_regrown_grid_lowers_again_exactly_the_cells_the_old_grid_lacked(dim):
    """``words.regrow`` on arms that end at the last cells whose reach crosses the
    old grid's edge, of the field (along -y) and of the pyramid's first level (along
    -x): their lowering beyond that edge is kept, so the grid equals ``rebuild``'s
    (a reach one cell shorter loses it: the field differs)."""
    width = 1024 if dim == 2 else 256
    off = width // 2
    s1 = maps.FIELD_SHIFT + maps.PYRAMID_STEP[dim]
    x_end = off - ((centres.FCAP[dim - 2] - 2) << s1) - 3  # first level: index FCAP - 2 from the old edge
    y_end = off - ((FIELD_CAP[dim] - 2) << maps.FIELD_SHIFT) - 1  # field: index FIELD_CAP - 2
    points = np.zeros((x_end + y_end + 2, 3), np.int64)
    points[1:x_end + 1, 0] = -np.arange(1, x_end + 1)
    points[x_end + 1:-1, 1] = -np.arange(1, y_end + 1)
    points[-1, 1] = off - 2  # the last: past the edge by ``_attach``'s rule
    assert ((off - x_end) >> s1, (off - y_end) >> maps.FIELD_SHIFT) == (centres.FCAP[dim - 2] - 2, FIELD_CAP[dim] - 2)
    m = len(points)
    old = rebuild(points, m - 1, dim, width, off, 0)
    new_width = (int(width * GRID_GROWTH["lattice"]) + 15) // 16 * 16  # as _attach
    fresh = rebuild(points, m, dim, new_width, new_width // 2, 0)
    carried = regrow(points, m, dim, new_width, new_width // 2, 0, (*old, width, off))
    for name, a, b in zip(("words", "start", "blocks", "cells", "field"), fresh, carried):
        np.testing.assert_array_equal(a, b, err_msg=name)
