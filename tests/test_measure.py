"""Box counts and mass-radius measures against slow, obviously right versions."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from dlasweep.measure import box_counts, default_scales, mass_within, max_radius, radius_of_gyration


def slow_box_count(points, scale, lattice, offsets=4):
    """The documented rule, one point and one box at a time."""
    points = np.asarray(points, float)
    points = points - points.min(axis=0)  # so the extreme disks touch the first box's edge exactly
    best = None
    for j in range(offsets):
        origin = np.full(points.shape[1], -0.5 - j / offsets * scale)
        boxes = set()
        for p in points:
            if lattice:
                boxes.add(tuple(np.floor((p - origin) / scale).astype(int)))
                continue
            u = p - origin  # in the grid's frame, box b spans [b * scale, (b + 1) * scale)
            home = np.floor(u / scale).astype(int)
            for step in itertools.product((-1, 0, 1), repeat=len(p)):
                box = home + np.array(step)
                nearest = np.clip(u, box * scale, (box + 1) * scale)
                if ((u - nearest) ** 2).sum() < 0.25:
                    boxes.add(tuple(box))
        best = len(boxes) if best is None else min(best, len(boxes))
    return best


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("lattice", [True, False])
def test_box_counts_match_slow_reference(dim, lattice):
    rng = np.random.default_rng(dim + 10 * lattice)
    points = rng.integers(0, 40, (300, dim)) if lattice else rng.random((120, dim)) * 40
    # Default scales reach 64: the scales from 4 up are counted from coarser
    # grids of the scale a quarter their size, so both code paths are checked.
    scales, counts = box_counts(points, lattice=lattice)
    assert scales[-1] >= 40
    expected = [slow_box_count(points, s, lattice) for s in scales]
    np.testing.assert_array_equal(counts, expected)


def test_box_counts_on_arbitrary_scales_match_reference():
    rng = np.random.default_rng(3)
    points = rng.random((200, 2)) * 30
    scales = [1.0, 1.7, 3.0, 5.5, 12.0, 13.0]
    _, counts = box_counts(points, lattice=False, scales=scales, offsets=3)
    np.testing.assert_array_equal(counts, [slow_box_count(points, s, False, offsets=3) for s in scales])



@pytest.mark.parametrize("lattice", [True, False])
@pytest.mark.parametrize("spread", [(1e5, 1e5), (2e3, 2e3, 2e3)], ids=["2d", "3d"])
def test_box_counts_of_sets_too_wide_for_a_bitmap_match_reference(spread, lattice):
    # Two clumps so far apart that the grids up to s = 2 have more boxes than
    # a bitmap may hold: those are counted by sorting, the coarser ones not.
    rng = np.random.default_rng(4)
    points = rng.random((60, len(spread))) * 20
    points = np.r_[points, points + np.array(spread)]
    if lattice:
        points = np.round(points)
    scales = [1.0, 1.5, 2.0, 4.0, 6.0]
    _, counts = box_counts(points, lattice=lattice, scales=scales)
    np.testing.assert_array_equal(counts, [slow_box_count(points, s, lattice) for s in scales])


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


def test_sphere_touches_face_neighbours_but_not_edges_or_corners():
    points = np.array([(0.0, 0.0, 0.0), (1.1, 1.1, 1.1)])
    _, counts = box_counts(points, lattice=False, scales=[2.0], offsets=1)
    # Its own box plus the three across the faces (0.4 away); edges 0.57, corner 0.69.
    assert counts[0] == 4


def test_boxes_are_placed_to_minimise_the_count():
    pair = np.array([(0, 0), (1, 0)])
    # From -0.5, boxes of 1.5 end at 1.0 and split the pair; the shift by
    # 3/4 of a box puts both in [-0.125, 1.375).
    assert box_counts(pair, scales=[1.5], offsets=1)[1][0] == 2
    assert box_counts(pair, scales=[1.5], offsets=4)[1][0] == 1


def test_default_scales_are_a_geometric_series_from_one_to_the_extent():
    np.testing.assert_allclose(default_scales(8), 2.0 ** (np.arange(13) / 4))
    np.testing.assert_array_equal(default_scales(1), [1.0])
    assert default_scales(9.0)[-1] >= 9.0 > default_scales(9.0)[-2]
    _, counts = box_counts(np.array([(0, 0), (5, 5)]), scales=[1, 100, 1000])
    np.testing.assert_array_equal(counts, [2, 1, 1])


def test_bad_input_is_refused():
    with pytest.raises(ValueError, match="points"):
        box_counts(np.zeros((5, 4)))
    with pytest.raises(ValueError, match="scales"):
        box_counts(np.zeros((5, 2)), scales=[0.5, 1])


@pytest.mark.parametrize("dim", [2, 3])
def test_radius_of_gyration_of_every_prefix_matches_direct_computation(dim):
    rng = np.random.default_rng(dim)
    # Far from the origin, where the textbook <x^2> - <x>^2 loses digits.
    points = rng.normal(size=(400, dim)) * 30 + 1e7
    rg = radius_of_gyration(points)
    direct = [np.sqrt(((points[:k] - points[:k].mean(axis=0)) ** 2).sum(axis=1).mean()) for k in range(1, 401)]
    np.testing.assert_allclose(rg, direct, rtol=1e-9, atol=1e-9)
    assert rg[0] == 0.0


def test_max_radius_and_mass_within_match_direct_computation():
    rng = np.random.default_rng(5)
    points = rng.integers(-50, 50, (500, 2))
    distance = np.sqrt(((points - points[0]) ** 2).sum(axis=1))
    np.testing.assert_allclose(max_radius(points), [distance[:k].max() for k in range(1, 501)])
    radii = np.array([0.0, 1.0, 10.0, 33.3, 1e3])
    np.testing.assert_array_equal(mass_within(points, radii), [(distance <= r).sum() for r in radii])
