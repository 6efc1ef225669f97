"""The statistical constants, once: how sure an interval is, how it is resampled, where a fit starts.

Every estimate of D, every interval and every growth history the package
samples reads these (``fit``, ``summary``, the report's words about them).
"""

CONFIDENCE = 0.95
"""Level of every interval: fits' CIs, intervals over seeds, bootstrap bands."""
LEVEL = f"{CONFIDENCE:.0%}"
"""``CONFIDENCE`` as the words, labels and long names say it ("95%")."""

RESAMPLES = 1000
"""Bootstrap resamples over seeds. Each interval draws its own stream (``summary``), so that
reruns agree and a statistic does not depend on which others were computed before it."""

MIN_CI_SEEDS = 3
"""Fewest clusters an interval over seeds needs; with fewer, every interval is NaN and says why.

Over 2 seeds the spread has one degree of freedom: the interval would be
+-12.7 standard errors (``fit.t95(1)``), wider than any difference in D it
could resolve, and its coverage would rest wholly on the normality of one
difference. From 3 seeds the t-scaled interval holds its coverage on
ensembles of growth histories of known D (tests/test_analysis.py; the figures
in docs/performance.md, "Statistics")."""

START_FRACTION = 0.05
"""End of the transient of a growth history, as a fraction of its largest count (``fit.mass_radius_counts``)."""

MIN_COUNT = 50
"""Fewest particles a growth history is read from (the local-slope curve, the mass-radius fit):
below, a cluster is a compact blob, not a fractal."""

PER_OCTAVE = 8
"""Counts per octave (factor two) at which a growth history is sampled: the mass-radius fit
and the local-slope curve."""

MIN_DECADES = 1.0
"""Narrowest window a fit of D accepts, in decades of its variable (both fits)."""
