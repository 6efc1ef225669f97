"""Fractal dimension from box counts and from mass-radius growth, and ensemble statistics.

Both fits pick their scaling range from the data: the longest window, within
limits set by the particle size and the cluster extent, whose points lie on a
straight line in log-log. A window is straight when the slope of a quadratic
fitted to it changes by at most ``max_drift`` across the window and the
line's RMS residual is at most ``max_rms``. A fit that cannot be trusted says
so (``ok=False`` and a reason) instead of returning a confident number.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Fit:
    """A fitted dimension and the evidence behind it.

    Attributes
    ----------
    D : float
        The dimension (NaN when no line could be fitted at all).
    stderr : float
        Standard error of the slope from the regression residuals. Points of
        one curve are correlated, so this measures the fit, not the spread
        over seeds (see ``ensemble`` for that).
    lo, hi : float
        Range of the abscissa used (box sides, or particle counts).
    npoints : int
        Points in the fitted window.
    ok : bool
        Whether the fit can be trusted.
    reason : str
        Why not, when ``ok`` is False; empty otherwise.
    """

    D: float
    stderr: float
    lo: float
    hi: float
    npoints: int
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
        Percentile bootstrap confidence interval of the mean.
    n : int
        Number of finite values used.
    """

    mean: float
    std: float
    stderr: float
    ci_lo: float
    ci_hi: float
    n: int


def _line(x, y):
    """Least-squares slope, its standard error, and the RMS residual."""
    xm = x - x.mean()
    sxx = (xm * xm).sum()
    slope = (xm * (y - y.mean())).sum() / sxx
    residual = y - y.mean() - slope * xm
    rms = np.sqrt((residual**2).mean())
    stderr = np.sqrt((residual**2).sum() / (len(x) - 2) / sxx) if len(x) > 2 else np.nan
    return slope, stderr, rms


def _slope_drift(x, y):
    """Change of the local slope across the window, from a quadratic fit."""
    curvature = np.polyfit(x - x.mean(), y, 2)[0]
    return abs(2 * curvature * (x[-1] - x[0]))


def _straight_fit(x, y, variable, sign, *, min_span, min_points, max_drift, max_rms, unit):
    """Fit ``sign * slope`` on the longest straight window of (x, y).

    ``variable`` (increasing, named ``unit`` in reasons) is the quantity whose
    decades the window must cover (``min_span`` of them) and whose range the
    fit reports; the arrays are already restricted to the admissible range.
    """
    span = np.log10(variable)
    m = len(x)
    if m < max(min_points, 3):
        return Fit(np.nan, np.nan, np.nan, np.nan, m, False, f"{m} admissible points, need {min_points}")

    def result(a, b, ok, reason=""):
        slope, stderr, _ = _line(x[a:b], y[a:b])
        return Fit(float(sign * slope), float(stderr), float(variable[a]), float(variable[b - 1]), b - a, ok, reason)

    full_span = span[-1] - span[0]
    if full_span < min_span:
        return result(0, m, False, f"admissible range spans {full_span:.2f} decades of {unit}, need {min_span:g}")
    # Longest first; among equally long straight windows the best line wins.
    for length in range(m, min_points - 1, -1):
        straight = []
        for a in range(m - length + 1):
            b = a + length
            if span[b - 1] - span[a] < min_span:
                continue
            rms = _line(x[a:b], y[a:b])[2]
            if rms <= max_rms and _slope_drift(x[a:b], y[a:b]) <= max_drift:
                straight.append((rms, a, b))
        if straight:
            _, a, b = min(straight)
            return result(a, b, True)
    drift = _slope_drift(x, y)
    rms = _line(x, y)[2]
    return result(
        0, m, False,
        f"no window of {min_span:g} decades is straight (whole range: slope drifts {drift:.2f}, RMS residual {rms:.3f})",
    )


