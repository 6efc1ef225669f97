"""D_inf: the local slope D_eff(n) of a growth history extrapolated to infinite N.

D_eff(n) = D_inf + a n**-w is fitted over independent octaves for each
correction exponent w of ``EXPONENTS``, from the lowest octave on at which
the model describes the data; D_inf is given only where it does and its
interval is narrow enough to say something (``summary`` fills the
summary's ``D_inf`` variables from it).
"""

from __future__ import annotations

import numpy as np

from .constants import LEVEL, PER_OCTAVE
from .fit import seed_interval

EXPONENTS = (0.25, 0.5, 0.75, 1.0)
"""Correction exponents w tried for D_eff(n) = D_inf + a n**-w."""
MAX_CHI2 = 2.0
"""Largest chi-square per degree of freedom at which the correction model describes D_eff."""
MAX_INF_HALF_WIDTH = 0.05
"""Widest 95% CI half-width of D_inf worth reporting; wider, the data do not constrain it."""
MIN_OCTAVES = 4
"""Fewest independent octaves of D_eff an extrapolation needs."""


def extrapolate(centres, local, band, n_seeds) -> dict:
    """D_inf from D_eff(n) = D_inf + a n**-w over independent (non-overlapping) octaves.

    Parameters
    ----------
    centres : ndarray
        Each octave's geometric centre (the summary's ``n_local``); octaves
        overlap, ``PER_OCTAVE`` apart they are independent.
    local : ndarray
        D_eff over each octave.
    band : ndarray, (octave, resample)
        The bootstrap of D_eff over ``n_seeds`` clusters.
    n_seeds : int
        Clusters the bootstrap resamples: the interval of D_inf is over them (``fit.seed_interval``).

    Returns
    -------
    dict
        The summary's ``D_inf``, its CI, ``D_inf_exponent`` and ``D_inf_range_lo``; or ``D_inf_reason`` alone.
    """
    pick = np.arange(len(local) - 1, -1, -PER_OCTAVE)[::-1]  # back from the largest octave
    centres = centres[pick]
    y, boot = local[pick], band[pick]
    sigma = boot.std(axis=1, ddof=1)
    if len(pick) < MIN_OCTAVES:
        return {"D_inf_reason": f"{len(pick)} independent octaves of D_eff, need {MIN_OCTAVES}"}
    best = None
    # The smallest octaves are the transient: start as low as the model allows.
    for start in range(len(pick) - MIN_OCTAVES + 1):
        for w in EXPONENTS:
            design = np.c_[np.ones(len(pick) - start), centres[start:] ** -w]
            weights = 1 / sigma[start:]
            coef, *_ = np.linalg.lstsq(design * weights[:, None], y[start:] * weights, rcond=None)
            chi2 = (((design @ coef - y[start:]) * weights) ** 2).sum() / (len(design) - 2)
            if chi2 <= MAX_CHI2 and (best is None or chi2 < best[0]):
                best = (chi2, start, w, design, weights, coef)
        if best is not None:
            break
    if best is None:
        return {"D_inf_reason": (f"D_eff(n) is not D_inf + a n^-w for any w in {EXPONENTS} "
                                 f"(chi2/dof > {MAX_CHI2:g} over every range of {MIN_OCTAVES} octaves)")}
    _, start, w, design, weights, coef = best
    solve = np.linalg.pinv(design * weights[:, None])
    values = solve[0] @ (boot[start:] * weights[:, None])
    lo, hi = seed_interval(coef[0], values, n_seeds)
    if (hi - lo) / 2 > MAX_INF_HALF_WIDTH:
        return {"D_inf_reason": f"extrapolation too uncertain ({LEVEL} CI half-width {(hi - lo) / 2:.3f})"}
    return {"D_inf": coef[0], "D_inf_ci_lo": lo, "D_inf_ci_hi": hi, "D_inf_exponent": w,
            "D_inf_range_lo": centres[start]}
