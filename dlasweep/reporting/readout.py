"""What the report reads of a sweep and its summary: the report's view model.

Everything the report draws or writes that is computed from a sweep and its
summary (``stats.summary.summarise``), beyond the summary itself: the table's rows,
names of configurations, the exact reference of each, fitted lines, plot
ranges and biases. The report (``dlasweep.report``) only draws and writes
these.
"""

from __future__ import annotations

import numpy as np

from ..data.schema import config_dims, plain
from ..data.selection import with_selected_clusters
from ..params import EXACT_METHOD, PARAMETERS, SHORTCUTS, Status
from ..stats.exact import exact_reference, method_axes
from ..stats.summary import summarise, sweep_checked

REFERENCE_D = {2: 1.7100, 3: 2.50}
"""D of DLA: 2D off-lattice 1.7100(3) (Menshutin et al. 2008); 3D about 2.50."""


class Readout:
    """A sweep, its summary (``summarise``), and what the report reads of them, by configuration.

    Attributes
    ----------
    ds : xarray.Dataset
        The sweep.
    s : xarray.Dataset
        ``summarise(ds)``.
    config_dims : list of str
        ``config_dims(ds)``; ``configs`` are index tuples on them, in C order.
    counts : ndarray
        The particle counts.
    dim, lattice
        The sweep's largest dimension, and whether every cluster is on a lattice.
    reference : float or None
        The published D the plots draw (``REFERENCE_D``); None for lattice
        sweeps, which cross over to axis-aligned growth.
    methods : list of str
        ``method_axes(ds)``.
    """

    def __init__(self, ds, summary=None):
        self.ds = ds = with_selected_clusters(sweep_checked(ds))
        self.s = summarise(ds) if summary is None else summary
        self.config_dims = config_dims(ds)
        self.params = [d for d in self.config_dims if d != "size"]
        self.counts = ds["n_particles"].values
        self.status_names = list(self.s["status"].values)
        self.dim = int(ds["dim"].max()) if "dim" in ds else 2
        self.lattice = bool((ds["model"] == "lattice").all()) if "model" in ds else True
        self.configs = list(np.ndindex(*(ds.sizes[d] for d in self.config_dims)))
        # Lattice clusters cross over to axis-aligned growth: the off-lattice value is not theirs.
        self.reference = None if self.lattice else REFERENCE_D.get(self.dim)
        self.methods = method_axes(ds)
        self.n_clusters = len(self.configs) * ds.sizes["seed"]
        """Clusters grown: one per configuration and seed."""
        self.n_stored = ds.sizes.get("cluster", 0)
        """Clusters whose positions the dataset keeps."""
        self._rows = {}

    def at(self, name, config, **index):
        """Values of summary variable ``name`` at a configuration (and e.g. ``n_particles=k``)."""
        return self.s[name][{**dict(zip(self.config_dims, config)), **index}].values

    def bars(self, name, config):
        """Summary variable ``name`` at a configuration, every count, and its 95% CI as ``error_bars``."""
        mean = self.at(name, config)
        return mean, error_bars(mean, self.at(f"{name}_ci_lo", config), self.at(f"{name}_ci_hi", config))

    def value(self, name, config):
        """The value of swept parameter (or ``size``) ``name`` at a configuration, as a plain Python value."""
        return plain(self.ds[name].values[config[self.config_dims.index(name)]])

    def param(self, name, config):
        """A model parameter at a configuration: swept, fixed (a scalar coordinate), or else its default."""
        if name in self.config_dims:
            return self.value(name, config)
        return plain(self.ds[name].values) if name in self.ds.coords else PARAMETERS[name].default

    def row(self, config, k) -> dict:
        """One line of the summary table at count index ``k`` (built once).

        The configuration's values, ``n_particles``, ``seeds``, ``status``
        (``name:count`` of the statuses present), ``flagged`` (some cluster
        stopped early), every summary variable on ``n_particles`` and, at the
        largest count, D_inf.
        """
        if (config, k) not in self._rows:
            self._rows[config, k] = self._row(config, k)
        return self._rows[config, k]

    def _row(self, config, k) -> dict:
        row = {name: plain(self.ds[name].values[i]) for name, i in zip(self.config_dims, config)}
        tally = self.at("status_count", config, n_particles=k)
        row.update(n_particles=int(self.counts[k]), seeds=int(tally.sum()),
                   status=" ".join(f"{n}:{t}" for n, t in zip(self.status_names, tally) if t),
                   flagged=bool(tally.sum() > tally[Status.ok]))
        for name in (*(n for n, v in self.s.data_vars.items() if v.dims[-1:] == ("n_particles",)), "D_reason"):
            row[name] = plain(self.at(name, config, n_particles=k))
        for name in ("D_inf", "D_inf_ci_lo", "D_inf_ci_hi", "D_inf_reason"):
            row[name] = plain(self.at(name, config)) if k == len(self.counts) - 1 else ""
        return row

    def rows(self):
        """Every row: configurations in C order, each at every count."""
        return [self.row(c, k) for c in self.configs for k in range(len(self.counts))]

    def label(self, config, dims=None) -> str:
        """``name=value`` for the swept parameters and the box size of a configuration."""
        parts = []
        for name, i in zip(self.config_dims, config):
            if dims is not None and name not in dims:
                continue
            value = self.ds[name].values[i]
            if name == "size":
                if self.ds.sizes["size"] > 1 or value:
                    parts.append("unbounded" if value == 0 else f"L={value}")
            else:
                parts.append(f"{name}={plain(value)}")
        return ", ".join(parts) or "all clusters"

    def cluster_of(self, config, seed):
        """Position on ``cluster`` of a configuration's cluster, or None when it is not stored."""
        index = int(self.at("cluster_index", config, seed=seed))
        return None if index < 0 else index

    def status_of(self, config, k, seed) -> str:
        """The growth status of one cluster at count index ``k``."""
        where = {**dict(zip(self.config_dims, config)), "n_particles": k, "seed": seed}
        return self.status_names[int(self.ds["status"][where])]

    def exact(self, config):
        """The configuration with every method axis at its exact value (``exact_reference``), or None."""
        return exact_reference(self.ds, config)

    def shortcuts(self, config) -> list:
        """The method axes on which a configuration departs from the exact method."""
        return [m for m in self.methods if self.value(m, config) != EXACT_METHOD[m]]

    def family(self, config) -> str:
        """The shortcuts a configuration takes, e.g. ``kill circle + single steps``; ``exact`` for none."""
        return " + ".join(SHORTCUTS[m] for m in self.shortcuts(config)) or "exact"

    def variant(self, config) -> str:
        """The non-exact method values of a configuration, e.g. ``kill_factor=1.2, step=2.0``."""
        shown = self.shortcuts(config)
        return self.label(config, shown) if shown else "exact"

    def pareto_front(self, configs, k) -> list:
        """The rows of ``configs`` at count index ``k`` on the Pareto front (``pareto``), cheapest first."""
        front = [row for row in (self.row(c, k) for c in configs) if row["pareto"]]
        return sorted(front, key=lambda r: r["seconds_per_particle"])

    def scenes(self) -> list:
        """One configuration per scene (values of the swept parameters that are not methods, and ``size``).

        Each at the exact method where the sweep has it, else the scene's first configuration.
        """
        seen = {}
        for config in self.configs:
            scene = tuple(i for d, i in zip(self.config_dims, config) if d not in self.methods)
            seen.setdefault(scene, self.exact(config) or config)
        return list(seen.values())

    def scene_label(self, config) -> str:
        """``name=value`` of the scene parameters that take several values; empty for a sweep of one scene."""
        shown = [d for d in self.config_dims if d not in self.methods and self.ds.sizes[d] > 1]
        return self.label(config, shown) if shown else ""

    def differences(self, k) -> list:
        """D between scenes one value apart on one swept parameter (not a method), at count index ``k``.

        Returns ``(config, other, D(other) - D(config), half-width)`` for
        every configuration and its neighbour along each such axis; the
        half-width is that of the difference's 95% CI (both CIs in
        quadrature, NaN without them).
        """
        pairs = []
        for axis in (d for d in self.config_dims if d not in self.methods and self.ds.sizes[d] > 1):
            a = self.config_dims.index(axis)
            for config in self.configs:
                if config[a] + 1 < self.ds.sizes[axis]:
                    other = (*config[:a], config[a] + 1, *config[a + 1:])
                    one, two = self.row(config, k), self.row(other, k)
                    pairs.append((config, other, two["D"] - one["D"],
                                  np.hypot(ci_half_width(one, "D"), ci_half_width(two, "D"))))
        return pairs

    def one_factor(self, axis, base):
        """The configurations that differ from ``base`` only along ``axis``: (at the exact value, the others)."""
        a = self.config_dims.index(axis)
        line = [c for c in self.configs if all(c[i] == base[i] for i in range(len(c)) if i != a)]
        exact = [c for c in line if self.value(axis, c) == EXACT_METHOD.get(axis)]
        return exact, [c for c in line if c not in exact]


