"""Drift (``drift``, ``drift_angle``, ``drift_azimuth``): a uniform drift of the walkers.

The laws the kernels draw under a drift, against their exact distributions: the
exit direction from a ball's centre (von Mises in 2D, von Mises-Fisher in 3D,
``walk.drift_dir``; also against a brute-force drifted Brownian motion), the
return to a substrate's launch plane (``walk.drift_to_plane``) and the lattice's
tilted moves (``walker.drifted_move``). Then clusters: grown with the jumps
against single steps at small and moderate drift (the tolerance the jumps keep),
off the lattice against small drifted Gaussian steps, D rising with drift
towards the compact limit, and the bad-input rule.

Kolmogorov-Smirnov and chi-square tests hold p above ``P_MIN`` = 1e-4 each; with
the cases of a test that is a false alarm below 2e-3 a test (Bonferroni).
"""

import numba
import numpy as np
import pytest
from scipy import special, stats

import dlasweep as dla
import naive
from dlasweep.kernels import walk
from dlasweep.kernels.lattice.exits import unit_moves
from dlasweep.kernels.lattice.walker import drifted_move
from dlasweep.params import drift_vector, resolve

P_MIN = 1e-4
DRAWS = 40_000


@numba.njit
def _draw_dirs(rs, dim, kappa, a0, a1, a2, n):
    s0, s1, s2, s3 = rs[0], rs[1], rs[2], rs[3]
    out = np.empty((n, 3))
    for k in range(n):
        s0, s1, s2, s3, out[k, 0], out[k, 1], out[k, 2] = walk.drift_dir(s0, s1, s2, s3, dim, kappa, a0, a1, a2)
    return out


def _drift_dirs(seed, dim, kappa, a0, a1, a2, n):
    """``n`` draws of ``drift_dir`` from a stream seeded by ``seed``, in numba, as the kernels draw them."""
    return _draw_dirs(walk.seed_stream(np.random.default_rng(seed)), dim, kappa, a0, a1, a2, n)


def _axis(dim):
    a = np.array([0.48, -0.6, 0.64]) if dim == 3 else np.array([0.6, -0.8, 0.0])
    return a / np.linalg.norm(a)


def _cos_cdf(dim, kappa):
    """The exact CDF of w = a.x for the exit point x on the unit sphere under the tilt exp(kappa a.x)."""
    if dim == 3 and kappa == 0.0:
        return lambda w: (np.asarray(w) + 1.0) / 2.0
    if dim == 3:  # density of w proportional to exp(kappa w) on [-1, 1]
        return lambda w: np.expm1(kappa * (np.asarray(w) + 1.0)) / np.expm1(2.0 * kappa)
    return lambda w: 2.0 * (1.0 - stats.vonmises(kappa).cdf(np.arccos(np.clip(w, -1, 1))))


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("kappa", [0.0, 1e-9, 0.3, 3.0, 40.0])
def test_drift_dir_draws_the_tilted_law_on_the_sphere(dim, kappa):
    """``drift_dir`` as the kernels call it (numba, the stream in registers): unit vectors whose
    component along the drift has the exact CDF (KS), whose angle about it is uniform (KS), and
    whose mean is the tilted law's (the Bessel ratio I1/I0 in 2D, coth k - 1/k in 3D) within 5
    standard errors. At kappa 0 and 1e-9 the law is uniform; at 40 a cap of half-angle ~13 degrees."""
    a = _axis(dim)
    x = _drift_dirs(11 + dim + int(kappa * 7), dim, kappa, *a, DRAWS)[:, :dim]
    np.testing.assert_allclose(np.linalg.norm(x, axis=1), 1.0, atol=1e-12)
    w = x @ a[:dim]
    assert stats.kstest(w, _cos_cdf(dim, kappa)).pvalue > P_MIN
    across = x - w[:, None] * a[:dim]
    if dim == 2:  # the side of the axis, fair
        side = across @ np.array([-a[1], a[0]])
        assert stats.binomtest(int((side > 0).sum()), DRAWS).pvalue > P_MIN
    else:
        e = np.cross(a, [1.0, 0.0, 0.0])
        e /= np.linalg.norm(e)
        angle = np.arctan2(across @ np.cross(a, e), across @ e)
        assert stats.kstest(angle, stats.uniform(-np.pi, 2 * np.pi).cdf).pvalue > P_MIN
    if kappa == 0.0:
        mean = 0.0
    elif dim == 2:
        mean = special.i1e(kappa) / special.i0e(kappa)
    else:
        mean = 1.0 / np.tanh(kappa) - 1.0 / kappa if kappa > 1e-4 else kappa / 3.0
    assert abs(w.mean() - mean) < 5 * w.std() / np.sqrt(DRAWS) + 1e-12


