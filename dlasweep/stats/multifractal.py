"""The multifractal spectrum of a sampled measure: D(q) by box partition sums, f(alpha) by the direct method.

A measure is sampled by counts on points (the walkers that stuck to each
particle of a cluster: ``dlasweep.measures.harmonic``). Boxes of side s
carry p_i(s), their share of the counts; the partition sum
Z(q, s) = sum_i p_i**q scales as s**((q - 1) D(q)), so that D(q) is the slope
of log Z / (q - 1) on log s (of sum_i p_i log p_i at q = 1, the information
dimension). The direct method of Chhabra and Jensen (Phys. Rev. Lett. 62,
1327, 1989) reads the spectrum from the same boxes: with mu_i = p_i**q / Z,
alpha(q) is the slope of sum_i mu_i log p_i and f(q) that of sum_i mu_i log mu_i.
The grids of sides b, 2b, 4b, ... (a family) nest, and the fit gives each
family its own intercept (``fit``: box counting's rule).

It lives with the statistics, not with the measures of one point set, because
what it returns is a fit with an error bar (``fit``'s scaling fit), whose
honesty rules are those of the box-counting dimension:

- the admissible sides run from ``min_scale`` to ``max_fraction`` of the hit
  points' extent, and at each q down only as far as the counts resolve the
  sums: where those of all the counts and of half of them differ by more than
  ``tolerance`` (in log Z / (q - 1)), too few counts fall in a box, and the
  smaller sides are left out (the sums of a finite sample are biased there:
  small boxes look emptier or lumpier than they are); for q < 1, where the
  boxes no count reached weigh in, also where they may be more than a
  fraction ``tolerance`` of those reached (Chao's estimate of the unseen, from
  the boxes of one and two counts): a sample's support grows too slowly with
  its size for the halves to show it;
- within that range, the widest flat window of ``min_decades`` is fitted
  (``fit``: the window, its statistical and systematic error, ``ok`` only when
  it is flat);
- to that error are added in quadrature the sampling error, by a jackknife
  over ``GROUPS`` random parts of the counts (each count given to a part at
  random, as the walkers would be), and the bias the finite sample leaves in
  the slope, estimated from the slope of the difference between half and all
  the counts over the window (a sample's bias falls as one over its size).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..measures.boxes import default_scales
from .constants import MIN_DECADES
from .fit import Z95, Fit, _families, _line, _local_slopes, _scaling_fit, _window

DEFAULT_Q = np.arange(0.0, 6.01, 0.5)
"""The q of a spectrum unless told: from 0 to 6 by halves."""
GROUPS = 16
"""Parts of the counts for the jackknife."""
SHIFTS = 1
"""Grids per side, shifted by 0, 1/SHIFTS, ... of the side along the diagonal, whose sums are averaged. One, its
corner at the lowest point: a grid shifted within a filled region cuts boxes at the region's edges, which biases
D(1) of a filled set low."""
PER_OCTAVE = 4
"""Box sides per factor of two."""


class _Moments:
    """A result indexed by moment q (its attribute ``q``): ``at`` finds a moment's index."""

    q: np.ndarray

    def at(self, q: float) -> int:
        """The index of moment ``q``.

        Parameters
        ----------
        q : float
            A moment of ``self.q``.

        Returns
        -------
        int
        """
        where = np.flatnonzero(np.isclose(self.q, q))
        if not len(where):
            raise KeyError(f"q={q} not in the spectrum's q: {self.q.tolist()}")
        return int(where[0])