def error_bars(mean, lo, hi):
    """The lengths below and above ``mean`` of its interval ``[lo, hi]``, 0 where there is none (a ``yerr``)."""
    return [np.nan_to_num(mean - lo), np.nan_to_num(hi - mean)]


def fitted_line(x, y, slope):
    """The line of ``slope`` in log-log through the points ``(x, y)`` (least squares, slope fixed), at ``x``."""
    anchor = np.exp(np.mean(np.log(y) - slope * np.log(x)))
    return anchor * x ** slope


def visible_scales(scales, box_count):
    """Box sides worth drawing: up to twice the first side at which every count is 1 (beyond, nothing changes)."""
    full = box_count.max(axis=tuple(range(box_count.ndim - 1))) <= 1
    return scales <= 2 * scales[min(np.argmax(full), len(scales) - 1)]


def fitted_scales(summary):
    """The midpoints of box sides within the largest box-counting fit window at the largest count."""
    mid = summary["scale_mid"].values
    fitted = summary["D_box_range_hi"].isel(n_particles=-1).values
    # Beyond the fitted windows the counts saturate and the slope is noise.
    top = np.nanmax(fitted) if np.isfinite(fitted).any() else mid[-1]
    return (mid >= 1.5) & (mid <= top)


def ci_half_width(row, name) -> float:
    """Half the width of the 95% CI of ``name`` in a row."""
    return (row[f"{name}_ci_hi"] - row[f"{name}_ci_lo"]) / 2


def bias(row, ref, name) -> float:
    """``name`` of a row minus that of the reference row, in units of their combined 95% CI half-widths."""
    return (row[name] - ref[name]) / np.hypot(ci_half_width(ref, name), ci_half_width(row, name))


def resolved(value, half) -> bool:
    """Whether a difference is resolved: its 95% CI excludes zero."""
    return abs(value) > half
