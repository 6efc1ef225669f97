"""The benchmark's chart: kernel time against N, log-log, one line per model (``dlasweep bench``'s ``bench.png``).

Drawn in the report's style (``figures.new_figure``); reads what
``benchmark.run_bench`` recorded and computes nothing.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..data.schema import plain
from ..reporting.figures import colour_of, new_figure, save_figure
from .targets import SCALING, exponent_attribute, power_label


def plot_bench(ds, outdir) -> Path:
    """Draw kernel time against N, log-log, one line per model, to ``bench.png``.

    Parameters
    ----------
    ds : xarray.Dataset
        As from ``dlasweep.bench.benchmark.run_bench``: dimension ``run``, coordinates
        ``model``, ``method`` (``exact`` or ``naive``) and ``n``, variable
        ``seconds``, attributes ``targets.exponent_attribute(<model>)``.
    outdir : str or Path
        Created when missing.

    Returns
    -------
    Path
        The PNG written.
    """
    out = Path(outdir)
    out.mkdir(parents=True, exist_ok=True)
    model = np.array([str(plain(v)) for v in ds["model"].values])
    method = np.array([str(plain(v)) for v in ds["method"].values])
    n, seconds = ds["n"].values.astype(float), ds["seconds"].values.astype(float)
    fig, (ax,) = new_figure(1, 6.5, 4.5)
    lo, hi = SCALING
    for c, name in enumerate(dict.fromkeys(model)):
        exponent = ds.attrs.get(exponent_attribute(name))
        fitted = ("" if exponent is None else
                  f", time $\\propto N^{{{exponent:.2f}}}$ over N in [{power_label(lo)}, {power_label(hi)}]")
        for kind, style, label in (
            ("exact", dict(marker="o", ls="-"), name + fitted),
            ("naive", dict(marker="x", ls=":", ms=8), f"{name}, naive walk (single steps, kill circle)"),
        ):
            pick = (model == name) & (method == kind)
            if pick.any():
                order = np.argsort(n[pick])
                ax.loglog(n[pick][order], seconds[pick][order], color=colour_of(c), label=label, **style)
    ax.set_xlabel("particles N")
    ax.set_ylabel("wall time to grow (s), one core")
    ax.set_title("Kernel time against cluster size")
    ax.legend(fontsize=7)
    path = out / "bench.png"
    save_figure(fig, path)
    return path
