"""Precision on demand (``[run] target_ci``): how many seeds a target sweep grows, batch by batch.

The seeds of the spec are a first batch. After each batch the sweep's
dataset is assembled and its headline D computed (``stats.summary.headline``);
while the 95% CI half-width of the headline D at the largest count is above
the target for some configuration (NaN counts as above) and fewer than
``max_seeds`` seeds are grown, every configuration gets more seeds,
replicates n..m-1 (``more_seeds`` says how many). Replicate j is the same task
in every batch, so a batch grows only new replicates, the result equals a
fixed sweep with the final count, and a resumed run replays the same batches
from its parts.

``Precision`` is the loop's decision as ask/tell: ``ask`` gives the spec of
the batch to grow, ``tell`` takes its dataset. It knows no dask and no file,
so the runner (``sweep.runner``) drives it and a test can drive it by hand.
"""

from __future__ import annotations

import numpy as np

from ..stats.summary import headline

TARGET_REACHED, CAP_REACHED, TASKS_FAILED = "target_ci reached", "max_seeds reached", "tasks failed"
"""Why a target sweep stopped (its ``stop_reason``); failed tasks stop it so that
``--resume`` retries them rather than seeds being added around them."""


class Precision:
    """The batches of a sweep: its spec once, or, with ``target_ci``, first batch and more until the target.

    Parameters
    ----------
    spec : Spec
        The sweep's spec; without ``target_ci`` its one batch is the spec itself.
    """

    def __init__(self, spec):
        self.spec = spec
        self.batch = spec
        self.half_width = None
        """CI half-width of the headline D per configuration after the last batch told (target sweeps)."""
        self.reason = None
        """Why a target sweep stopped (``TARGET_REACHED``, ``CAP_REACHED``, ``TASKS_FAILED``), once it has."""

    def ask(self):
        """The spec of the batch to grow next, or ``None`` once the sweep is done."""
        return self.batch

    def tell(self, ds, failed):
        """Take the dataset assembled after the batch ``ask`` gave, and its failed tasks; decide the next batch.

        Parameters
        ----------
        ds : xarray.Dataset
            The sweep's dataset with every seed grown so far (no clusters needed).
        failed : sequence
            The batch's failed tasks, (key, message) pairs: they stop a target sweep.

        Returns
        -------
        Spec or None
            The next batch (as ``ask`` gives it), or ``None``: the sweep is done.
        """
        if self.spec.target_ci is None:
            self.batch = None
            return None
        self.half_width = ci_half_width(ds)
        more, self.reason = more_seeds(self.spec, len(self.batch.seeds), self.half_width.values, failed)
        self.batch = self.spec.with_seeds(more) if more else None
        return self.batch


def ci_half_width(ds):
    """Half-width of the 95% CI of the headline D at the largest count, per configuration.

    NaN where there is no interval (too few seeds or too small clusters).
    """
    top = headline(ds)
    return ((top["D_ci_hi"] - top["D_ci_lo"]) / 2).reset_coords(drop=True)


def more_seeds(spec, n, half_width, failed):
    """Seeds the next batch should bring the sweep to, or ``None`` and why it stops.

    The CI half-width of a mean over n seeds falls as 1/sqrt(n), so a
    configuration at half-width w needs about ``n * (w / target_ci)**2``
    seeds; a tenth more covers the noise of w, so that one more batch usually
    suffices (bootstrap intervals from few seeds are, if anything, too
    narrow, so the estimate errs towards too few seeds, not too many). A
    configuration without an interval yet (NaN) asks for twice n. The worst
    configuration sets the batch, which is at least one first batch (so the
    workers get a batch worth distributing) and at most ``max_seeds``.

    Parameters
    ----------
    spec : Spec
        A target sweep's spec (``target_ci`` set).
    n : int
        Seeds grown so far.
    half_width : ndarray
        CI half-width of every configuration after n seeds.
    failed : sequence
        Failed tasks of the batch: they stop the sweep.

    Returns
    -------
    (int, None) or (None, str)
        The new seed count, or the stop reason.
    """
    if failed:
        return None, TASKS_FAILED
    unmet = ~(half_width <= spec.target_ci)  # NaN compares False: unmet
    if not unmet.any():
        return None, TARGET_REACHED
    if n >= spec.max_seeds:
        return None, CAP_REACHED
    wanted = np.where(np.isnan(half_width), 2 * n, np.ceil(1.1 * n * (half_width / spec.target_ci) ** 2))
    return min(spec.max_seeds, max(n + len(spec.seeds), int(wanted[unmet].max()))), None
