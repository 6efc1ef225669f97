"""Box counts and mass-radius measures against slow, obviously right versions."""

from __future__ import annotations

import numpy as np
import pytest

import dlasweep
import naive
from dlasweep.measures import bitmaps as box_bitmaps
from dlasweep.measures import boxes
from dlasweep.measures import shape as measure
from dlasweep.measures.boxes import box_counts, default_scales
from dlasweep.measures.shape import max_radius, radius_of_gyration
from known_sets import CARPET, DUST_2D, DUST_3D, MENGER, iterated, pascal_gasket


def random_set(dim, lattice, n, width, seed):
    rng = np.random.default_rng(seed)
    return rng.integers(0, width, (n, dim)) if lattice else rng.random((n, dim)) * width


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("lattice", [True, False])
def test_box_counts_match_slow_reference(dim, lattice):
    width = 40 if dim == 2 else 16  # the reference tries up to 11**dim grids per side
    points = random_set(dim, lattice, 200 if lattice else 60, width, dim + 10 * lattice)
    # The default sides up to the extent: the bases 1, 3, 5, 7 are counted
    # from the particles, their doubles by halving bitmaps, so both paths are checked.
    scales, counts = box_counts(points, lattice=lattice)
    assert scales[-1] >= width
    offsets = naive.grid_offsets(scales)
    np.testing.assert_array_equal(counts, [naive.box_count(points, s, lattice, offsets[int(s)]) for s in scales])


@pytest.mark.parametrize("dim", [2, 3])
def test_box_counts_on_arbitrary_scales_match_reference(dim):
    points = random_set(dim, False, 60, 30, 3)
    # Unsorted, with a family 3, 6, 12 (and 13, 26) whose members are not neighbours.
    scales = [12, 1, 3, 13, 6, 26, 2, 5]
    _, counts = box_counts(points, lattice=False, scales=scales, offsets=3)
    offsets = naive.grid_offsets(scales, offsets=3)
    np.testing.assert_array_equal(counts, [naive.box_count(points, s, False, offsets[s]) for s in scales])


@pytest.mark.parametrize("lattice", [True, False])
@pytest.mark.parametrize("spread", [(1e5, 1e5), (2e3, 2e3, 2e3)], ids=["2d", "3d"])
def test_box_counts_of_sets_too_wide_for_a_bitmap_match_reference(spread, lattice):
    # Two clumps so far apart that the grids of the finest sides have more
    # boxes than a bitmap may hold (counted by sorting), the next ones fit one
    # at a time but not all together (their doubles are counted from the
    # particles again), the coarsest are kept and halved.
    rng = np.random.default_rng(4)
    points = rng.random((20, len(spread))) * 20
    points = np.r_[points, points + np.array(spread)]
    if lattice:
        points = np.round(points)
    scales = [1, 2, 3, 4, 6, 8, 16, 32, 64]
    _, counts = box_counts(points, lattice=lattice, scales=scales)
    offsets = naive.grid_offsets(scales)
    np.testing.assert_array_equal(counts, [naive.box_count(points, s, lattice, offsets[s]) for s in scales])


@pytest.mark.parametrize("cap", [0, 1 << 10, 1 << 14, 1 << 18])
@pytest.mark.parametrize("lattice", [True, False])
@pytest.mark.parametrize("dim", [2, 3])
def test_box_counts_do_not_depend_on_the_bitmap_cap(monkeypatch, dim, lattice, cap):
    # Cap 0 sorts every grid; the others let bitmaps in from some side on
    # (strips of sites among them) and keep a side's grids for halving from
    # a larger side on.
    points = random_set(dim, lattice, 2000 if dim == 2 else 500, 120 if dim == 2 else 24, 7)
    expected = box_counts(points, lattice=lattice)
    monkeypatch.setattr(boxes, "_BITMAP_CAP", cap)
    np.testing.assert_array_equal(box_counts(points, lattice=lattice), expected)