def fit_dimension(
    scales,
    counts,
    *,
    min_scale: float = 2.0,
    max_fraction: float = 0.25,
    min_decades: float = 1.0,
    min_points: int = 6,
    max_drift: float = 0.25,
    max_rms: float = 0.05,
) -> Fit:
    """Box-counting dimension: D = -d log N / d log s over a straight range.

    Admissible scales run from ``min_scale`` particle sizes (below, the
    particle shape dominates) to ``max_fraction`` of the set's extent, taken
    as the smallest scale whose count is 1 (the largest scale given when none
    is); near the extent the counts saturate. Within that range the longest
    straight window of at least ``min_decades`` and ``min_points`` points is
    fitted by least squares (see the module docstring).

    Parameters
    ----------
    scales, counts : array_like
        Output of ``box_counts``.
    min_scale, max_fraction, min_decades, min_points, max_drift, max_rms
        The range and straightness rules above (drift and RMS in natural log).

    Returns
    -------
    Fit
        ``lo``/``hi`` in box sides. ``ok`` is False, with a reason, for less
        than ``min_decades`` of admissible scales, fewer than ``min_points``
        points, or no straight window.
    """
    s = np.asarray(scales, dtype=np.float64).ravel()
    n = np.asarray(counts, dtype=np.float64).ravel()
    if s.shape != n.shape:
        raise ValueError(f"scales and counts differ in length: {len(s)} and {len(n)}")
    order = np.argsort(s)
    s, n = s[order], n[order]
    single = np.flatnonzero(n <= 1)
    extent = s[single[0]] if len(single) else s[-1]
    keep = (s >= min_scale) & (s <= max_fraction * extent) & (n > 0)
    x = np.log(s[keep])
    return _straight_fit(
        x, np.log(n[keep]), s[keep], -1.0,
        min_span=min_decades, min_points=min_points, max_drift=max_drift, max_rms=max_rms, unit="box side",
    )


def fit_mass_radius(
    n,
    rg,
    *,
    start_fraction: float = 0.05,
    min_count: int = 50,
    per_octave: int = 8,
    min_decades: float = 1.0,
    min_points: int = 6,
    max_drift: float = 0.25,
    max_rms: float = 0.05,
) -> Fit:
    """Mass-radius dimension from the growth history: N ~ Rg**D.

    The transient is cut at ``max(start_fraction * N_max, min_count)``
    particles: early on the cluster is a lattice blob, not a fractal. The
    history above that is sampled at ``per_octave`` geometrically spaced
    counts (so the many late prefixes do not outweigh the early ones) and the
    longest straight window of at least ``min_decades`` decades of N is
    fitted: D is the slope of log N against log Rg.

    Parameters
    ----------
    n : array_like of int
        Particle counts, increasing; for the Rg of every prefix,
        ``np.arange(1, len(rg) + 1)``.
    rg : array_like
        Radius of gyration at each count.
    start_fraction, min_count, per_octave, min_decades, min_points, max_drift, max_rms
        The range, sampling and straightness rules above.

    Returns
    -------
    Fit
        ``lo``/``hi`` in particles. The growth history is one correlated
        realisation, so ``stderr`` understates the seed-to-seed spread.
    """
    n = np.asarray(n, dtype=np.float64).ravel()
    rg = np.asarray(rg, dtype=np.float64).ravel()
    if n.shape != rg.shape:
        raise ValueError(f"n and rg differ in length: {len(n)} and {len(rg)}")
    if len(n) == 0:
        return Fit(np.nan, np.nan, np.nan, np.nan, 0, False, "no data")
    lo = max(start_fraction * n[-1], float(min_count))
    if n[-1] <= lo:
        targets = np.empty(0)
    else:
        targets = lo * 2.0 ** (np.arange(int(per_octave * np.log2(n[-1] / lo)) + 1) / per_octave)
        targets = np.r_[targets[targets < n[-1]], n[-1]]
    picks = np.unique(np.clip(np.searchsorted(n, targets), 0, len(n) - 1))
    picks = picks[(n[picks] >= lo) & (rg[picks] > 0)]
    return _straight_fit(
        np.log(rg[picks]), np.log(n[picks]), n[picks], 1.0,
        min_span=min_decades, min_points=min_points, max_drift=max_drift, max_rms=max_rms, unit="N",
    )


def ensemble(values, *, confidence: float = 0.95, resamples: int = 4000, seed: int = 0) -> Ensemble:
    """Mean, spread and bootstrap confidence interval of values over seeds.

    Parameters
    ----------
    values : array_like
        One value per seed; NaN (failed fits) are dropped.
    confidence : float
        Coverage of the percentile bootstrap interval of the mean.
    resamples : int
        Bootstrap resamples, drawn from ``numpy.random.default_rng(seed)`` so
        that reruns agree.

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
    std = float(v.std(ddof=1))
    means = v[np.random.default_rng(seed).integers(0, k, (resamples, k))].mean(axis=1)
    tail = 100 * (1 - confidence) / 2
    ci_lo, ci_hi = np.percentile(means, [tail, 100 - tail])
    return Ensemble(float(v.mean()), std, std / np.sqrt(k), float(ci_lo), float(ci_hi), k)
