"""Fractal dimension from box counts and from mass-radius growth, and ensemble statistics.

Both fits read the local slope along the curve: the least-squares slope over
each octave of the variable (box side, or particle count). A window of the
curve is *flat* when the change of the local slope across it, from a line
fitted to the local slopes, is at most twice its own standard error plus
``flat_tolerance``. The standard error counts one independent local slope per
octave, since slopes over overlapping octaves share their points.

D is the least-squares slope over the widest flat window of at least
``min_decades``. Its ``stderr`` adds in quadrature a statistical part (the
larger of the regression error and the scatter of the local slopes divided by
the square root of the octaves) and a systematic part (half the change of the
local slope across the window, the most by which the window's choice can
move the slope). Log-periodic wiggles of lacunar sets enter as scatter, a
bend as change; a fit with no flat window says so (``ok=False`` and a
reason) instead of returning a confident number.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache
from math import lgamma, log, pi
from statistics import NormalDist

import numpy as np

from .constants import CONFIDENCE, MIN_COUNT, MIN_DECADES, PER_OCTAVE, RESAMPLES, START_FRACTION

Z95 = NormalDist().inv_cdf((1 + CONFIDENCE) / 2)
"""Two-sided ``CONFIDENCE`` quantile of the standard normal (1.96): every interval here is a 95% CI."""


@cache
def t95(dof: int) -> float:
    """Two-sided ``CONFIDENCE`` quantile of Student's t with ``dof`` degrees of freedom (``Z95`` as ``dof`` grows).

    Bisection on the distribution function, the density integrated by
    Simpson's rule (to 1e-9; the package needs no scipy).
    """
    if dof < 1:
        raise ValueError(f"dof: {dof} is below 1")
    log_norm = lgamma((dof + 1) / 2) - lgamma(dof / 2) - 0.5 * log(dof * pi)

    def mass(x):  # P(0 < T < x)
        t = np.linspace(0.0, x, 4001)
        f = np.exp(log_norm - (dof + 1) / 2 * np.log1p(t * t / dof))
        return (t[1] / 3) * (f[0] + 4 * f[1:-1:2].sum() + 2 * f[2:-1:2].sum() + f[-1])

    lo, hi = Z95, 13.0  # t95(1) = 12.706
    while hi - lo > 1e-10:
        mid = (lo + hi) / 2
        lo, hi = (mid, hi) if mass(mid) < CONFIDENCE / 2 else (lo, mid)
    return (lo + hi) / 2


def seed_interval(estimate, replicates, n: int, axis=-1):
    """The 95% CI over ``n`` seeds of ``estimate`` from its bootstrap ``replicates`` (along ``axis``).

    ``estimate`` +- ``t95(n - 1)`` times the replicates' standard deviation
    times sqrt(n / (n - 1)), which undoes the bootstrap's plug-in variance.
    Percentile intervals of a bootstrap over a few seeds are too narrow
    (tests/test_analysis.py; docs/performance.md, "Statistics"); this one
    holds its coverage from 3 seeds on.

    Parameters
    ----------
    estimate : float or ndarray
        The estimate from all ``n`` seeds.
    replicates : ndarray
        Its bootstrap replicates, along ``axis``.
    n : int
        Seeds the estimate is over.
    axis : int
        The axis of ``replicates`` that holds the replicates.

    Returns
    -------
    tuple
        The interval's low and high ends.
    """
    half = t95(n - 1) * np.std(replicates, axis=axis, ddof=1) * np.sqrt(n / (n - 1))
    return estimate - half, estimate + half


def bootstrap_means(curves, rng, resamples=RESAMPLES):
    """Means over seeds of ``resamples`` bootstrap draws of the rows of ``curves`` (a row per seed):
    the replicates ``seed_interval`` reads."""
    draws = rng.integers(0, len(curves), (resamples, len(curves)))
    return np.stack([curves[d].mean(axis=0) for d in draws])


_OCTAVE = np.log(2.0)


@dataclass(frozen=True)
class Fit:
    """A fitted dimension and the evidence behind it.

    Attributes
    ----------
    D : float
        The dimension (NaN when no line could be fitted at all).
    stderr : float
        Standard error, statistical and systematic (module docstring).
    ci_lo, ci_hi : float
        95% confidence interval, ``D -+ 1.96 stderr``.
    range_lo, range_hi : float
        The fitted window of the abscissa (box sides, or particle counts).
    npoints : int
        Points in the fitted window.
    drift : float
        Change of the local slope across the window (signed: up is positive).
    ok : bool
        Whether the fit can be trusted: a flat window of ``min_decades``.
    reason : str
        Why not, when ``ok`` is False; empty otherwise.
    """

    D: float
    stderr: float
    ci_lo: float
    ci_hi: float
    range_lo: float
    range_hi: float
    npoints: int
    drift: float
    ok: bool
    reason: str = ""


@dataclass(frozen=True)
class Ensemble:
    """Statistics of one quantity over seeds (NaN entries dropped).

    Attributes
    ----------
    mean, std : float
        Sample mean and standard deviation (ddof=1).
    stderr : float
        ``std / sqrt(n)``.
    ci_lo, ci_hi : float
        95% confidence interval of the mean: ``mean`` +- ``t95(n - 1) * stderr``.
    n : int
        Number of finite values used.
    """

    mean: float
    std: float
    stderr: float
    ci_lo: float
    ci_hi: float
    n: int


def _line(u, v, groups=None):
    """Least-squares slope of v on u, each group with its own intercept, and its standard error."""
    if groups is None:
        groups = np.zeros(len(u), np.int64)
    else:
        groups = np.unique(groups, return_inverse=True)[1]
    size = np.bincount(groups)
    um = u - (np.bincount(groups, u) / size)[groups]
    vm = v - (np.bincount(groups, v) / size)[groups]
    sxx = um @ um
    slope = um @ vm / sxx if sxx > 0 else np.nan
    residual = vm - slope * um
    dof = len(u) - len(size) - 1
    stderr = np.sqrt(residual @ residual / dof / sxx) if dof > 0 and sxx > 0 else np.nan
    return slope, stderr


def _local_slopes(x, y, u, groups):
    """Slope of y on x over each complete octave of u within a group.

    Returns the first and one past the last index of each octave's points,
    the slopes and the octaves' centres (mean u).
    """
    starts, ends, slopes, centres = [], [], [], []
    for i in range(len(u)):
        members = np.flatnonzero((u >= u[i]) & (u <= u[i] + _OCTAVE * (1 + 1e-9)) & (groups == groups[i]))
        # An octave is complete when its points reach (nearly: counts are
        # whole numbers) a factor two; the last points of the curve start none.
        if len(members) >= 2 and u[members[-1]] - u[i] >= 0.95 * _OCTAVE:
            starts.append(i)
            ends.append(members[-1] + 1)
            slopes.append(_line(x[members], y[members])[0])
            centres.append(u[members].mean())
    return np.array(starts, np.int64), np.array(ends, np.int64), np.array(slopes), np.array(centres)


@dataclass(frozen=True)
class _Window:
    a: int
    b: int
    D: float
    stat: float
    drift: float
    drift_err: float
    flat: bool

    @property
    def stderr(self):
        return float(np.hypot(self.stat, self.drift / 2))


def _window(x, y, u, groups, sign, local, a, b, tolerance):
    """The fit over points a..b-1 and the flatness of its local slopes."""
    slope, regression = _line(x[a:b], y[a:b], groups[a:b])
    starts, ends, slopes, centres = local
    inside = (starts >= a) & (ends <= b)
    d, c = sign * slopes[inside], centres[inside]
    span = u[b - 1] - u[a]
    octaves = (c[-1] - c[0]) / _OCTAVE + 1 if len(c) else 0.0
    if len(d) < 2 or octaves < 2:
        return _Window(a, b, float(sign * slope), np.nan, np.nan, np.nan, False)
    trend, _ = _line(c, d) if c[-1] > c[0] else (0.0, np.nan)
    residual = d - d.mean() - trend * (c - c.mean())
    scatter = np.sqrt(residual @ residual / max(len(d) - 2, 1))
    # Slopes over overlapping octaves share points: count one per octave.
    trend_err = scatter * np.sqrt(len(d) / octaves / ((c - c.mean()) @ (c - c.mean())))
    drift, drift_err = trend * span, trend_err * span
    stat = max(np.nan_to_num(regression), scatter / np.sqrt(octaves))
    flat = abs(drift) <= 2 * drift_err + tolerance
    return _Window(a, b, float(sign * slope), float(stat), float(drift), float(drift_err), bool(flat))


def _scaling_fit(x, y, variable, groups, sign, *, min_decades, min_points, flat_tolerance, unit):
    """Fit ``sign * slope`` of y on x over the widest flat window (module docstring).

    ``variable`` (increasing, named ``unit`` in reasons) is the quantity whose
    octaves define the local slopes and whose decades the window must span;
    points of one of ``groups`` share an intercept; the arrays are already
    restricted to the admissible range.
    """
    m = len(x)

    def result(w, ok, reason=""):
        stderr = w.stderr
        return Fit(w.D, stderr, w.D - Z95 * stderr, w.D + Z95 * stderr, float(variable[w.a]),
                   float(variable[w.b - 1]), w.b - w.a, w.drift, ok, reason)

    if m < max(min_points, 3):
        nan = np.nan
        return Fit(nan, nan, nan, nan, nan, nan, m, nan, False, f"{m} admissible points, need {max(min_points, 3)}")
    u = np.log(variable)
    decades = (u - u[0]) / np.log(10)
    local = _local_slopes(x, y, u, groups)
    whole = _window(x, y, u, groups, sign, local, 0, m, flat_tolerance)
    if decades[-1] < min_decades:
        return result(whole, False, f"admissible range spans {decades[-1]:.2f} decades of {unit}, need {min_decades:g}")
    # Widest first; among equally wide flat windows the most precise wins.
    windows = [(a, b) for a in range(m) for b in range(a + min_points, m + 1)
               if (u[b - 1] - u[a]) / np.log(10) >= min_decades]
    windows.sort(key=lambda w: -(u[w[1] - 1] - u[w[0]]))
    best, width = None, None
    for a, b in windows:
        if width is not None and u[b - 1] - u[a] < width - 1e-12:
            break
        w = _window(x, y, u, groups, sign, local, a, b, flat_tolerance)
        if w.flat and (best is None or w.stderr < best.stderr):
            best, width = w, u[b - 1] - u[a]
    if best is not None:
        return result(best, True)
    return result(whole, False, (
        f"local slope not flat over any {min_decades:g} decades of {unit}: across the whole range it "
        f"changes by {whole.drift:+.3f} (standard error {whole.drift_err:.3f})"))


def fit_dimension(
    scales,
    counts,
    *,
    min_scale: float = 2.0,
    max_fraction: float = 0.25,
    min_decades: float = MIN_DECADES,
    min_points: int = 4,
    flat_tolerance: float = 0.02,
) -> Fit:
    """Box-counting dimension: D = -d log N / d log s over the widest flat window.

    Admissible sides run from ``min_scale`` particle sizes (below, the
    particle shape dominates) to ``max_fraction`` of the set's extent, taken
    as the smallest side whose count is 1 (the largest side given when none
    is); near the extent the counts saturate. Within that range the widest
    window of at least ``min_decades`` and ``min_points`` points whose local
    slope is flat is fitted by least squares (module docstring).

    Parameters
    ----------
    scales, counts : array_like
        Output of ``box_counts``.
    min_scale : float
        Smallest admissible box side, in particle sizes.
    max_fraction : float
        Largest admissible box side, as a fraction of the set's extent.
    min_decades : float
        Narrowest window fitted, in decades of box side.
    min_points : int
        Fewest sides in the window fitted.
    flat_tolerance : float
        Change of the local slope across a window, beyond twice its standard
        error, that still counts as flat (module docstring).

    Returns
    -------
    Fit
        ``range_lo``/``range_hi`` in box sides. ``ok`` is False, with a
        reason, for less than ``min_decades`` of admissible sides, too few
        points, or no flat window.
    """
    s = np.asarray(scales, dtype=np.float64).ravel()
    n = np.asarray(counts, dtype=np.float64).ravel()
    if s.shape != n.shape:
        raise ValueError(f"scales and counts differ in length: {len(s)} and {len(n)}")
    order = np.argsort(s)
    s, n = s[order], n[order]
    single = np.flatnonzero(n <= 1)
    extent = s[single[0]] if len(single) else s.max(initial=0.0)  # no scales: no extent, and no fit
    keep = (s >= min_scale) & (s <= max_fraction * extent) & (n > 0)
    s, n = s[keep], n[keep]
    return _scaling_fit(np.log(s), np.log(n), s, _families(s), -1.0, min_decades=min_decades,
                        min_points=min_points, flat_tolerance=flat_tolerance, unit="box side")


def _families(scales):
    """The family of each box side: its odd part for whole sides (b, 2b, 4b, ... share b), else one family.

    Grids of one family nest, so their counts share one prefactor; between
    families the prefactor jumps on sets commensurate with the lattice
    (the gasket fills boxes of 2**k exactly, of 3 * 2**k not).
    """
    whole = np.round(scales).astype(np.int64)
    if not np.array_equal(whole, scales):
        return np.zeros(len(scales), np.int64)
    return whole // (whole & -whole)


def mass_radius_counts(n_max: int, *, start_fraction: float = START_FRACTION, min_count: int = MIN_COUNT,
                       per_octave: int = PER_OCTAVE) -> np.ndarray:
    """Particle counts at which a growth history is sampled for ``fit_mass_radius``.

    Geometrically spaced, ``per_octave`` per factor two, from the end of the
    transient, ``max(start_fraction * n_max, min_count)``, to ``n_max``: early
    on a cluster is a compact blob, not a fractal, and evenly spaced counts
    would let the many late prefixes outweigh the early ones.

    Returns
    -------
    ndarray of int64
        Increasing; empty when ``n_max`` does not exceed the transient.
    """
    lo = max(start_fraction * n_max, float(min_count))
    if n_max <= lo:
        return np.zeros(0, np.int64)
    targets = lo * 2.0 ** (np.arange(int(per_octave * np.log2(n_max / lo)) + 1) / per_octave)
    return np.unique(np.r_[np.round(targets[targets < n_max]), n_max].astype(np.int64))


def growth_counts(counts) -> np.ndarray:
    """Counts at which a sweep records each cluster's Rg along its growth (``radius_gyration_history``).

    Everything the analysis reads of a growth history: the local-slope
    curve (``PER_OCTAVE`` per octave up to the largest count) and
    ``mass_radius_counts`` of each count, so that a fit on these equals one
    on every prefix.
    """
    counts = np.asarray(counts, np.int64)
    return np.unique(np.concatenate([history_counts(int(counts[-1])), *map(mass_radius_counts, counts)]))


def history_counts(n_max) -> np.ndarray:
    """Counts from ``MIN_COUNT`` to ``n_max``, ``PER_OCTAVE`` per octave: the local-slope curve."""
    if n_max <= MIN_COUNT:
        return np.array([n_max], np.int64)
    k = np.arange(int(PER_OCTAVE * np.log2(n_max / MIN_COUNT)) + 1)
    return np.unique(np.r_[np.round(MIN_COUNT * 2.0 ** (k / PER_OCTAVE)), n_max].astype(np.int64))


def fit_mass_radius(
    rg,
    n=None,
    *,
    start_fraction: float = START_FRACTION,
    min_count: int = MIN_COUNT,
    per_octave: int = PER_OCTAVE,
    min_decades: float = MIN_DECADES,
    min_points: int = 6,
    flat_tolerance: float = 0.02,
) -> Fit:
    """Mass-radius dimension from a growth history: N ~ Rg**D.

    The history is sampled at ``mass_radius_counts`` (the transient left
    out) and D, the slope of log N against log Rg, is fitted over the widest
    flat window of at least ``min_decades`` decades of N (module docstring).

    Parameters
    ----------
    rg : array_like
        Radius of gyration at each count; by default of every prefix, as
        ``radius_of_gyration`` gives it.
    n : array_like of int, optional
        The counts of ``rg``, increasing (default ``1, 2, ..., len(rg)``).
    start_fraction : float
        End of the transient, as a fraction of the largest count
        (``mass_radius_counts``).
    min_count : int
        Fewest particles the history is read from.
    per_octave : int
        Counts sampled per factor two of N.
    min_decades : float
        Narrowest window fitted, in decades of N.
    min_points : int
        Fewest sampled counts in the window fitted.
    flat_tolerance : float
        Change of the local slope across a window, beyond twice its standard
        error, that still counts as flat (module docstring).

    Returns
    -------
    Fit
        ``range_lo``/``range_hi`` in particles. One growth history is one
        correlated realisation: its ``stderr`` is that of this cluster's
        curve, and the spread over seeds is the ensemble's business
        (``dlasweep.summarise``).
    """
    rg = np.asarray(rg, dtype=np.float64).ravel()
    if n is not None:
        n = np.asarray(n, dtype=np.float64).ravel()
        if n.shape != rg.shape:
            raise ValueError(f"n and rg differ in length: {len(n)} and {len(rg)}")
    if len(rg) == 0:
        nan = np.nan
        return Fit(nan, nan, nan, nan, nan, nan, 0, nan, False, "no data")
    n_max = len(rg) if n is None else int(n[-1])
    targets = mass_radius_counts(n_max, start_fraction=start_fraction, min_count=min_count, per_octave=per_octave)
    # Every prefix's Rg (the default) is indexed by its count; other histories are searched.
    picks = targets - 1 if n is None else np.unique(np.clip(np.searchsorted(n, targets), 0, len(n) - 1))
    picks = picks[rg[picks] > 0]
    counts = picks + 1.0 if n is None else n[picks]
    return _scaling_fit(np.log(rg[picks]), np.log(counts), counts, np.zeros(len(picks), np.int64), 1.0,
                        min_decades=min_decades,
                        min_points=min_points, flat_tolerance=flat_tolerance, unit="N")


def ensemble(values) -> Ensemble:
    """Mean, spread and the 95% confidence interval of the mean (Student's t) of values over seeds.

    Parameters
    ----------
    values : array_like
        One value per seed; NaN entries are dropped (say so where it matters:
        dropping values selects).

    Returns
    -------
    Ensemble
        NaN where a statistic needs more values than there are.
    """
    v = np.asarray(values, dtype=np.float64).ravel()
    v = v[np.isfinite(v)]
    k = len(v)
    if k == 0:
        return Ensemble(np.nan, np.nan, np.nan, np.nan, np.nan, 0)
    if k == 1:
        return Ensemble(float(v[0]), np.nan, np.nan, np.nan, np.nan, 1)
    mean, std = float(v.mean()), float(v.std(ddof=1))
    half = t95(k - 1) * std / np.sqrt(k)
    return Ensemble(mean, std, std / np.sqrt(k), mean - half, mean + half, k)
