"""D(q) and f(alpha) of measures whose spectrum is known exactly: multiplicative cascades built here.

A binomial cascade splits each cell's measure between its halves (quarters, in 2D) with fixed
weights w_i, so that tau(q) = -log2 sum_i w_i**q exactly and D(q) = tau(q) / (q - 1); its sample
is M counts, each a cell drawn by L independent choices of a child. The error bars must hold:
every q's exact D within its 95% interval, ``ok`` where the sample resolves the sums.
"""

import numpy as np
import pytest

from dlasweep.stats.fit import Z95
from dlasweep.stats.multifractal import multifractal_spectrum

Q = np.arange(0.0, 6.01, 1.0)


def cascade(weights, dim, level, counts, seed):
    """``counts`` draws from the cascade of ``weights`` (2**dim of them) to ``level``: cells and their counts."""
    rng = np.random.default_rng(seed)
    child = rng.choice(len(weights), size=(counts, level), p=weights)
    place = 1 << np.arange(level - 1, -1, -1)
    cells = np.stack([(((child >> a) & 1) * place).sum(axis=1) for a in range(dim)], axis=1)
    if dim == 1:
        cells = np.concatenate([cells, np.zeros_like(cells)], axis=1)  # on a line of the plane
    where, n = np.unique(cells, axis=0, return_counts=True)
    return where + 0.5, n


def exact_d(weights, q):
    w = np.asarray(weights)
    return np.array([-(w * np.log2(w)).sum() if np.isclose(x, 1) else np.log2((w ** x).sum()) / (1 - x) for x in q])


def exact_alpha_f(weights, q):
    """The Legendre transform of tau(q) = -log2 sum w**q: alpha = tau'(q), f = q alpha - tau."""
    w = np.asarray(weights, np.float64)
    alpha, f = [], []
    for x in q:
        mu = w ** x / (w ** x).sum()
        a = -(mu * np.log2(w)).sum()
        alpha.append(a)
        f.append(x * a + np.log2((w ** x).sum()))
    return np.array(alpha), np.array(f)


@pytest.mark.parametrize("weights, dim, level, seed", [((0.3, 0.7), 1, 12, 1), ((0.3, 0.7), 1, 12, 2),
                                                       ((0.1, 0.2, 0.3, 0.4), 2, 8, 1)])
def test_cascades_within_their_error_bars(weights, dim, level, seed):
    points, counts = cascade(weights, dim, level, 200_000, seed)
    s = multifractal_spectrum(points, counts, q=Q)
    exact = exact_d(weights, Q)
    # q >= 1 resolved; q = 0 (every cell the cascade reaches, most with few counts) may not be
    assert s.ok[Q >= 1].all(), s.reasons
    ok = s.ok
    # where trusted, the intervals hold the exact values, and are no wider than useful
    assert (np.abs(s.D - exact) <= Z95 * s.stderr)[ok].all(), (s.D, s.stderr, exact)
    assert (s.stderr[ok] < 0.2).all()
    alpha, f = exact_alpha_f(weights, Q)
    assert (np.abs(s.alpha - alpha) <= Z95 * s.alpha_err + 0.02)[ok].all(), (s.alpha, s.alpha_err, alpha)
    assert (np.abs(s.f - f) <= Z95 * s.f_err + 0.02)[ok].all(), (s.f, s.f_err, f)
    # f(alpha) from the direct method is the Legendre transform of tau: f = q alpha - (q - 1) D
    assert np.allclose(s.f, Q * s.alpha - (Q - 1) * s.D, atol=3 * np.hypot(s.f_err, s.alpha_err * Q).max())


def test_uniform_measure_is_flat():
    """Counts spread evenly on a filled square: D(q) = 2 for every q."""
    side = 128
    xy = np.stack(np.meshgrid(np.arange(side), np.arange(side)), -1).reshape(-1, 2) + 0.5
    counts = np.random.default_rng(3).multinomial(400_000, np.full(len(xy), 1 / len(xy)))
    s = multifractal_spectrum(xy, counts, q=Q)
    assert s.ok.all(), s.reasons
    assert (np.abs(s.D - 2) <= Z95 * s.stderr).all(), (s.D, s.stderr)
    assert (np.abs(s.alpha - 2) <= Z95 * s.alpha_err + 0.02).all(), (s.alpha, s.alpha_err)
    assert (np.abs(s.f - 2) <= Z95 * s.f_err + 0.02).all(), (s.f, s.f_err)


def test_undersampled_sides_left_out():
    """Few counts do not resolve small boxes: the fit starts higher up, or says why it cannot."""
    points, counts = cascade((0.3, 0.7), 1, 12, 200_000, 1)
    few_points, few = cascade((0.3, 0.7), 1, 12, 2_000, 1)
    many = multifractal_spectrum(points, counts, q=[0.0, 2.0])
    sparse = multifractal_spectrum(few_points, few, q=[0.0, 2.0])
    assert sparse.range_lo[0] > many.range_lo[0] or not sparse.ok[0]
    assert not sparse.ok[0] or abs(sparse.D[0] - 1) <= Z95 * sparse.stderr[0]
    # a handful of counts: no spectrum, and the reason
    tiny = multifractal_spectrum(few_points[:5], few[:5], q=[0.0, 1.0])
    assert not tiny.ok.any() and all(tiny.reasons)


def test_bad_input():
    with pytest.raises(ValueError, match="counts"):
        multifractal_spectrum(np.zeros((3, 2)), np.array([1, -1, 2]))
    with pytest.raises(ValueError, match="q"):
        multifractal_spectrum(np.zeros((3, 2)), np.array([1, 1, 2]), q=[-1.0])
    with pytest.raises(ValueError, match="points and counts"):
        multifractal_spectrum(np.zeros((3, 2)), np.array([1, 1]))
    with pytest.raises(TypeError, match="counts"):
        multifractal_spectrum(np.zeros((3, 2)))
