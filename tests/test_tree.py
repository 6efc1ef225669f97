"""Branch statistics of trees whose answers are known (``dlasweep.measures.tree``)."""

import sys
import time

import numpy as np
import pytest

from dlasweep.measures import tree


def complete_binary(depth):
    """Parents of the complete binary tree of the given depth, in breadth-first order."""
    i = np.arange(2 ** (depth + 1) - 1)
    return np.where(i > 0, (i - 1) // 2, -1).astype(np.int32)


def random_forest(n, roots, rng):
    """Each particle's parent drawn uniformly among the earlier ones, the first ``roots`` without."""
    parents = (rng.random(n) * np.arange(n)).astype(np.int32)
    parents[:roots] = -1
    # some chains, as DLA's branches grow: a fifth of the particles hang on the one just before
    chain = rng.random(n) < 0.2
    parents[chain & (np.arange(n) >= roots)] = np.arange(n)[chain & (np.arange(n) >= roots)] - 1
    return parents


def naive(parents):
    """Orders, generations and branch counts by recursion over children lists: the definitions as written."""
    children = [[] for _ in parents]
    for i, p in enumerate(parents):
        if p >= 0:
            children[p].append(i)

    def order(i):
        below = [order(c) for c in children[i]]
        if not below:
            return 1
        top = max(below)
        return top + 1 if below.count(top) >= 2 else top

    orders = [order(i) for i in range(len(parents))]

    def depth(i):
        return 0 if parents[i] < 0 else depth(parents[i]) + 1

    counts = {}
    for i, p in enumerate(parents):
        # a branch of order k starts where the parent has a higher order, or at a root
        if p < 0 or orders[p] > orders[i]:
            counts[orders[i]] = counts.get(orders[i], 0) + 1
    top = max(orders)
    return (np.array(orders), np.array([depth(i) for i in range(len(parents))]),
            np.array([counts.get(k, 0) for k in range(1, top + 1)]))


@pytest.mark.parametrize("depth", [1, 2, 5, 10])
def test_complete_binary_tree(depth):
    parents = complete_binary(depth)
    counts = tree.branch_counts(parents)
    np.testing.assert_array_equal(counts, [2 ** (depth - i) for i in range(depth + 1)])
    assert tree.bifurcation_ratio(counts, min_branches=1) == pytest.approx(2.0)
    # by default only the orders with MIN_BRANCHES branches or more: those of 2**(depth - i) >= 10
    ratio = tree.bifurcation_ratio(counts)
    assert ratio == pytest.approx(2.0) if depth >= 5 else np.isnan(ratio)
    gen = tree.generations(parents)
    assert gen.max() == depth and (np.bincount(gen) == 2 ** np.arange(depth + 1)).all()
    assert tree.strahler(parents)[0] == depth + 1


def test_a_path_is_one_branch():
    parents = np.arange(1000, dtype=np.int32) - 1
    np.testing.assert_array_equal(tree.branch_counts(parents), [1])
    assert np.isnan(tree.bifurcation_ratio([1], min_branches=1))
    np.testing.assert_array_equal(tree.generations(parents), np.arange(1000))
    assert tree.chemical_dimension(parents) == pytest.approx(1.0, abs=1e-2)


def test_bifurcation_ratio_leaves_out_the_sparse_orders():
    """Counts 500, 100, 20, 8, 4: the orders with 10 or more fall by exactly 5, the last two (cut short) by less."""
    assert tree.bifurcation_ratio([500, 100, 20, 8, 4]) == pytest.approx(5.0)
    assert tree.bifurcation_ratio([500, 100, 20, 8, 4], min_branches=1) < 4.5


def test_one_particle_and_no_particle():
    np.testing.assert_array_equal(tree.branch_counts(np.array([-1])), [1])
    assert len(tree.branch_counts(np.zeros(0, np.int32))) == 0


@pytest.mark.parametrize("seed", range(6))
def test_random_trees_against_the_naive_reference(seed):
    rng = np.random.default_rng(seed)
    parents = random_forest(int(rng.integers(1, 3000)), int(rng.integers(1, 4)), rng)
    orders, gen, counts = naive(parents)
    np.testing.assert_array_equal(tree.strahler(parents), orders)
    np.testing.assert_array_equal(tree.generations(parents), gen)
    np.testing.assert_array_equal(tree.branch_counts(parents), counts)


def test_chemical_dimension_of_a_square_grid_tree():
    """The breadth-first tree of a square of sites from its centre: mass within l bonds ~ 2 l**2."""
    half = 200
    x, y = np.meshgrid(np.arange(-half, half + 1), np.arange(-half, half + 1), indexing="ij")
    x, y = x.ravel(), y.ravel()
    order = np.lexsort((y, x, np.abs(x) + np.abs(y)))  # by Manhattan distance: parents come first
    x, y = x[order], y[order]
    index = {(a, b): i for i, (a, b) in enumerate(zip(x.tolist(), y.tolist()))}
    # parent: one step towards the centre, along x first
    parents = np.array([-1 if a == b == 0 else index[(a - np.sign(a), b) if a else (a, b - np.sign(b))]
                        for a, b in zip(x.tolist(), y.tolist())], np.int32)
    assert (parents < np.arange(len(parents))).all()
    assert tree.chemical_dimension(parents) == pytest.approx(2.0, abs=0.05)


def test_ten_million_particles_take_no_recursion_and_little_time():
    n = 10_000_000
    parents = np.arange(n, dtype=np.int32) - 1  # the deepest tree there is
    limit = sys.getrecursionlimit()
    tree.branching(parents[:10])  # compiled
    start = time.perf_counter()
    result = tree.branching(parents)
    assert time.perf_counter() - start < 30  # 4 s on a shared 2-core machine
    np.testing.assert_array_equal(result["branch_counts"], [1])
    assert result["max_generation"] == n - 1 and sys.getrecursionlimit() == limit