@numba.njit
def _brownian_exits(rng, dim, mu0, mu1, mu2, n, dt):
    """Where Brownian motion with drift mu (D = 1/2: dx = mu dt + dW) first leaves the unit ball
    from its centre, by Euler steps of dt, each exit projected onto the sphere (``rng`` a Generator)."""
    out = np.zeros((n, 3))
    sd = np.sqrt(dt)
    for k in range(n):
        x0 = x1 = x2 = 0.0
        while x0 * x0 + x1 * x1 + x2 * x2 < 1.0:
            x0 += mu0 * dt + sd * rng.standard_normal()
            x1 += mu1 * dt + sd * rng.standard_normal()
            if dim == 3:
                x2 += mu2 * dt + sd * rng.standard_normal()
        r = np.sqrt(x0 * x0 + x1 * x1 + x2 * x2)
        out[k, 0], out[k, 1], out[k, 2] = x0 / r, x1 / r, x2 / r
    return out


@pytest.mark.slow
@pytest.mark.parametrize("dim", [2, 3])
def test_drift_dir_is_where_drifted_brownian_motion_leaves_a_ball(dim):
    """The Girsanov argument checked: exits of a drifted Brownian motion (Euler steps of 2e-5: a step's
    overshoot about 0.003 of the radius, 0.58 of a step's spread) from the centre of the unit ball at
    kappa 1.5, against ``drift_dir``; KS of the component along the drift and across it, 4000 walks (a
    4% shift in the law fails it)."""
    a = _axis(dim)
    brute = _brownian_exits(np.random.default_rng(5 + dim), dim, *(1.5 * a), 4000, 2e-5)[:, :dim]
    got = _drift_dirs(50 + dim, dim, 1.5, *a, 4000)[:, :dim]
    across = np.array([-a[1], a[0], 0.0][:dim]) / np.linalg.norm(a[:2])
    for v in (a[:dim], across):
        assert stats.ks_2samp(brute @ v, got @ v).pvalue > P_MIN


def _plane_landings(dim, h, mu, n, seed):
    rng = np.random.Generator(np.random.PCG64(seed))
    out = np.empty((n, 3))
    for k in range(n):
        pos = np.zeros(3)
        pos[dim - 1] = 1.0 + h
        walk.drift_to_plane(rng, dim, pos, 1.0, 1e9, *mu)
        out[k] = pos
    return out


QUANTILES = 4000
"""Midpoints of the time's quantiles the lateral CDF averages over: the midpoint rule's error is at most
the integrand's variation (a normal CDF's, between 0 and 1) over the count, a few 1e-4, below the KS
statistic's spread at 3000 landings (about 0.015)."""


def _lateral_cdf(h, down, lat):
    """The exact CDF of the lateral landing offset from height h: lat t + sqrt(t) N with t inverse Gaussian
    (mean h / down, shape h**2), or Levy (h**2 / N**2) when ``down`` is 0."""
    law = stats.invgauss(h / down / h**2, scale=h**2) if down > 0 else stats.levy(scale=h**2)

    t = law.ppf((np.arange(QUANTILES) + 0.5) / QUANTILES)  # the time's quantiles: a bounded integrand on (0, 1)
    return lambda x: stats.norm.cdf((np.asarray(x)[:, None] - lat * t) / np.sqrt(t)).mean(axis=1)


@pytest.mark.parametrize("dim, mu", [(2, (0.3, -0.5, 0.0)), (2, (-0.4, 0.0, 0.0)), (2, (0.0, -0.05, 0.0)),
                                     (3, (0.2, -0.1, -0.6))])
def test_drift_to_plane_lands_by_the_inverse_gaussian_law(dim, mu):
    """The return to the launch plane from 2 above it, its lateral offsets (no wrap: a period of 1e9)
    against the exact mixture law (KS on 3000 landings, every axis), and every landing on the plane.
    Cases: down and sideways, purely sideways (Levy's hitting time), nearly no drift, and 3D."""
    h = 2.0
    got = _plane_landings(dim, h, mu, 3000, 9 + dim)
    np.testing.assert_array_equal(got[:, dim - 1], 1.0)
    down = -mu[dim - 1]
    for axis in range(dim - 1):
        offset = got[:, axis]
        offset = np.where(offset > 5e8, offset - 1e9, offset)
        assert stats.kstest(offset, _lateral_cdf(h, down, mu[axis])).pvalue > P_MIN