@dataclass(frozen=True)
class Spectrum(_Moments):
    """The generalised dimensions and the f(alpha) spectrum of a sampled measure.

    Attributes
    ----------
    q : ndarray
        The moments.
    D, stderr : ndarray
        D(q) and its standard error (the fit's, the jackknife's and the sample's bias in quadrature).
    ci_lo, ci_hi : ndarray
        95% intervals, ``D -+ 1.96 stderr``.
    alpha, alpha_err, f, f_err : ndarray
        The direct method's alpha(q) and f(q) over D(q)'s window, with standard errors
        (the fit's, statistical and systematic, and the jackknife's in quadrature).
    ok : ndarray of bool
        Whether D(q) is trusted: a flat fitted window of ``min_decades`` within the sides the counts resolve.
    reasons : tuple of str
        Why not, for each q ('' when ``ok``).
    range_lo, range_hi : ndarray
        Each q's fitted window of box sides.
    fits : tuple of Fit
        Each q's fit of D (``fit.Fit``), its error before the jackknife and the bias were added.
    sampling, bias : ndarray
        The parts of ``stderr`` beyond the fit's: the jackknife's sampling error, and the
        bias the finite sample leaves in the slope.
    counts : int
        The counts (walkers) the measure was sampled with.
    """

    q: np.ndarray
    D: np.ndarray
    stderr: np.ndarray
    ci_lo: np.ndarray
    ci_hi: np.ndarray
    alpha: np.ndarray
    alpha_err: np.ndarray
    f: np.ndarray
    f_err: np.ndarray
    ok: np.ndarray
    reasons: tuple
    range_lo: np.ndarray
    range_hi: np.ndarray
    fits: tuple
    sampling: np.ndarray
    bias: np.ndarray
    counts: int


def _sides(extent, min_scale):
    """Whole box sides from ``min_scale`` up to ``extent``, ``PER_OCTAVE`` to a factor of two
    (``boxes.default_scales``: families b, 2b, 4b, ... whose grids nest)."""
    sides = default_scales(extent, PER_OCTAVE)
    return sides[(sides >= min_scale) & (sides <= extent)]


def _sums(points, weights, sides, q):
    """The shift-averaged sums at each side for each weight column: log Z(q) / (q - 1)
    (sum p log p at q = 1), sum mu log p and sum mu log mu, each (sides, q, columns); and for the
    first column (whole counts) at each side, log(1 + n1**2 / (2 n2 N)): the boxes no count reached,
    as Chao's estimate (n1 and n2 boxes hold one and two counts, N any) adds them to those it did."""
    lo = points.min(axis=0)
    columns = weights.shape[1]
    shape = (len(sides), len(q), columns)
    Z, H, A, F = (np.zeros(shape) for _ in range(4))
    unseen = np.zeros(len(sides))
    total = weights.sum(axis=0)
    for j, s in enumerate(sides):
        for t in range(SHIFTS):
            cells = np.floor((points - lo) / s + t / SHIFTS).astype(np.int64)
            span = cells.max(axis=0) + 1
            key = np.ravel_multi_index(cells.T, span)
            _, inverse = np.unique(key, return_inverse=True)
            boxes = np.stack([np.bincount(inverse, weights[:, c]) for c in range(columns)], axis=1)
            n1, n2 = (boxes[:, 0] == 1).sum(), (boxes[:, 0] == 2).sum()
            unseen[j] += np.log1p(n1 * n1 / (2.0 * max(n2, 1) * len(boxes))) / SHIFTS
            boxes /= total
            held = boxes > 0
            logp = np.log(np.where(held, boxes, 1.0))
            for k, qk in enumerate(q):
                pq = np.where(held, np.exp(qk * logp), 0.0)
                z = pq.sum(axis=0)
                mu = pq / z
                Z[j, k] += z / SHIFTS
                H[j, k] += (boxes * logp).sum(axis=0) / SHIFTS
                A[j, k] += (mu * logp).sum(axis=0) / SHIFTS
                F[j, k] += (mu * np.log(np.where(held, mu, 1.0))).sum(axis=0) / SHIFTS
    one = np.isclose(q, 1.0)
    with np.errstate(divide="ignore"):
        Y = np.where(one[None, :, None], H, np.log(Z) / np.where(one, 1.0, q - 1.0)[None, :, None])
    return Y, A, F, unseen


