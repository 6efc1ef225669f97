"""Lattice deposits on a substrate grown with the jumps against deposits grown by single steps.

Both walks are the same lattice random walk: the square exits and Brownian
jumps only skip its steps where no particle, and no substrate, lies within
reach. So the two ensembles are draws of one distribution, and any statistic
of a deposit has the same mean. Compared here over 24 seeds of 8000
particles each (a strip 256 sites wide, a plane 64 by 64 sites): the mean
height of the particles, the deposit's radius of gyration along the height
(the rms spread of the heights; across the periodic sides a radius of
gyration has no meaning) and the density profile (the fraction of the
particles in each of eight height bands of equal mass in the pooled
ensemble). At this size the far jumps reach down the fjords between the
trees to the substrate.

Each mean difference is held within t * se, se the standard error of a
difference of two 24-seed means from the seeds' own spread, and t Student's
quantile for a two-sided false alarm of 1e-3 spread over the ten statistics
of a dimension (Bonferroni; 46 degrees of freedom, t = 4.26).
"""

import numpy as np
import pytest
from scipy import stats

import dlasweep as dla

SEEDS = 24
N = 8000
BANDS = 8
FALSE_ALARM = 1e-3


def _statistics(points, edges):
    """Mean height, the rms spread of the heights, and the fraction of particles in each band."""
    h = points[:, -1].astype(np.float64)
    profile = np.histogram(h, edges)[0] / len(h)
    return np.r_[h.mean(), h.std(), profile]


def _ensemble(kw, jumps):
    return [dla.grow(N, seed=700 + s, jumps=jumps, **kw).points for s in range(SEEDS)]


@pytest.mark.slow
@pytest.mark.parametrize("kw", [dict(dim=2, seed_shape="line", size=256),
                                dict(dim=3, seed_shape="line", size=64)], ids=["line", "plane"])
def test_deposits_grown_with_jumps_match_single_steps(kw):
    fast, slow = _ensemble(kw, True), _ensemble(kw, False)
    assert all(len(p) == N for p in fast + slow)
    pooled = np.concatenate([p[:, -1] for p in fast + slow]).astype(np.float64)
    edges = np.quantile(pooled, np.linspace(0, 1, BANDS + 1))
    edges[0], edges[-1] = -np.inf, np.inf  # a particle below the substrate still counts, in the lowest band
    a = np.array([_statistics(p, edges) for p in fast])
    b = np.array([_statistics(p, edges) for p in slow])
    se = np.sqrt(a.var(axis=0, ddof=1) / SEEDS + b.var(axis=0, ddof=1) / SEEDS)
    t = stats.t.ppf(1 - FALSE_ALARM / 2 / a.shape[1], 2 * SEEDS - 2)
    z = np.abs(a.mean(axis=0) - b.mean(axis=0)) / se
    names = ["mean height", "height spread"] + [f"band {k}" for k in range(BANDS)]
    assert (z < t).all(), {name: round(v, 2) for name, v in zip(names, z)}
