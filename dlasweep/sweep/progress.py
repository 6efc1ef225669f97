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


COMPILE_TIME = {2: "about a minute", 3: "one to two minutes"}
"""How long a growth kernel takes to compile, by dimension, said roughly (a 3D kernel takes longer
than a 2D one), so that the words hold on a faster or slower machine; the figures are in
docs/performance.md and in ``dlasweep bench``'s ``cold`` rows."""


def compiling(kernels) -> str:
    """What compiles and how long to expect, e.g. ``compiling the off-lattice 2D kernels, once: about a minute``,
    and, where ``dlasweep compile`` would have compiled them (each model's defaults), that it does.

    ``kernels`` lists (model, dim, lockstep, gaussian) of the growth kernels that numba's cache lacks
    (``growth.cluster.kernel_of``); lockstep walkers and Gaussian steps are kernels of their own.
    """
    names = [f"{'off-lattice' if model == 'offlattice' else 'lattice'} {dim}D"
             + (" lockstep" if lockstep else "") + (" Gaussian-step" if gaussian else "")
             for model, dim, lockstep, gaussian in kernels]
    each = " each" if len(names) > 1 else ""
    # the kernels `dlasweep compile` compiles ahead: each model's defaults, one walker and exact moves
    ahead = " (`dlasweep compile` compiles every model ahead)" if not any(
        lockstep or gaussian for _, _, lockstep, gaussian in kernels) else ""
    return (f"compiling the {', '.join(names[:-1]) + ' and ' if len(names) > 1 else ''}{names[-1]} kernels, "
            f"once: {COMPILE_TIME[max(dim for _, dim, _, _ in kernels)]}{each}{ahead}")


def growth_bar(n, params):
    """A progress bar for ``grow`` on a terminal (particles, rate, time left), else ``nullcontext(None)``.

    Says first, on a terminal or in a log, what compiles and how long to expect when numba's cache
    lacks the kernel of the resolved parameters ``params`` (``compiling``). The bar shows once growth
    has taken a second: small clusters print nothing more.
    """
    from ..growth.cluster import compiled, kernel_of

    if not compiled(params):
        print(f"dlasweep grow: {compiling([kernel_of(params)])}", file=sys.stderr, flush=True)
    if not sys.stderr.isatty():
        return contextlib.nullcontext()
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
