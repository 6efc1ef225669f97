"""Each variant against the exact method: the method axes, each configuration's exact reference,
its departure from it at equal N, and the Pareto front of cost against accuracy.

The exact method is the parameter table's (``params.EXACT_METHOD``); a sweep
compares with it along its method axes, the other parameters equal.
"""

from __future__ import annotations

import numpy as np

from ..data.schema import config_dims, plain
from ..params import EXACT_METHOD

COMPARED = {"D": False, "rg_mean": True, "rg_over_rmax": False}
"""Quantities compared with the exact method at equal N: name -> relative (ratio - 1) or difference."""



def method_axes(ds) -> list:
    """The swept parameters that switch an approximation on or off (``EXACT_METHOD``'s, with several values)."""
    return [name for name in EXACT_METHOD if name in config_dims(ds) and ds.sizes[name] > 1]


def exact_reference(ds, config):
    """The configuration (indices on ``config_dims``) with every method axis at its exact value, or None."""
    dims = config_dims(ds)
    reference = list(config)
    for name in method_axes(ds):
        exact = [i for i, v in enumerate(ds[name].values) if plain(v) == EXACT_METHOD[name]]
        if not exact:
            return None
        reference[dims.index(name)] = exact[0]
    return tuple(reference)


def against_exact(ds, out):
    """Fill ``out`` (``summary.SUMMARY``'s arrays on a sweep ``ds``'s configurations) with each configuration's
    departure from the exact method at equal N, its 95% CI half-width, and the Pareto front."""
    if not method_axes(ds):
        return
    for config in np.ndindex(*(ds.sizes[d] for d in config_dims(ds))):
        ref = exact_reference(ds, config)
        if ref is None:
            continue
        if ref == config:
            for name in COMPARED:
                out[f"{name}_vs_exact"][config] = out[f"{name}_vs_exact_half_width"][config] = 0.0
            continue
        for name, relative in COMPARED.items():
            stem = "rg" if name == "rg_mean" else name
            value, base = out[name][config], out[name][ref]
            half, base_half = ((out[f"{stem}_ci_hi"][c] - out[f"{stem}_ci_lo"][c]) / 2 for c in (config, ref))
            if relative:
                out[f"{name}_vs_exact"][config] = value / base - 1
                out[f"{name}_vs_exact_half_width"][config] = value / base * np.hypot(half / value, base_half / base)
            else:
                out[f"{name}_vs_exact"][config] = value - base
                out[f"{name}_vs_exact_half_width"][config] = np.hypot(half, base_half)
    _pareto(out, ds.sizes["n_particles"])


def _pareto(out, n_counts):
    """Mark, at each count, the configurations no other beats on both cost and accuracy.

    Accuracy is the bound |Rg/Rg(exact) - 1| + its CI half-width (Rg at equal
    N separates the methods more sharply than D); the exact method's bound is 0.
    """
    cost = out["seconds_per_particle"].reshape(-1, n_counts)
    bound = (np.abs(out["rg_mean_vs_exact"]) + out["rg_mean_vs_exact_half_width"]).reshape(-1, n_counts)
    front = np.zeros_like(cost)
    for k in range(n_counts):
        c, b = cost[:, k], bound[:, k]
        for i in np.flatnonzero(np.isfinite(c) & np.isfinite(b)):
            beaten = (c <= c[i]) & (b <= b[i]) & ((c < c[i]) | (b < b[i]))
            front[i, k] = not beaten.any()
    out["pareto"][...] = front.reshape(out["pareto"].shape)
