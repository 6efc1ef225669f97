"""Progress on stderr: bars on a terminal (tqdm, ``growth_bar``, ``steps_bar``), and a sweep's lines for a
log (``Lines``), where a progress bar would be a mess."""

from __future__ import annotations

import contextlib
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


def growth_bar(n, model, dim, walkers=1):
    """A progress bar for ``grow`` on a terminal (particles, rate, time left), else ``nullcontext(None)``.

    Announces first that the kernels compile when numba's cache lacks them.
    The bar shows once growth has taken a second: small clusters print nothing more.
    """
    if not sys.stderr.isatty():
        return contextlib.nullcontext()
    from ..growth.cluster import compiled

    if not compiled(model, dim, walkers):
        print("dlasweep grow: compiling kernels (once)", file=sys.stderr)
    from tqdm import tqdm

    return tqdm(total=n, unit=" particles", unit_scale=True, desc="grow", file=sys.stderr, delay=1.0, leave=False)


def steps_bar(desc):
    """A progress bar of named steps on a terminal (shown after a second), else ``nullcontext(None)``."""
    if not sys.stderr.isatty():
        return contextlib.nullcontext()
    from tqdm import tqdm

    return tqdm(desc=desc, unit="step", file=sys.stderr, delay=1.0, leave=False,
                bar_format="{desc}: {n}/{total} [{elapsed}<{remaining}]{postfix}")


def follow(bar):
    """``progress(done, steps, name)`` that moves ``bar`` to step ``done`` of ``steps``, named."""
    def progress(done, steps, name):
        bar.total = steps
        bar.set_postfix_str(name, refresh=False)
        bar.update(done - bar.n)
    return progress
