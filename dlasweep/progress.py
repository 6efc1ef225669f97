"""Progress of a sweep as lines on stderr, for a log: where a progress bar would be a mess (not a terminal)."""

from __future__ import annotations

import sys
import time


class Lines:
    """A line each time another ``fraction`` of the clusters has finished (``gap`` seconds at least after the
    last line, so a quick sweep stays quiet), or ``seconds`` after it once one more has: ``tqdm``'s
    ``update`` and context, printing for a log file. The command says when the sweep ends.

    Parameters
    ----------
    total, initial : int
        Clusters in the sweep, and those finished before it started (a resumed run's).
    desc : str
        The start of each line (the spec's name).
    """

    def __init__(self, total, initial=0, desc="", fraction=0.1, seconds=10.0, gap=1.0, file=None):
        self.total, self.n, self.desc = total, initial, desc
        self.initial, self.step, self.seconds, self.gap = initial, max(1, round(fraction * total)), seconds, gap
        self.file = file or sys.stderr
        self.start = self.last = time.monotonic()
        self.shown = initial

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return False

    def update(self, n=1):
        """Count ``n`` more finished clusters; print a line when one is due."""
        self.n += n
        now = time.monotonic()
        since = now - self.last
        if since >= self.seconds or (since >= self.gap and self.n - self.shown >= self.step):
            self.shown, self.last = self.n, now
            print(self._line(now - self.start), file=self.file, flush=True)

    def _line(self, elapsed) -> str:
        line = (f"{self.desc} {time.strftime('%H:%M:%S')}: {self.n}/{self.total} clusters finished "
                f"({100 * self.n / self.total:.0f}%) in {_duration(elapsed)}")
        done = self.n - self.initial
        if self.n < self.total and done:
            line += f", about {_duration(elapsed / done * (self.total - self.n))} left"
        return line


def _duration(seconds) -> str:
    """``42 s``, ``12 min``, ``3.5 h``."""
    if seconds < 120:
        return f"{seconds:.0f} s"
    return f"{seconds / 60:.0f} min" if seconds < 7200 else f"{seconds / 3600:.1f} h"