@pytest.mark.parametrize("most", [1, 700, 1 << 24])
def test_pieces_are_the_shifted_prefix_in_first_axis_order(most):
    # A prefix handed to the marking in pieces of at most ``most`` particles (more only where one first
    # coordinate holds more): together, in order, the stable first-axis sort of the shifted prefix.
    rng = np.random.default_rng(4)
    prefix = np.c_[rng.integers(0, 300, 5000), rng.integers(-50, 50, 5000)].astype(np.int32)
    low = prefix.min(axis=0)
    shifted = prefix - low
    expected = shifted[np.argsort(shifted[:, 0], kind="stable")]
    cuts, start, buffer = box_bitmaps.pieces(prefix, low, np.int64(shifted[:, 0].max()), True, most)
    pieces = [box_bitmaps.nth_piece(prefix, low, start, cuts, c, buffer).copy() for c in range(len(cuts) - 1)]
    np.testing.assert_array_equal(np.concatenate(pieces), expected)
    widest = np.bincount(shifted[:, 0]).max()
    assert all(len(piece) <= max(most, widest) for piece in pieces)
    assert (len(pieces) == 1) == (most >= len(prefix))


@pytest.mark.parametrize("lattice", [True, False])
def test_box_counts_do_not_depend_on_the_pieces(monkeypatch, lattice):
    # A set whose bitmaps outgrow the cache is marked in first-axis order; in pieces of 1000 particles
    # (each marking fills each piece anew) it counts as in one, on every route the caps send it to.
    rng = np.random.default_rng(9)
    points = np.c_[rng.integers(0, 2048, 20_000), rng.integers(0, 1100, 20_000)]
    if not lattice:
        points = points + rng.random(points.shape)
    expected = boxes.prefix_box_counts(points, [5000, 20_000], lattice=lattice)[1]
    monkeypatch.setattr(boxes, "_PIECE_BYTES", 1000 * points[:1].nbytes)
    for cap in (1 << 31, 1 << 16, 1 << 12):
        monkeypatch.setattr(boxes, "_BITMAP_CAP", cap)
        np.testing.assert_array_equal(boxes.prefix_box_counts(points, [5000, 20_000], lattice=lattice)[1], expected)


ROUTES = {
    # How the sides counted from the particles are counted: the settings that force it, and its code.
    "strips of sites": ({}, boxes.STRIPS),
    "every grid in one pass": ({"_STRIP_WORDS_PER_SITE": 0}, boxes.ONE_PASS),
    "grids a few at a time": ({"_STRIP_WORDS_PER_SITE": 0, "_BITMAP_CAP": 1 << 12}, boxes.PASSES),
    "boxes sorted": ({"_BITMAP_CAP": 0}, boxes.SORTED),
    "a grid in bands of rows": ({"_STRIP_WORDS_PER_SITE": 0, "_BITMAP_CAP": 1 << 10}, boxes.BANDS),
}


@pytest.mark.parametrize(
    "kind, route",
    [(kind, route) for kind in ("sites", "centres", "disks") for route in ROUTES
     if kind == "sites" or route != "strips of sites"],  # only integer sites are put in strips
)
@pytest.mark.parametrize("dim", [2, 3])
def test_every_route_from_the_particles_matches_reference(monkeypatch, dim, kind, route):
    # Lattice sites (integers), lattice points anywhere, disks: each route
    # against the rule, on the bases counted from the particles and on the
    # sides halved from them (or, where those do not fit, counted likewise).
    lattice = kind != "disks"
    points = random_set(dim, kind == "sites", 200 if lattice else 60, 40 if dim == 2 else 16, dim)
    settings, code = ROUTES[route]
    for name, value in settings.items():
        monkeypatch.setattr(boxes, name, value)
    counted = boxes.PrefixBoxes(points, None, lattice, None, 4)
    counted.count()
    assert code in counted.routes[0], "the route did not run"
    offsets = naive.grid_offsets(counted.scales)
    np.testing.assert_array_equal(counted.counts[0], [naive.box_count(points, s, lattice, offsets[int(s)])
                                                      for s in counted.scales])
    np.testing.assert_array_equal(box_counts(points, lattice=lattice)[1], counted.counts[0])


def occupied(stack, shape):
    """Each grid's occupied boxes (rows of box indices, sorted) from its bitmap in ``stack``."""
    bits = np.unpackbits(stack.view(np.uint8), axis=-1, bitorder="little")[..., : shape[-1]]
    return [np.argwhere(grid.reshape(tuple(shape))) for grid in bits]


def slab(shape):
    """A grid's shape on the kernels' three axes (a 2D grid has one box on axis 0)."""
    return (1,) * (3 - len(shape)) + tuple(int(n) for n in shape)