@pytest.mark.parametrize("dim, moore", [(2, False), (2, True), (3, False), (3, True)])
def test_drifted_move_takes_each_move_with_its_tilted_probability(dim, moore):
    """``drifted_move`` from uniforms: move m at (1 + mu.m) / M (chi-square, 200 000 draws), so
    the mean step is mu times the per-axis variance of a step."""
    moves = unit_moves(dim, moore)
    assert (moves[::-1] == -moves).all()  # the opposite pairs drifted_move reads
    p = resolve(dim=dim, drift=0.9 if not moore else 0.5, drift_angle=35.0, drift_azimuth=20.0 if dim == 3 else 0.0,
                neighbours=len(moves), kill_factor=2.0)
    mu = drift_vector(p)
    u = np.random.default_rng(3).random(200_000)
    picks = np.array([drifted_move(moves, x, *mu) for x in u])
    want = (1.0 + moves @ np.array(mu)) / len(moves)
    assert abs(want.sum() - 1.0) < 1e-12 and want.min() >= 0
    counts = np.bincount(picks, minlength=len(moves))
    assert stats.chisquare(counts, want * len(u)).pvalue > P_MIN


# ---------------------------------------------------------------- clusters -----

SEEDS = 12
FALSE_ALARM = 1e-3


def elongation(points):
    """A cluster's anisotropy under a drift: its largest principal radius over its smallest (the square
    roots of its covariance's eigenvalues)."""
    radii = np.linalg.eigvalsh(np.cov(points.T))
    return float(np.sqrt(radii[-1] / radii[0]))


def _statistics(points, line):
    """Radius of gyration, mean height, the height's spread and the elongation of a cluster's ``points``;
    on a substrate (``line``) the height's mean and spread alone (across the periodic sides the others have
    no meaning)."""
    pts = points.astype(np.float64)
    h = pts[:, -1]
    if line:
        return np.array([h.mean(), h.std()])
    rg = np.sqrt(((pts - pts.mean(axis=0)) ** 2).sum(axis=1).mean())
    return np.array([rg, h.mean(), h.std(), elongation(pts)])


FAR = dict(launch_factor=2.0, kill_factor=1.5)
"""Walkers released at twice the cluster's radius and killed at three times it: they cross open space
by jumps, which the statistics then see."""
HIGH = dict(launch_margin=40.0)
"""Walkers released 40 sites above a deposit: they come down by jumps."""
JUMP_CASES = {
    "lattice-2d-0.05": dict(n=2000, drift=0.05, **FAR),
    "lattice-2d-0.3": dict(n=2000, drift=0.3, drift_angle=30.0, **FAR),
    "lattice-line-0.05": dict(n=4000, drift=0.05, seed_shape="line", size=128, **HIGH),
    "lattice-line-0.3": dict(n=4000, drift=0.3, drift_angle=60.0, seed_shape="line", size=128, **HIGH),
    "lattice-3d-0.05": dict(n=1500, dim=3, drift=0.05, **FAR),
    "lattice-3d-0.3": dict(n=1500, dim=3, drift=0.3, drift_angle=50.0, drift_azimuth=30.0, **FAR),
    "lattice-plane-0.3": dict(n=3000, dim=3, drift=0.3, seed_shape="line", size=32, **HIGH),
}


@pytest.mark.slow
@pytest.mark.parametrize("case", sorted(JUMP_CASES))
def test_clusters_grown_with_jumps_match_single_steps_under_a_drift(case):
    """The jumps' tolerance: under a drift the lattice walker's circle jumps (from ``CIRCLE_MIN`` sites on,
    the drifted Brownian exit law) stand in for the drifted lattice walk only through its continuum
    limit, which differs from it at O(drift**2) in its covariance. Clusters grown with them against
    clusters of single drifted steps (``jumps=false``), 12 seeds each: each statistic's mean
    difference within t * se, se from the seeds' spread, t Student's for a two-sided false alarm of
    1e-3 spread over the statistics of a case (Bonferroni, 22 degrees of freedom)."""
    kw = dict(JUMP_CASES[case])
    n = kw.pop("n")
    line = kw.get("seed_shape") == "line"
    fast = np.array([_statistics(dla.grow(n, seed=900 + s, **kw).points, line) for s in range(SEEDS)])
    slow = np.array([_statistics(dla.grow(n, seed=900 + s, jumps=False, **kw).points, line) for s in range(SEEDS)])
    _assert_same_means(case, fast, slow)