def multifractal_spectrum(points, counts=None, q=DEFAULT_Q, *, min_scale: float = 2.0, max_fraction: float = 0.25,
                          min_decades: float = MIN_DECADES, min_points: int = 4, flat_tolerance: float = 0.02,
                          tolerance: float = 0.05, groups: int = GROUPS, seed: int = 0) -> Spectrum:
    """D(q) and f(alpha) of the measure ``counts`` on ``points``, with error bars (module docstring).

    Parameters
    ----------
    points : array_like (n, dim) or HarmonicMeasure
        Where the measure sits (a particle's centre or site); a ``HarmonicMeasure`` gives its
        cluster's points and its hits.
    counts : array_like (n,) of int, optional
        The measure's sample: how many counts (walkers) each point received. Given with points only.
    q : array_like
        The moments, q >= 0.
    min_scale : float
        Smallest box side (particle sizes): below, a box holds part of one particle.
    max_fraction : float
        Largest box side, as a fraction of the extent of the points that received counts.
    min_decades : float
        Narrowest window fitted, in decades of box side (``fit.fit_dimension``).
    min_points : int
        Fewest sides in the window fitted (``fit.fit_dimension``).
    flat_tolerance : float
        Change of the local slope across a window, beyond twice its standard error, that
        still counts as flat (``fit.fit_dimension``).
    tolerance : float
        Largest difference between the sums of half the counts and of all, in log Z / (q - 1),
        at an admissible side.
    groups : int
        Parts of the counts for the jackknife, >= 4.
    seed : int
        The stream that gives each count its part.

    Returns
    -------
    Spectrum
    """
    if counts is None:
        if not hasattr(points, "hits"):
            raise TypeError("counts: needed with points (or pass a HarmonicMeasure alone)")
        points, counts = points.points, points.hits
    points = np.asarray(points, np.float64)
    counts = np.asarray(counts)
    q = np.atleast_1d(np.asarray(q, np.float64))
    if points.ndim != 2 or counts.shape != (len(points),):
        raise ValueError(f"points and counts: expected (n, dim) and (n,), got {points.shape} and {counts.shape}")
    if counts.dtype.kind not in "iu" or (counts < 0).any():
        raise ValueError("counts: expected non-negative whole counts")
    if (q < 0).any():
        raise ValueError(f"q: expected q >= 0, got {q.tolist()}")
    if groups < 4:
        raise ValueError(f"groups: expected at least 4, got {groups}")
    held = counts > 0
    points, counts = points[held], counts[held].astype(np.int64)
    total = int(counts.sum())
    nq = len(q)
    nan = np.full(nq, np.nan)
    if total < 2 * groups:
        fits = tuple(Fit(np.nan, np.nan, np.nan, np.nan, np.nan, np.nan, 0, np.nan, False, "too few counts")
                     for _ in q)
        return Spectrum(q, nan, nan, nan, nan, nan, nan, nan, nan, np.zeros(nq, bool),
                        ("too few counts",) * nq, nan, nan, fits, nan, nan, total)
    parts = np.random.default_rng(seed).multinomial(counts, np.full(groups, 1.0 / groups))  # (n, groups)
    # the columns: all the counts, half of them, and all but each part
    weights = np.concatenate([counts[:, None], parts[:, :groups // 2].sum(axis=1)[:, None],
                              counts[:, None] - parts], axis=1).astype(np.float64)
    extent = float((points.max(axis=0) - points.min(axis=0)).max()) + 1.0
    sides = _sides(max_fraction * extent, min_scale)
    sides = sides[sides <= max_fraction * extent * (1 + 1e-9)]
    if len(sides):
        Y, A, F, unseen = _sums(points, weights, sides, q)
    else:
        Y, A, F, unseen = (np.zeros((0, nq, 2 + groups)),) * 3 + (np.zeros(0),)
    x = np.log(sides)
    families = _families(tuple(sides))
    out = {k: np.full(nq, np.nan) for k in ("D", "err", "alpha", "aerr", "f", "ferr", "lo", "hi",
                                                   "sampling", "bias")}
    ok = np.zeros(nq, bool)
    reasons, fits = [], []
    for k in range(nq):
        y, half = Y[:, k, 0], Y[:, k, 1]
        good = np.isfinite(y) & np.isfinite(half) & (np.abs(half - y) <= tolerance)
        if q[k] < 1:  # boxes no count reached weigh in: as many as the counts leave unseen, at most
            good &= unseen <= tolerance
        # the sides from the largest down, as far as each one is resolved
        first = len(sides)
        while first > 0 and good[first - 1]:
            first -= 1
        keep = slice(first, len(sides))
        fit = _scaling_fit(x[keep], y[keep], sides[keep], families[keep], 1.0,
                           min_decades=min_decades, min_points=min_points, flat_tolerance=flat_tolerance,
                           unit="box side")
        if first > 0 and not fit.ok:
            fit = Fit(*[getattr(fit, name) for name in ("D", "stderr", "ci_lo", "ci_hi", "range_lo", "range_hi",
                                                        "npoints", "drift", "ok")],
                      reason=f"{fit.reason} (the counts resolve "
                             + (f"sides from {sides[first]:.3g} up)" if first < len(sides) else "no side)"))
        fits.append(fit)
        reasons.append(fit.reason)
        if not np.isfinite(fit.D):
            continue
        window = (sides >= fit.range_lo * (1 - 1e-9)) & (sides <= fit.range_hi * (1 + 1e-9))
        xw = x[window]

        def slope(v):
            return _line(xw, v[window], families[window])[0]

        def jackknife(V):
            loo = np.array([slope(V[:, 2 + g]) for g in range(groups)])
            return np.sqrt((groups - 1) / groups * ((loo - loo.mean()) ** 2).sum())

        bias = abs(slope(Y[:, k, 1] - Y[:, k, 0]))
        sampling = jackknife(Y[:, k])
        err = np.sqrt(fit.stderr ** 2 + sampling ** 2 + bias ** 2)
        out["sampling"][k], out["bias"][k] = sampling, bias
        out["D"][k], out["err"][k] = fit.D, err
        out["lo"][k], out["hi"][k] = fit.range_lo, fit.range_hi
        a, b = np.flatnonzero(window)[[0, -1]] + [0, 1]
        for name, V in (("alpha", A), ("f", F)):
            # the fit's errors over D's window (statistical, and half the change of the local slope)
            w = _window(x, V[:, k, 0], x, families, 1.0, _local_slopes(x, V[:, k, 0], x, families), a, b,
                        flat_tolerance)
            out[name][k] = w.D
            out["aerr" if name == "alpha" else "ferr"][k] = np.hypot(w.stderr, jackknife(V[:, k]))
        ok[k] = fit.ok
    D, err = out["D"], out["err"]
    return Spectrum(q, D, err, D - Z95 * err, D + Z95 * err, out["alpha"], out["aerr"], out["f"], out["ferr"], ok,
                    tuple(reasons), out["lo"], out["hi"], tuple(fits), out["sampling"], out["bias"], total)


@dataclass(frozen=True)
class SeedSpectrum(_Moments):
    """D(q) of a configuration over its seeds.

    Attributes
    ----------
    q : ndarray
        The moments.
    mean, ci_lo, ci_hi : ndarray
        Mean over seeds of each q's trusted D(q) (``ok``) and its 95% confidence interval (Student's t,
        ``fit.ensemble``; NaN below ``MIN_CI_SEEDS`` trusted values).
    n : ndarray of int
        Seeds whose D(q) is trusted, for each q.
    """

    q: np.ndarray
    mean: np.ndarray
    ci_lo: np.ndarray
    ci_hi: np.ndarray
    n: np.ndarray


def seed_spectrum(q, D, ok) -> SeedSpectrum:
    """D(q) over seeds: each q's trusted values (``ok``) averaged, with a 95% interval over seeds.

    Only the trusted values count: an untrusted one is a fit whose window is
    not flat or that the walkers do not resolve, whose error bar does not
    hold. The seeds are independent clusters, so the interval over them
    holds the spread of the clusters and of each one's sampling together.

    Parameters
    ----------
    q : array_like (nq,)
        The moments.
    D : array_like (seeds, nq)
        Each seed's D(q) (``harmonic_D`` of a sweep's configuration).
    ok : array_like (seeds, nq) of bool
        Whether each is trusted (``harmonic_D_ok``).

    Returns
    -------
    SeedSpectrum
    """
    from .constants import MIN_CI_SEEDS
    from .fit import ensemble

    q = np.asarray(q, np.float64)
    D = np.asarray(D, np.float64).reshape(-1, len(q))
    ok = np.asarray(ok, bool).reshape(D.shape) & np.isfinite(D)
    trusted = np.where(ok, D, np.nan)
    stats = [ensemble(trusted[:, k]) for k in range(len(q))]
    few = np.array([s.n < MIN_CI_SEEDS for s in stats])
    lo = np.where(few, np.nan, [s.ci_lo for s in stats])
    hi = np.where(few, np.nan, [s.ci_hi for s in stats])
    return SeedSpectrum(q, np.array([s.mean for s in stats]), lo, hi, np.array([s.n for s in stats]))


@dataclass(frozen=True)
class SizeScaling(_Moments):
    """D(q) of a configuration's harmonic measure from its growth with the cluster's size, between successive counts.

    Attributes
    ----------
    q : ndarray (nq,)
        The moments.
    counts : ndarray (K,)
        The particle counts; the slopes are between successive ones.
    D, ci_lo, ci_hi : ndarray (K - 1, nq)
        D(q): the change of the mean Renyi entropy H_q over the change of the log of the mean Rg,
        with its 95% CI over seeds; each H_q corrected for the walkers' finite number
        (``size_scaling``).
    correction : ndarray (K - 1, nq)
        The part of D(q) that correction makes: the slope of the entropies of all the walkers
        minus those of the first half.
    ok : ndarray (K - 1, nq) of bool
        Whether D(q) is trusted: an interval, and a correction no larger than its half-width (the
        correction removes the leading term of the bias, which must dominate what it leaves).
    mass, mass_ci_lo, mass_ci_hi : ndarray (K - 1,)
        The mass dimension between the same counts, the change of log N over that of the log of the
        mean Rg, with its 95% CI over the same seeds.
    halsey, halsey_ci_lo, halsey_ci_hi : ndarray (K - 1,)
        2 D(3) - the mass dimension, with its 95% CI: Halsey's relation says 0. Both slopes come from the
        same clusters, so the interval is of the paired difference. NaN without q = 3.
    seeds : int
        Seeds used: those with every count's values.
    """

    q: np.ndarray
    counts: np.ndarray
    D: np.ndarray
    ci_lo: np.ndarray
    ci_hi: np.ndarray
    correction: np.ndarray
    ok: np.ndarray
    mass: np.ndarray
    mass_ci_lo: np.ndarray
    mass_ci_hi: np.ndarray
    halsey: np.ndarray
    halsey_ci_lo: np.ndarray
    halsey_ci_hi: np.ndarray
    seeds: int


def size_scaling(q, counts, rg, entropy, half=None, *, resamples: int = 2000, seed: int = 0) -> SizeScaling:
    """D(q) from how the harmonic measure's Renyi entropies grow with the cluster, and Halsey's check.

    The growth probabilities p_i of a cluster's particles (``HarmonicMeasure.renyi_entropies``) have
    sum_i p_i**q ~ R**(-(q - 1) D(q)) as the cluster grows: the Renyi entropy H_q grows as D(q) log R.
    This is the scaling that Halsey's relation 2 D(3) = D (D the cluster's mass dimension) and
    Makarov's D(1) = 1 are statements about, and it needs no box sides: the box partition sums of one
    cluster (``multifractal_spectrum``) read the same exponents from how the measure is spread within
    the cluster, over the few decades of sides a finite cluster offers, where the corrections to
    scaling are others.

    Between successive counts, D(q) is the change of the mean of H_q over seeds over the change of the
    log of the mean Rg, as the headline D is a slope of the mean Rg; the mass dimension between the
    same counts comes from the same seeds, so that Halsey's difference is paired. The intervals are
    ``fit.seed_interval`` over a bootstrap of the seeds (``fit.bootstrap_means``).

    A sample of M walkers biases each H_q by a term in 1/M (the unseen particles lower Shannon's
    entropy by about (K - 1) / 2M, K the particles hit; the sums of p**q of counts are high by
    about 1/M), and the bias grows with the cluster as K does, so that it tilts the slopes. With
    ``half``, the entropies of the first half of the walkers, each H_q is taken as
    2 H_q(M) - H_q(M/2) (Richardson's extrapolation in 1/M), which removes that term.

    Parameters
    ----------
    q : array_like (nq,)
        The moments.
    counts : array_like (K,)
        Particle counts, ascending, K >= 2.
    rg : array_like (seeds, K)
        Each seed's radius of gyration at each count.
    entropy : array_like (seeds, K, nq)
        Each seed's H_q at each count, of all its walkers.
    half : array_like (seeds, K, nq), optional
        The same of the first half of the walkers (``renyi_entropies(q, first=walkers // 2)``);
        without it no correction is made and none is trusted.
    resamples : int
        Bootstrap draws of the seeds.
    seed : int
        The bootstrap's stream.

    Returns
    -------
    SizeScaling
    """
    from .constants import MIN_CI_SEEDS
    from .fit import bootstrap_means, seed_interval

    q = np.atleast_1d(np.asarray(q, np.float64))
    counts = np.asarray(counts, np.float64)
    rg = np.asarray(rg, np.float64)
    k, nq = len(counts), len(q)
    entropy = np.asarray(entropy, np.float64).reshape(len(rg), k, nq)
    correction = np.full_like(entropy, np.nan) if half is None else entropy - np.asarray(half, np.float64).reshape(
        entropy.shape)
    whole = np.isfinite(rg).all(axis=1) & np.isfinite(entropy).all(axis=(1, 2))
    rg, entropy, correction = rg[whole], entropy[whole], correction[whole]
    n = len(rg)
    corrected = entropy + np.nan_to_num(correction)
    # a row per seed: Rg (its mean's log is taken), the corrected entropies, their corrections
    rows = np.concatenate([rg, corrected.reshape(n, k * nq), correction.reshape(n, k * nq)], axis=1)

    def slopes(means):
        means = np.atleast_2d(means)
        dr = np.diff(np.log(means[:, :k]), axis=1)  # (draws, K - 1)
        h = means[:, k:k * (1 + nq)].reshape(len(means), k, nq)
        c = means[:, k * (1 + nq):].reshape(len(means), k, nq)
        D = np.diff(h, axis=1) / dr[..., None]
        mass = np.diff(np.log(counts))[None, :] / dr
        three = np.isclose(q, 3.0)
        halsey = 2 * D[..., np.argmax(three)] - mass if three.any() else np.full_like(mass, np.nan)
        return D, np.diff(c, axis=1) / dr[..., None], mass, halsey

    nan, untrusted = np.full((k - 1, nq), np.nan), np.zeros((k - 1, nq), bool)
    line = nan[:, 0]
    if n == 0:
        return SizeScaling(q, counts, nan, nan, nan, nan, untrusted, line, line, line, line, line, line, 0)
    D, shift, mass, halsey = (v[0] for v in slopes(rows.mean(axis=0)))
    if n < MIN_CI_SEEDS:
        return SizeScaling(q, counts, D, nan, nan, shift, untrusted, mass, line, line, halsey, line, line, n)
    boot = slopes(bootstrap_means(rows, np.random.default_rng(seed), resamples))
    (lo, hi), (mlo, mhi), (hlo, hhi) = (seed_interval(est, rep, n, axis=0)
                                        for est, rep in ((D, boot[0]), (mass, boot[2]), (halsey, boot[3])))
    ok = np.abs(shift) <= (hi - lo) / 2  # NaN (no correction) compares False
    return SizeScaling(q, counts, D, lo, hi, shift, ok, mass, mlo, mhi, halsey, hlo, hhi, n)