def bitmaps(shape, grids):
    padded = slab(shape)
    return np.zeros((grids, padded[0] * padded[1], -(-padded[2] // 64)), np.uint64)


def marked(points, side, offsets, radius):
    """Every grid of ``side`` marked from the particles, in one pass: their bitmaps and shape."""
    shape = np.floor((points.max(axis=0) + radius + 0.5 + offsets[-1]) / side).astype(np.int64) + 1
    stack = bitmaps(shape, len(offsets) ** points.shape[1])
    box_bitmaps.mark_boxes(points.astype(float), np.array(offsets), float(side), radius, slab(shape), 0, stack,
                           np.empty((0, 0), np.int64))
    return stack, shape


def merged(points, side, offsets):
    """Every grid of ``side`` merged from strips of integer sites (one per offset on the last axis)."""
    dim, high = points.shape[1], points.max(axis=0)
    shape = np.floor((high + 0.5 + offsets[-1]) / side).astype(np.int64) + 1
    cells = np.r_[high[:-1] + 1, shape[-1]]
    strips = bitmaps(cells, len(offsets))
    box_bitmaps.mark_sites(points, np.array(offsets), float(side), tuple(int(n) for n in cells[:-1]), strips)
    part, shift = np.zeros((3, len(offsets)), np.int64), np.zeros((3, len(offsets)), np.int64)
    part[2], shift[3 - dim : 2] = np.arange(len(offsets)), offsets
    stack = bitmaps(shape, len(offsets) ** dim)
    count = box_bitmaps.coarsen(strips, slab(cells), part, shift, slab((side,) * (dim - 1) + (1,)), stack, slab(shape))
    return count, stack, shape


def halved(fine, fine_shape, fine_offsets, side, offsets):
    """Every grid of ``side`` from those of half the side (``fine``)."""
    dim = len(fine_shape)
    shape = fine_shape // 2 + 1
    part, shift = boxes._halving(fine_offsets, side // 2, offsets, dim)
    stack = bitmaps(shape, len(offsets) ** dim)
    count = box_bitmaps.coarsen(fine, slab(fine_shape), part, shift, slab((2,) * dim), stack, slab(shape))
    return count, stack, shape


@pytest.mark.parametrize("lattice", [True, False])
@pytest.mark.parametrize("dim", [2, 3])
def test_every_grid_merged_or_halved_holds_the_boxes_marked_from_the_particles(dim, lattice):
    # Grid by grid, not only the least count, on sets wide enough for rows of
    # several words (bits move between words when a halved grid is shifted).
    points = random_set(dim, lattice, 3000 if dim == 2 else 6000, 300 if dim == 2 else 70, 11)
    points = points - points.min(axis=0)
    radius = 0.0 if lattice else 0.5
    offsets = {s: sorted(o) for s, o in naive.grid_offsets([1, 2, 4, 3, 6, 12]).items()}
    for base in (1, 3):
        stack, shape = marked(points, base, offsets[base], radius)
        count = min(map(len, occupied(stack, shape)))
        if lattice and base > 1:  # integer sites: the grids merged from strips, as the lattice measures them
            count, stack, shape = merged(points, base, offsets[base])
        for side in (base, 2 * base, 4 * base):
            if side > base:
                count, stack, shape = halved(stack, shape, offsets[side // 2], side, offsets[side])
            expected = occupied(*marked(points, side, offsets[side], radius))
            assert len(occupied(stack, shape)) == len(expected) == len(offsets[side]) ** dim
            for got, want in zip(occupied(stack, shape), expected):
                np.testing.assert_array_equal(got, want)
            assert count == min(len(grid) for grid in expected)


SELF_SIMILAR = {
    # name: (points, side ratio, pieces, level)
    "gasket": (pascal_gasket(10), 2, 3, 10),
    "square": (np.argwhere(np.ones((1024, 1024), bool)), 2, 4, 10),
    "carpet": (iterated(CARPET, 5), 3, 8, 5),
    "menger": (iterated(MENGER, 4), 3, 20, 4),
    "dust2": (iterated(DUST_2D, 5), 3, 4, 5),
    "dust3": (iterated(DUST_3D, 4), 3, 8, 4),
    "vicsek": (iterated([(0, 1), (1, 0), (1, 1), (1, 2), (2, 1)], 5), 3, 5, 5),  # the plus: axis-aligned arms
}


@pytest.mark.parametrize("lattice", [True, False])
@pytest.mark.parametrize("name", list(SELF_SIMILAR))
def test_self_similar_lattice_sets_give_exact_counts(name, lattice):
    # Disks at integer sites touch the box edges (at half-integers) only from
    # inside, so both rules give the aligned grid's count, and no placement beats it.
    points, ratio, pieces, level = SELF_SIMILAR[name]
    sides = ratio ** np.arange(level + 1)
    _, counts = box_counts(points, lattice=lattice, scales=sides)
    np.testing.assert_array_equal(counts, pieces ** (level - np.arange(level + 1)))
    if ratio == 2:  # the default series holds the powers of two
        scales, counts = box_counts(points, lattice=lattice)
        np.testing.assert_array_equal(counts[np.isin(scales, sides)], pieces ** (level - np.arange(level + 1)))


def dla(dim, model):
    return dlasweep.grow(n=3000, seed=2, dim=dim, model=model).points


@pytest.mark.parametrize(
    "make, lattice",
    [
        (lambda: random_set(2, True, 5000, 300, 1), True),
        (lambda: random_set(3, True, 5000, 60, 2), True),
        (lambda: random_set(2, False, 5000, 300, 3), False),
        (lambda: random_set(3, False, 5000, 60, 4), False),
        (lambda: dla(2, "lattice"), True),
        (lambda: dla(3, "lattice"), True),
        (lambda: dla(2, "offlattice"), False),
        (lambda: dla(3, "offlattice"), False),
    ],
    ids=["random-2d-lattice", "random-3d-lattice", "random-2d-disks", "random-3d-spheres",
         "dla-2d-lattice", "dla-3d-lattice", "dla-2d-offlattice", "dla-3d-offlattice"],
)
def test_counts_never_rise_along_a_family(make, lattice):
    """counts[2s] <= counts[s] for every side s whose double is a side too.

    Why: the box of side 2s of the grid at offset o is the union of 2**dim
    boxes of side s of the grid at offset o % s; a union of boxes is
    occupied iff one of them is (a disk overlaps a union of boxes iff it
    overlaps one of them), and distinct 2s-boxes hold distinct s-boxes. So
    that 2s-grid has at most as many boxes as the s-grid at o % s. And
    O(2s) holds O(s) (each o in O(s) is its own o % s), so the least count
    over the 2s-grids is at most the least over the s-grids.
    """
    scales, counts = box_counts(make(), lattice=lattice)
    count = dict(zip(scales.astype(int).tolist(), counts.tolist()))
    doubles = [s for s in count if 2 * s in count]
    assert len(doubles) >= 8
    for s in doubles:
        assert count[2 * s] <= count[s], (s, count)


def test_gasket_counts_rise_between_families_only_where_every_integer_grid_does():
    # The issue: with sides 2**(k/4) the gasket's count rose from side 2
    # (19683) to 2.38 (about 20700), and within every octave. Whole sides keep
    # each family exact (3**(10-k) at 2**k, checked above) and never rising.
    scales, counts = box_counts(pascal_gasket(10))
    count = dict(zip(scales.astype(int).tolist(), counts.tolist()))
    assert (count[2], count[3], count[4]) == (19683, 15243, 6561)
    # Between families the counts still rise on this set, which is tuned to
    # powers of two: observed 6561 -> 7046 (side 4 -> 5), 2187 -> 2348
    # (8 -> 10), 729 -> 790 (16 -> 20), 9 -> 10 (256 -> 320). The rule does
    # not promise monotone counts across families (a periodic set can make
    # any side look best). At sides 5 and 10 it is the set's doing, not the
    # placement's: no grid at any integer offset does better.
    assert (count[5], count[10]) == (7046, 2348)
    points = pascal_gasket(10)
    for side in (5, 10):
        boxes = [(points + (a, b)) // side for a in range(side) for b in range(side)]
        every = [len(np.unique(x * 4096 + y)) for x, y in (box.T for box in boxes)]
        assert count[side] == min(every)


def test_boxes_are_placed_per_axis_to_minimise_the_count():
    points = np.array([(0, 0), (1, 3), (2, 2)])
    # Side 2 from -1/2 (offset 0) splits the last two points on the first
    # axis; offset 1 on every axis (a diagonal shift, as before) splits them
    # on the second. Only offset 1 on the first axis and 0 on the second
    # puts them in one box.
    assert box_counts(points, scales=[2], offsets=1)[1][0] == 3
    assert box_counts(points + 1, scales=[2], offsets=1)[1][0] == 3  # placement is relative to the set
    assert box_counts(points, scales=[2])[1][0] == 2


@pytest.mark.parametrize(
    "where, lattice_count, offlattice_count",
    [
        # Grid of side 2 from -0.5: edges at 1.5. The disk at (1.1, 1.1) crosses
        # both edges but misses the corner (distance 0.57 > 0.5): 3 boxes, not 4.
        ((1.1, 1.1), 1, 3),
        ((1.2, 1.2), 1, 4),
        # Touching an edge from inside is no overlap.
        ((1.0, 0.0), 1, 1),
    ],
)
def test_offlattice_particle_counts_in_every_box_its_disk_overlaps(where, lattice_count, offlattice_count):
    points = np.array([(0.0, 0.0), where])
    for lattice, expected in ((True, lattice_count), (False, offlattice_count)):
        _, counts = box_counts(points, lattice=lattice, scales=[2.0], offsets=1)
        assert counts[0] == expected


@pytest.mark.parametrize("dim", [2, 3])
def test_a_disk_at_exactly_half_a_unit_from_a_corner_only_touches_it(dim):
    # Side 2 from -0.5: box edges at 1.5. From (1.2089..., 1.0934...) the
    # squared distances to the corner (edge in 3D) add to 0.25 exactly in
    # floating point, in the rule's order: touching, no overlap. The next
    # float nearer the corner overlaps that box too.
    x, y = 1.2089114938035637, 1.093468966055078
    for near, expected in ((y, 3), (np.nextafter(y, 2.0), 4)):
        points = np.array([(0.0, 0.0, 0.0), (x, near, 0.8)])[:, :dim]
        assert box_counts(points, lattice=False, scales=[2.0], offsets=1)[1][0] == expected
        assert naive.box_count(points, 2, False, [0]) == expected


def test_sphere_touches_face_neighbours_but_not_edges_or_corners():
    points = np.array([(0.0, 0.0, 0.0), (1.1, 1.1, 1.1)])
    _, counts = box_counts(points, lattice=False, scales=[2.0], offsets=1)
    # Its own box plus the three across the faces (0.4 away); edges 0.57, corner 0.69.
    assert counts[0] == 4


def test_default_scales_are_families_of_whole_sides_from_one_to_the_extent():
    np.testing.assert_array_equal(default_scales(40), [1, 2, 3, 4, 5, 6, 7, 8, 10, 12, 14, 16, 20, 24, 28, 32, 40])
    assert default_scales(40).dtype == np.float64
    np.testing.assert_array_equal(default_scales(1), [1.0])
    np.testing.assert_array_equal(default_scales(33, per_octave=1), [1, 2, 4, 8, 16, 32, 64])
    np.testing.assert_array_equal(default_scales(30, per_octave=2), [1, 2, 3, 4, 6, 8, 12, 16, 24, 32])
    assert default_scales(9.0)[-1] >= 9.0 > default_scales(9.0)[-2]
    # Every side is an odd base below 2 * per_octave times a power of two.
    for side in default_scales(1e6).astype(int):
        assert side // (side & -side) < 8
    with pytest.raises(ValueError, match="per_octave"):
        default_scales(10, per_octave=3)
    _, counts = box_counts(np.array([(0, 0), (5, 5)]), scales=[1, 100, 1000])
    np.testing.assert_array_equal(counts, [2, 1, 1])


@pytest.mark.parametrize("measure_of", [box_counts, radius_of_gyration, max_radius,
                                        lambda points: measure.anisotropy(points, [1])])
@pytest.mark.parametrize("points, why", [(np.zeros((5, 4)), "got shape"), (np.zeros((0, 2)), "got shape"),
                                          (np.zeros(5), "got shape"), ([[0.0, 1.0], [np.nan, 0.0]], "finite")])
def test_every_measure_refuses_bad_points_alike(measure_of, points, why):
    with pytest.raises(ValueError, match=f"^points: .*{why}"):
        measure_of(points)


def test_bad_input_is_refused():
    with pytest.raises(ValueError, match="scales"):
        box_counts(np.zeros((5, 2)), scales=[0.5, 1])
    with pytest.raises(ValueError, match="scales"):  # whole sides only
        box_counts(np.zeros((5, 2)), scales=[1, 1.7])
    with pytest.raises(ValueError, match="scales"):
        box_counts(np.zeros((5, 2)), scales=[1, np.inf])


@pytest.mark.parametrize("dim", [2, 3])
def test_radius_of_gyration_of_every_prefix_matches_direct_computation(dim):
    rng = np.random.default_rng(dim)
    # Far from the origin, where the textbook <x^2> - <x>^2 loses digits.
    points = rng.normal(size=(400, dim)) * 30 + 1e7
    rg = radius_of_gyration(points)
    np.testing.assert_allclose(rg, naive.radius_of_gyration(points), rtol=1e-9, atol=1e-9)
    assert rg[0] == 0.0


def test_max_radius_of_every_prefix_matches_direct_computation():
    rng = np.random.default_rng(5)
    points = rng.integers(-50, 50, (500, 2))
    np.testing.assert_allclose(max_radius(points), naive.max_radius(points))


def test_anisotropy_matches_cos_4_theta_from_angles():
    from dlasweep.measures.shape import anisotropy

    rng = np.random.default_rng(8)
    points = rng.normal(size=(501, 2)) * 10
    counts = [2, 3, 50, 501]
    np.testing.assert_allclose(anisotropy(points, counts), [naive.anisotropy(points, m) for m in counts], atol=1e-12)


@pytest.mark.parametrize(
    "directions, expected",
    [
        ([(1, 0), (-1, 0), (0, 1), (0, -1)], 1.0),
        ([(1, 1), (-1, 1), (1, -1), (-1, -1)], -1.0),
        ([(1, 0, 0), (0, -1, 0), (0, 0, 1)], 1.0),
        ([(1, 1, 1), (-1, 1, -1)], -2 / 3),
    ],
    ids=["2d axes", "2d diagonals", "3d axes", "3d body diagonals"],
)
def test_anisotropy_of_arms_along_axes_and_diagonals(directions, expected):
    from dlasweep.measures.shape import anisotropy

    arms = np.array(directions, float)
    points = np.r_[np.zeros((1, arms.shape[1])), np.concatenate([arms * k for k in range(1, 21)])]
    assert anisotropy(points, [len(points)])[0] == pytest.approx(expected, abs=1e-12)


@pytest.mark.parametrize("gather", [1, 7, 1 << 16])
@pytest.mark.parametrize("kind", ["lattice ties", "random", "one value", "two values", "a narrow range"])
def test_kth_smallest_squared_distance_is_the_sorted_ones(kind, gather):
    # The anisotropy's median without an array of every distance: histograms narrow the range until
    # ``gather`` values are left. Against a sort, every k, on sets with many ties (lattice sites), a
    # single value, two, and values a few ulps apart (no histogram splits them: they are sorted).
    rng = np.random.default_rng(3)
    points = {"lattice ties": rng.integers(-6, 7, (400, 2)),
              "random": rng.normal(size=(300, 3)),
              "one value": np.array([[0, 0]] + [[3, 4], [4, 3], [-5, 0], [0, 5]] * 20),
              "two values": np.array([[0.0, 0.0]] + [[1.0, 0.0], [0.0, 2.0]] * 30),
              "a narrow range": np.c_[1.0 + np.arange(50) * 2.0**-52, np.zeros(50)]}[kind]
    points = np.r_[np.zeros((1, points.shape[1]), points.dtype), points]
    for m in (2, 3, len(points) // 2, len(points)):
        expected = np.sort(((points[1:m] - points[0]).astype(float) ** 2).sum(axis=1))
        np.testing.assert_array_equal([measure._kth_smallest(points, m, k, gather) for k in range(m - 1)], expected)


def test_anisotropy_equals_the_median_of_a_sorted_array():
    # The streaming anisotropy against the array version it replaced: squared distances in an array,
    # np.median, the outer half's quartic ratio averaged (in order), for lattice and off-lattice clusters.
    def sorted_version(points, m):
        u2 = (points[1:m].astype(float) - points[0].astype(float)) ** 2
        r2, quartic = u2.sum(axis=1), (u2 * u2).sum(axis=1)
        outer = r2 >= np.median(r2)
        ratio = quartic[outer] / r2[outer] ** 2
        c = 3 / (points.shape[1] + 2)
        return (ratio.mean() - c) / (1 - c)

    for model, dim in (("lattice", 2), ("offlattice", 2), ("lattice", 3), ("offlattice", 3)):
        points = dlasweep.grow(3000, 4, model=model, dim=dim).points
        counts = [2, 3, 10, 1001, 3000]
        np.testing.assert_allclose(measure.anisotropy(points, counts), [sorted_version(points, m) for m in counts],
                                   rtol=1e-12, atol=1e-14)


@pytest.mark.parametrize("dim", [2, 3])
def test_anisotropy_of_an_isotropic_cloud_is_zero(dim):
    from dlasweep.measures.shape import anisotropy

    points = np.random.default_rng(dim).normal(size=(200_001, dim))
    points[0] = 0  # the seed at the centre of the cloud
    # The outer 1e5 directions: the mean of a quantity of spread < 0.75 has a
    # standard error below 0.0024; 5 of those bound it.
    assert abs(anisotropy(points, [len(points)])[0]) < 0.012


@pytest.mark.slow
def test_square_lattice_clusters_grow_along_the_axes_and_continuum_ones_do_not():
    import dlasweep as dla
    from dlasweep.measures.shape import anisotropy
    from dlasweep.stats.fit import ensemble

    lattice = ensemble([anisotropy(dla.grow(n=30_000, seed=s).points, [30_000])[0] for s in range(6)])
    continuum = ensemble([anisotropy(dla.grow(n=10_000, seed=s, model="offlattice").points, [10_000])[0]
                          for s in range(12)])
    # Measured here: lattice 0.2-0.6 per cluster at 3e4 (0.21 at 1e4, 0.64 at 1e6 in the issue);
    # off-lattice scatters by ~0.2 about 0 (a handful of arms).
    assert lattice.mean - 3 * lattice.stderr > 0.1, lattice
    assert abs(continuum.mean) < 3 * continuum.stderr + 0.05, continuum


def prefixes_one_by_one(points, ends, lattice, scales):
    return np.stack([box_counts(points[:m], lattice=lattice, scales=scales)[1] for m in ends])


def some_prefixes(n, rng):
    """The whole set, its first point, and a few lengths between, unsorted, one repeated."""
    ends = [n, 1, *rng.integers(1, n + 1, 5)]
    return ends + ends[-1:]


@pytest.mark.parametrize("lattice", [True, False])
@pytest.mark.parametrize("dim", [2, 3])
def test_every_prefix_counted_at_once_equals_box_counts_of_that_prefix(dim, lattice):
    # DLA clusters of every model, random sets of integer sites and of points
    # anywhere (wide and narrow, so both sparse and full grids), at the
    # default scales of the whole set and at a sweep's longer axis.
    rng = np.random.default_rng(dim + 2 * lattice)
    sets = [dlasweep.grow(n, seed, dim=dim, model="lattice" if lattice else "offlattice").points
            for n, seed in [(300, 0), (2000, 1), (2000, 2)]]
    for seed in range(6):
        n, width = int(rng.integers(2, 400)), int(rng.integers(2, 200 if dim == 2 else 40))
        sets.append(random_set(dim, seed % 2 == 0, n, width, seed) - width // 2)
    for points in sets:
        ends = some_prefixes(len(points), rng)
        for scales in (None, default_scales(len(points) + 2)):
            got_scales, got = boxes.prefix_box_counts(points, ends, lattice=lattice, scales=scales)
            np.testing.assert_array_equal(got_scales, box_counts(points, scales=scales)[0] if scales is None
                                          else scales)
            np.testing.assert_array_equal(got, prefixes_one_by_one(points, ends, lattice, got_scales))


@pytest.mark.parametrize("cap", [0, 1 << 10, 1 << 14])
@pytest.mark.parametrize("lattice", [True, False])
@pytest.mark.parametrize("dim", [2, 3])
def test_every_prefix_at_once_takes_the_routes_box_counts_takes(monkeypatch, dim, lattice, cap):
    # Small caps send sides to the particles, a few grids at a time, or (0)
    # to sorting their boxes; strips of sites are tried
    # with and without their cost rule. Sorting every side's boxes is slow
    # (it is the route of sets too wide for any bitmap): a fifth of the points.
    n = (1500 if dim == 2 else 400) // (5 if cap == 0 else 1)
    points = random_set(dim, True, n, 100 if dim == 2 else 20, 5)
    if not lattice:
        points = points + np.random.default_rng(6).random(points.shape)
    ends = some_prefixes(len(points), np.random.default_rng(7))
    monkeypatch.setattr(boxes, "_BITMAP_CAP", cap)
    for strips in (2, 0):
        monkeypatch.setattr(boxes, "_STRIP_WORDS_PER_SITE", strips)
        scales, got = boxes.prefix_box_counts(points, ends, lattice=lattice)
        np.testing.assert_array_equal(got, prefixes_one_by_one(points, ends, lattice, scales))


def test_prefix_box_counts_refuses_bad_input():
    with pytest.raises(ValueError, match="ends"):
        boxes.prefix_box_counts(np.zeros((3, 2)), [0, 3])
    with pytest.raises(ValueError, match="ends"):
        boxes.prefix_box_counts(np.zeros((3, 2)), [4])
    with pytest.raises(ValueError, match="scales"):
        boxes.prefix_box_counts(np.zeros((3, 2)), [3], scales=[1, 2.5])
    with pytest.raises(ValueError, match="points"):
        boxes.prefix_box_counts(np.zeros((3, 4)), [3])


@pytest.mark.parametrize("lattice", [True, False])
@pytest.mark.parametrize("dim", [2, 3])
def test_cluster_measures_equal_the_functions_they_gather(dim, lattice):
    # The sweep's one call per cluster against each measure on its own, bit
    # for bit: clusters, random sets (sparse and full), sites beyond int32
    # (box counts handed to box_counts), and history counts past the end.
    rng = np.random.default_rng(10 + dim + 2 * lattice)
    sets = [dlasweep.grow(n, seed, dim=dim, model="lattice" if lattice else "offlattice").points
            for n, seed in [(1, 0), (400, 1), (1500, 2)]]
    sets += [random_set(dim, seed % 2 == 0, int(rng.integers(2, 300)), 60, seed) for seed in range(4)]
    if dim == 2:  # (in 3D, box_counts sorts 16**3 grids' boxes per side: slow, and the same route)
        sets.append(random_set(dim, True, 12, 20, 9) * (2**30))
    for points in sets:
        n = len(points)
        ends = np.array(some_prefixes(n, rng))
        history = np.unique(np.r_[1, rng.integers(1, 2 * n + 2, 6)])
        scales = default_scales(min(np.ptp(points, axis=0).max() + 2, 3000))
        got = measure.cluster_measures(points, ends, history, lattice=lattice, scales=scales)
        rg = radius_of_gyration(points)
        np.testing.assert_array_equal(got["box_count"], boxes.prefix_box_counts(points, ends, lattice, scales)[1])
        np.testing.assert_array_equal(got["radius_gyration"], rg[ends - 1])
        np.testing.assert_array_equal(got["radius_gyration_history"],
                                      np.where(history <= n, rg[np.minimum(history, n) - 1], np.nan))
        np.testing.assert_array_equal(got["max_radius"], max_radius(points)[ends - 1])
        np.testing.assert_array_equal(got["anisotropy"], measure.anisotropy(points, ends))
    with pytest.raises(ValueError, match="history"):
        measure.cluster_measures(np.zeros((3, 2)), [3], [0])


@pytest.mark.parametrize("high, ordered", [((91, 92), False), ((2047, 1100), True), ((63, 63, 63), False),
                                           ((200, 200, 200), True), ((5e6, 3.0), False)])
def test_particles_are_put_in_first_axis_order_only_where_their_bitmaps_outgrow_the_cache(high, ordered):
    # 92 x 2 words of 8 bytes, or 2048 x 18; a 3D set of 64 x 64 rows of 1 word, or 201 x 201 of 4 words;
    # a first axis longer than the sort's table allows (and than the set's size) is never sorted.
    points = np.zeros((1000, len(high)))
    assert box_bitmaps.ordered(points, np.array(high, float)) is ordered