def _assert_same_means(case, fast, slow):
    """Each statistic's (column's) mean over the seeds (rows) of ``fast`` and ``slow`` equal within t * se:
    se from the seeds' spread, t Student's for a two-sided false alarm of ``FALSE_ALARM`` spread over the
    statistics (Bonferroni)."""
    se = np.sqrt(fast.var(axis=0, ddof=1) / len(fast) + slow.var(axis=0, ddof=1) / len(slow))
    t = stats.t.ppf(1 - FALSE_ALARM / 2 / fast.shape[1], len(fast) + len(slow) - 2)
    z = np.abs(fast.mean(axis=0) - slow.mean(axis=0)) / se
    assert (z < t).all(), (case, z.round(2), fast.mean(axis=0).round(2), slow.mean(axis=0).round(2))


OFF_FAR = dict(FAR, model="offlattice")
"""``FAR`` off the lattice: walkers cross open space by jumps of the drifted exit law."""
OFF_HIGH = dict(HIGH, model="offlattice")
"""``HIGH`` off the lattice: walkers released 40 diameters above a deposit come down by jumps."""
GAUSS_CASES = {
    "offlattice-2d-0.05": dict(n=1000, drift=0.05, **OFF_FAR),
    "offlattice-2d-0.3": dict(n=1000, drift=0.3, drift_angle=30.0, **OFF_FAR),
    "offlattice-line-0.05": dict(n=1500, drift=0.05, seed_shape="line", size=64, **OFF_HIGH),
    "offlattice-line-0.3": dict(n=1500, drift=0.3, drift_angle=60.0, seed_shape="line", size=64, **OFF_HIGH),
    "offlattice-3d-0.05": dict(n=800, dim=3, drift=0.05, **OFF_FAR),
    "offlattice-3d-0.3": dict(n=800, dim=3, drift=0.3, drift_angle=50.0, drift_azimuth=30.0, **OFF_FAR),
    "offlattice-plane-0.05": dict(n=1500, dim=3, drift=0.05, seed_shape="line", size=24, **OFF_HIGH),
    "offlattice-plane-0.3": dict(n=1500, dim=3, drift=0.3, seed_shape="line", size=24, **OFF_HIGH),
}


@pytest.mark.slow
@pytest.mark.parametrize("case", sorted(GAUSS_CASES))
def test_offlattice_jumps_match_small_drifted_gaussian_steps(case):
    """The off-lattice twin: clusters grown with the exact jumps (every move from a sphere's centre drawn
    from the drifted exit law, ``walk.drift_dir``, at concentration drift x radius) against clusters of
    walkers taking small Gaussian steps of the drifted Brownian motion (``naive.gaussian_drift_cluster``:
    a step of spread s moves by mu s**2 plus N(0, s**2) an axis, exact in free space; its contacts by the
    step's end, off by about 0.01 of a diameter), nothing of the package's walk shared (the package's own
    Gaussian steps, ``step`` with ``jumps=false``, take about 1e6 steps a particle here at a spread of 0.1,
    and with jumps draw their far moves from ``drift_dir`` too). Point seed with a
    kill circle and substrate, 2D and 3D, drift 0.05 and 0.3; 12 seeds each, the means compared as
    the lattice's are (``_assert_same_means``: false alarm 1e-3 a case). With the concentration of
    ``drift_dir`` multiplied by 3, six of the eight cases fail: the four at drift 0.05 by 6 to 10 standard
    errors in the mean height, both substrates' at 0.3 by 8 and 23; the point seeds' at 0.3 pass (beyond
    3 diameters their walk is nearly ballistic either way)."""
    kw = dict(GAUSS_CASES[case])
    n = kw.pop("n")
    line = kw.get("seed_shape") == "line"
    p = resolve(**kw)
    fast = np.array([_statistics(dla.grow(n, seed=900 + s, **kw).points, line) for s in range(SEEDS)])
    slow = np.array([_statistics(naive.gaussian_drift_cluster(n, p, 900 + s), line) for s in range(SEEDS)])
    _assert_same_means(case, fast, slow)


