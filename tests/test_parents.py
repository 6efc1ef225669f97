"""Who stuck to whom: ``Cluster.parents`` in every model and variant of ``dla.grow``."""

import itertools

import numpy as np
import pytest

import dlasweep as dla
from dlasweep.growth.cluster import grow_many
from dlasweep.kernels.lattice.exits import unit_moves
from dlasweep.kernels.lattice.parents import lattice_parents
from naive import seed_count
from test_models import CASES

N = 600


@pytest.fixture(scope="module", params=sorted(CASES))
def grown(request):
    return request.param, dla.grow(N, seed=5, **CASES[request.param])


def _offsets(c, parents):
    """Child minus parent, the nearest periodic image on a substrate's sides."""
    d = (c.points - c.points[parents]).astype(np.float64)
    if c.params["seed_shape"] == "line":
        period = c.params["size"]
        d[:, :-1] -= period * np.round(d[:, :-1] / period)
    return d


def _on_substrate(c) -> np.ndarray:
    """Whether each particle rests on a substrate."""
    return (c.params["seed_shape"] == "line") & (np.abs(c.points[:, -1]) < 1e-9)


def roots(parents) -> np.ndarray:
    """The root of each particle's chain of parents (by pointer jumping)."""
    up = np.where(parents >= 0, parents, np.arange(len(parents)))
    while True:
        nxt = up[up]
        if (nxt == up).all():
            return up
        up = nxt


def test_parents_form_a_tree_in_attachment_order(grown):
    _, c = grown
    p = c.parents
    assert p.dtype == np.int32 and p.shape == (c.n,)
    i = np.arange(c.n)
    assert (p < i).all() and (p >= -1).all()
    seeds = seed_count(c.params)
    assert (p[:seeds] == -1).all()
    # -1 only for the seed and for particles on the substrate
    np.testing.assert_array_equal(p[seeds:] == -1, _on_substrate(c)[seeds:])
    # connected: every chain ends at a seed particle or on the substrate
    r = roots(p)
    assert ((r < seeds) | _on_substrate(c)[r]).all()


def test_every_parent_touches_its_child(grown):
    _, c = grown
    child = np.flatnonzero(c.parents >= 0)
    d = _offsets(c, c.parents)[child]
    if c.params["model"] == "lattice":
        moves = unit_moves(c.params["dim"], c.params["neighbours"] != 2 * c.params["dim"])[:, :c.params["dim"]]
        assert (np.abs(d[:, None, :] - moves[None]).max(axis=2) == 0).any(axis=1).all()
    else:
        np.testing.assert_allclose(np.linalg.norm(d, axis=1), 1.0, atol=1e-9)


def test_parent_follows_its_models_rule(grown):
    """On the lattice, of the occupied neighbours at attachment the earliest
    (the substrate before any); off it, the disk touched, which is the
    nearest earlier one (nothing overlaps)."""
    name, c = grown
    if c.params["model"] == "lattice":
        _lattice_rule(name, c)
    else:
        _offlattice_rule(name, c)


def _lattice_rule(name, c):
    dim, period = c.params["dim"], c.params["size"]
    moves = unit_moves(dim, c.params["neighbours"] != 2 * dim)[:, :dim]
    index = {}
    for i, site in enumerate(map(tuple, c.points)):
        want = -1
        if i >= seed_count(c.params) and not (c.params["seed_shape"] == "line" and site[-1] == 0):
            near = []
            for m in moves:
                q = np.array(site) + m
                if c.params["seed_shape"] == "line":
                    q[:-1] %= period
                near += [index[tuple(q)]] if tuple(q) in index else []
            want = min(near)
        assert c.parents[i] == want, f"{name}: particle {i}"
        index[site] = i


def _offlattice_rule(name, c):
    for i in np.flatnonzero(c.parents >= 0)[::7]:
        d = c.points[:i] - c.points[i]
        if c.params["seed_shape"] == "line":
            d[:, :-1] -= c.params["size"] * np.round(d[:, :-1] / c.params["size"])
        assert np.argmin(np.linalg.norm(d, axis=1)) == c.parents[i], f"{name}: particle {i}"


def test_parents_are_prefixes():
    for kw in (CASES["lattice-2d"], CASES["off-2d"]):
        big, small = dla.grow(400, seed=2, **kw), dla.grow(150, seed=2, **kw)
        np.testing.assert_array_equal(small.parents, big.parents[:150])


def test_grow_many_gives_the_same_parents():
    for kw in (CASES["lattice-3d"], CASES["off-3d"]):
        many = grow_many(200, [3, 4], **kw)
        for seed, c in zip([3, 4], many):
            np.testing.assert_array_equal(c.parents, dla.grow(200, seed=seed, **kw).parents)


def test_lattice_parents_on_a_known_path():
    """A hand-made chain that bends back next to an earlier site: the earliest neighbour wins."""
    # 0 at the origin, then right, up, left: particle 3 touches 0 and 2
    points = np.array([[0, 0], [1, 0], [1, 1], [0, 1], [-1, 1]], np.int32)
    moves = unit_moves(2, False)
    np.testing.assert_array_equal(lattice_parents(points, moves, 1, 0), [-1, 0, 1, 0, 3])
    # Moore contacts: particle 2 also touches 0 diagonally
    np.testing.assert_array_equal(lattice_parents(points, unit_moves(2, True), 1, 0), [-1, 0, 0, 0, 0])
    # on a substrate of period 3 (height is the last axis): height 0 is -1, the sides wrap
    line = np.array([[0, 0], [0, 1], [2, 1]], np.int32)
    np.testing.assert_array_equal(lattice_parents(line, moves, 0, 3), [-1, 0, 1])
    hashed = np.array(list(itertools.product(range(-40, 40), range(-40, 40))), np.int32)
    assert (lattice_parents(hashed, moves, 1, 0)[1:] >= 0).all()  # a full block: every site found


@pytest.mark.parametrize("name", ["lattice-2d", "lattice-3d"])
def test_lattice_parents_across_the_directory(name):
    """Clusters that span several of the directory's squares (cubes) of tiles on every axis (2D 256
    sites, 3D 32), which the last pass reads in their order: the naive rule still holds."""
    c = dla.grow(20_000, seed=3, **CASES[name])
    span = np.ptp(c.points, axis=0)
    assert (span > 2 * (256 if c.params["dim"] == 2 else 32)).all()
    _lattice_rule(name, c)
