"""The lattice kernel's exact machinery: square/cube exit laws and their alias tables."""

import numpy as np
import pytest
from scipy.stats import chi2

from dlasweep.kernels.lattice import TABLE_MAX, _moves, exit_law, exit_tables


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
    assert sorted(map(tuple, sites)) == sorted(map(tuple, _moves(2, False)[:, :2]))
    np.testing.assert_allclose(probs, 0.25)


@pytest.mark.parametrize("dim, moore, r", [(2, False, 3), (2, True, 4), (3, False, 2), (3, True, 2)])
def test_exit_law_matches_single_steps(dim, moore, r):
    """Chi-square of 40000 seeded brute-force walks against the law.

    Sites are pooled by symmetry class (sorted absolute coordinates) so every
    class expects hundreds of hits; at the 0.1% level a correct law fails
    one run in a thousand, a wrong one (e.g. the Brownian harmonic measure,
    which differs by several percent near corners) fails every time.
    """
    rng = np.random.default_rng(5)
    moves = _moves(dim, moore)[:, :dim]
    walks = 40_000
    x = np.zeros((walks, dim), np.int64)
    alive = np.ones(walks, bool)
    while alive.any():
        idx = np.flatnonzero(alive)
        x[idx] += moves[rng.integers(len(moves), size=len(idx))]
        alive[idx] = np.abs(x[idx]).max(1) < r
    sites, probs = exit_law(dim, moore, r)
    key = lambda s: tuple(sorted(np.abs(s)))  # noqa: E731
    classes = sorted({key(s) for s in sites})
    expected = np.array([probs[[key(s) == c for s in sites]].sum() for c in classes]) * walks
    observed = np.array([sum(key(s) == c for s in x) for c in classes])
    assert observed.sum() == walks
    stat = ((observed - expected) ** 2 / expected).sum()
    assert stat < chi2.ppf(0.999, len(classes) - 1)


@pytest.mark.parametrize("dim, moore", [(2, False), (3, True)])
def test_alias_tables_reproduce_the_law(dim, moore):
    """The alias table's implied probabilities equal the exit law exactly."""
    start, cut, alias, offsets = exit_tables(dim, moore)
    for r in (2, 7, TABLE_MAX[dim]):
        lo, hi = start[r], start[r + 1]
        k = hi - lo
        implied = cut[lo:hi] / k
        np.add.at(implied, alias[lo:hi], (1 - cut[lo:hi]) / k)
        sites, probs = exit_law(dim, moore, r)
        assert (offsets[lo:hi, :dim] == sites).all()
        np.testing.assert_allclose(implied, probs, rtol=1e-9, atol=1e-15)