# --------------------------------------------------------------- bad input -----

@pytest.mark.parametrize("options, name", [
    (["--drift", "-0.1", "--kill-factor", "2"], "drift"),
    (["--drift", "1.5", "--kill-factor", "2"], "drift"),
    (["--drift", "0.8", "--neighbours", "8", "--drift-angle", "45", "--kill-factor", "2"], "drift"),
    (["--drift", "0.1"], "drift"),
    (["--drift", "0.1", "--size", "64", "--walkers", "20"], "drift"),
    (["--drift", "0.1", "--seed-shape", "line", "--size", "64", "--drift-angle", "120"], "drift_angle"),
    (["--drift", "0.1", "--drift-angle", "200", "--kill-factor", "2"], "drift_angle"),
    (["--drift", "0.1", "--drift-azimuth", "30", "--kill-factor", "2"], "drift_azimuth"),
])
def test_bad_drifts_are_refused_in_one_line_naming_the_key(options, name, run_cli, tmp_path):
    """A negative drift, one above 1, a lattice tilt that gives a move a negative probability, a drift
    at a point seed with the exact return (no drifted law for it), with lockstep walkers, upwards from
    a substrate, an angle out of range and an azimuth in 2D: exit 2, one line, the key named."""
    status, out, err = run_cli("grow", "-n", "10", "-o", str(tmp_path / "a.nc"), *options)
    assert status == 2 and out == "", err
    assert len(err.strip().splitlines()) == 1 and f"--{name.replace('_', '-')}: " in err, err


def test_drifts_the_kernels_grow_are_accepted():
    """The limits themselves: drift 1 along an axis (nearest neighbours), sideways over a substrate,
    1/sqrt(2) along a Moore diagonal, and in a box without a kill circle."""
    for kw in (dict(drift=1.0, kill_factor=2.0), dict(drift=0.5, drift_angle=90.0, seed_shape="line", size=32),
               dict(drift=2 ** -0.5, neighbours=8, drift_angle=45.0, kill_factor=2.0), dict(drift=0.2, size=64),
               dict(model="offlattice", dim=3, drift=0.3, drift_angle=120.0, drift_azimuth=300.0, kill_factor=2.0)):
        resolve(**kw)


def _mass_radius_dimension(c, counts):
    """D of one cluster: the slope of log n against log Rg(n) over ``counts``."""
    pts = c.points.astype(np.float64)
    rg = [np.sqrt(((pts[:k] - pts[:k].mean(axis=0)) ** 2).sum(axis=1).mean()) for k in counts]
    return np.polyfit(np.log(rg), np.log(counts), 1)[0]


@pytest.mark.slow
def test_drift_takes_d_from_dlas_towards_the_compact_limit():
    """D of 2D lattice clusters (point seed, kill circle at twice the launch radius) over n 500 to
    1e4, 6 seeds a drift: beyond the crossover 1/drift the walk is ballistic and the cluster compact,
    so with the crossover well inside the cluster (drift 0.1, 0.3: 10 and 3 sites) D rises from DLA's
    towards 2. Measured (``drift.toml``'s report at 1e4, 8 seeds): 1.71, 1.87, 1.92 at drift 0, 0.1,
    0.3, per-seed spreads 0.03 to 0.08. Asked: each drift's D above plain DLA's by 5 standard errors
    of the difference, the rise from 0.1 to 0.3 not a fall beyond 3, and every D below 2 + 3 of its
    own (compact is the limit)."""
    n, seeds = 10_000, range(6)
    counts = [500, 1000, 2000, 5000, 10_000]
    rows = []
    for drift in (0.0, 0.1, 0.3):
        d = np.array([_mass_radius_dimension(dla.grow(n, seed=s, drift=drift, kill_factor=2.0), counts)
                      for s in seeds])
        rows.append((drift, d.mean(), d.std(ddof=1) / np.sqrt(len(d))))
    (_, d0, e0), (_, d1, e1), (_, d3, e3) = rows
    assert d1 - d0 > 5 * np.hypot(e0, e1) and d3 - d0 > 5 * np.hypot(e0, e3), rows
    assert d3 - d1 > -3 * np.hypot(e1, e3), rows
    assert all(d < 2.0 + 3 * e for _, d, e in rows), rows
