"""Report of a sweep: a summary table, plots and a short write-up.

Draws and writes what ``stats.summary.summarise`` computes (the headline
ensemble mass-radius D with its 95% CI, local slopes, D_inf, box-counting D,
Rg, costs), read through ``readout.Readout`` (rows, labels, the exact
reference, fitted lines, plot ranges, biases); it computes nothing else. Writes ``summary.csv``,
``summary.md``, PNG plots and ``report.md`` into one folder, which holds
one report: an earlier report there is removed first (``files`` names
everything a report may write), a folder holding anything else is refused.
Plots the dataset has no data for are skipped, never drawn empty. The
plots are ``plots``', the tables and the words ``text``'s;
this module runs them into the folder.
"""

from __future__ import annotations

from pathlib import Path

from .plots import PLOTS
from .readout import Readout
from .text import write_csv, write_report, write_table

TABLES = ("summary.csv", "summary.md")
WRITEUP = "report.md"


def report(ds, outdir, progress=None) -> list:
    """Write the report of a sweep into ``outdir``.

    Parameters
    ----------
    ds : xarray.Dataset
        A sweep, as from ``run_sweep`` or ``open_sweep``.
    outdir : str or Path
        Created when missing.
    progress : callable, optional
        Called as ``progress(done, steps, name)`` as each step starts (the
        summary, the tables, each plot, report.md) and once at the end.

    Returns
    -------
    list of Path
        Every file written: ``summary.csv``, ``summary.md``, the plots that
        the dataset has data for, and ``report.md``.

    Raises
    ------
    ReportFolderError
        When ``outdir`` holds anything but an earlier report; nothing is written then.
    """
    steps = ["summary", "tables", *PLOTS, WRITEUP, ""]
    done = iter(range(len(steps)))

    def tell():
        if progress:
            k = next(done)
            progress(k, len(steps) - 1, steps[k])

    out = Path(outdir)
    earlier = earlier_report(out)
    tell()
    sweep = Readout(ds)  # before the folder is touched: a dataset that cannot be read leaves an earlier report whole
    for name in earlier:
        (out / name).unlink()
    out.mkdir(parents=True, exist_ok=True)
    tell()
    written = [write_csv(sweep, out / TABLES[0]), write_table(sweep, out / TABLES[1])]
    figures = {}
    for name, draw in PLOTS.items():
        tell()
        caption = draw(sweep, out / f"{name}.png")
        if caption:
            figures[name] = caption
            written.append(out / f"{name}.png")
    tell()
    written.append(write_report(sweep, figures, out / WRITEUP))
    tell()
    return written


class ReportFolderError(ValueError):
    """A report's folder that holds something other than a report."""


def files() -> set:
    """The name of every file a report may write."""
    return {*TABLES, *(f"{name}.png" for name in PLOTS), WRITEUP}


def earlier_report(outdir) -> list:
    """The files of an earlier report in ``outdir``, which the next one replaces (none when it is missing).

    Raises
    ------
    ReportFolderError
        When ``outdir`` is not a folder, or holds anything a report does not write.
    """
    out = Path(outdir)
    if not out.exists():
        return []
    if not out.is_dir():
        raise ReportFolderError(f"{out}: exists and is not a folder")
    names = sorted(entry.name for entry in out.iterdir())
    foreign = [name for name in names if name not in files() or not (out / name).is_file()]
    if foreign:
        more = f" (and {len(foreign) - 1} more)" if len(foreign) > 1 else ""
        raise ReportFolderError(f"{out}: holds {foreign[0]}{more}, which is not a report's; a report folder "
                                "holds one report: choose an empty or new folder")
    return names


