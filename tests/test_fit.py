"""Dimension fits on sets of known dimension, refusals, and ensemble statistics."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from dlasweep.fit import ensemble, fit_dimension, fit_mass_radius
from dlasweep.measure import box_counts, radius_of_gyration


def iterated(pieces, level):
    """Lattice points of a self-similar set: ``pieces`` are the kept sub-blocks of a base**dim block."""
    pieces = np.array(pieces)
    base = pieces.max() + 1
    points = np.zeros((1, pieces.shape[1]), np.int64)
    for _ in range(level):
        points = (points[:, None, :] * base + pieces[None]).reshape(-1, pieces.shape[1])
    return points


def sierpinski_triangle(level):
    """Pascal's triangle mod 2: the sites (x, y) of a 2**level square with x & y == 0."""
    x, y = np.meshgrid(np.arange(2**level), np.arange(2**level))
    keep = (x & y) == 0
    return np.c_[x[keep], y[keep]]


CARPET = [p for p in itertools.product(range(3), repeat=2) if p != (1, 1)]
DUST = list(itertools.product((0, 2), repeat=2))

# (points, exact D, tolerance, straight). Finite sets read low: boxes at
# their edge are partly empty, N(s) = ceil(L/s)**dim for a filled block, which
# bends the 100**3 cube's 1.2 decades enough for the fit to say so. Lacunar
# sets (triangle, dust) oscillate log-periodically between the scales of their
# construction, so their curves are not straight at 4 scales per octave either.
KNOWN = {
    "line": (np.c_[np.arange(2000), np.zeros(2000, np.int64)], 1.0, 0.02, True),
    "square": (np.argwhere(np.ones((300, 300))), 2.0, 0.05, True),
    "cube": (np.argwhere(np.ones((100, 100, 100))), 3.0, 0.15, False),
    "sierpinski carpet": (iterated(CARPET, 6), np.log(8) / np.log(3), 0.04, True),
    "sierpinski triangle": (sierpinski_triangle(10), np.log(3) / np.log(2), 0.05, False),
    "cantor dust": (iterated(DUST, 6), np.log(4) / np.log(3), 0.05, False),
    "uniform random": (np.random.default_rng(1).random((200_000, 2)) * 400, 2.0, 0.06, True),
}


@pytest.mark.parametrize("lattice", [True, False], ids=["lattice", "offlattice"])
@pytest.mark.parametrize("name", list(KNOWN))
def test_box_counting_dimension_of_known_sets(name, lattice):
    points, exact, tolerance, straight = KNOWN[name]
    fit = fit_dimension(*box_counts(points, lattice=lattice))
    assert abs(fit.D - exact) <= tolerance, fit
    assert fit.ok == straight, fit
    assert fit.lo >= 2 and fit.hi / fit.lo >= 10 and fit.stderr > 0
    if not straight:
        assert "straight" in fit.reason


def test_exact_power_law_is_recovered_with_its_range():
    scales = 2.0 ** (np.arange(41) / 4)
    counts = 1e9 * scales**-1.7
    counts[-1] = 1  # the set's extent: 1024
    fit = fit_dimension(scales, counts)
    assert fit.ok and abs(fit.D - 1.7) < 1e-9 and fit.stderr < 1e-9
    assert fit.lo == 2.0 and fit.hi == 256.0


@pytest.mark.parametrize(
    "points, reason",
    [
        (np.array([(0, 0), (1, 0), (0, 1)]), "admissible points"),
        (np.argwhere(np.ones((12, 12))), "admissible points"),
        (np.argwhere(np.ones((30, 30))), "decades"),
    ],
)
def test_fit_refuses_sets_too_small_to_show_scaling(points, reason):
    fit = fit_dimension(*box_counts(points))
    assert not fit.ok and reason in fit.reason


def test_fit_refuses_a_curved_log_log_plot():
    scales = 2.0 ** (np.arange(41) / 4)
    x = np.log(scales)
    counts = np.exp(25 - 0.8 * x - 0.12 * x**2)  # local slope runs from 1.0 to 2.5
    counts[-1] = 1
    fit = fit_dimension(scales, counts)
    assert not fit.ok and "straight" in fit.reason


def test_fit_finds_the_straight_part_of_a_broken_power_law():
    scales = 2.0 ** (np.arange(49) / 4)
    x = np.log(scales)
    # Slope 1 up to s = 64, slope 2 beyond, as a crossover would give.
    counts = np.exp(np.where(x < np.log(64), 30 - x, 30 - np.log(64) - 2 * (x - np.log(64))))
    counts[-1] = 1
    fit = fit_dimension(scales, counts)
    # One branch (within what the drift rule lets in), not the average 1.5.
    assert fit.ok and (abs(fit.D - 1) < 0.05 or abs(fit.D - 2) < 0.05), fit


def test_mass_radius_recovers_a_power_law_history_and_skips_the_transient():
    n = np.arange(1, 20_001)
    rng = np.random.default_rng(2)
    rg = n ** (1 / 1.71) * np.exp(0.01 * rng.standard_normal(len(n)))
    rg[:200] = 1.0  # a transient the rule must leave out
    fit = fit_mass_radius(n, rg)
    assert fit.ok and abs(fit.D - 1.71) < 0.01, fit
    assert fit.lo >= 0.05 * n[-1] and fit.hi == n[-1]


def test_mass_radius_refuses_a_short_history():
    n = np.arange(1, 301)
    fit = fit_mass_radius(n, n**0.6)
    assert not fit.ok and "decades" in fit.reason


@pytest.mark.slow
def test_mass_radius_dimension_of_offlattice_dla_is_near_1_71():
    import dlasweep as dla

    values = []
    for seed in range(12):
        points = dla.grow(n=10_000, seed=seed, model="offlattice").points
        rg = radius_of_gyration(points)
        values.append(fit_mass_radius(np.arange(1, len(rg) + 1), rg).D)
    stats = ensemble(values)
    # One cluster's D scatters by ~0.04, so 12 give a standard error of ~0.012;
    # allow 3 of those plus 0.03 for corrections to scaling at N = 1e4.
    assert stats.n == 12 and stats.std < 0.08
    assert abs(stats.mean - 1.71) < 3 * stats.stderr + 0.03, stats


def test_ensemble_statistics_match_numpy_and_rerun_identically():
    values = np.random.default_rng(4).normal(1.7, 0.05, 16)
    stats = ensemble(np.r_[values, np.nan])
    assert stats.n == 16
    assert stats.mean == pytest.approx(values.mean())
    assert stats.std == pytest.approx(values.std(ddof=1))
    assert stats.stderr == pytest.approx(values.std(ddof=1) / 4)
    # The bootstrap interval of the mean is about mean +- 1.96 stderr.
    assert stats.ci_lo < stats.mean < stats.ci_hi
    assert (stats.ci_hi - stats.ci_lo) / (2 * 1.96 * stats.stderr) == pytest.approx(1, abs=0.15)
    assert ensemble(values) == ensemble(values)
    assert ensemble(values, seed=1) != ensemble(values)


def test_ensemble_of_too_few_values_gives_nan_not_numbers():
    one = ensemble([1.7, np.nan])
    assert one.n == 1 and one.mean == 1.7 and np.isnan(one.std) and np.isnan(one.ci_lo)
    assert ensemble([]).n == 0 and np.isnan(ensemble([]).mean)
