"""Fractal dimension of every model from an ensemble, by mass-radius.

    .venv/bin/python workflows/dimensions.py [--n 20000] [--seeds 8] [--only NAME]

For each model: D from N ~ Rg**D over each cluster's growth history
(``fit.fit_mass_radius``), then mean, standard error and a bootstrap 95%
interval over seeds (``fit.ensemble``). Seeds are 0..seeds-1 of ``dla.grow``.
"""

import argparse
import time

import numpy as np

import dlasweep as dla
from dlasweep.fit import ensemble, fit_mass_radius

MODELS = {
    "lattice-2d": dict(),
    "lattice-2d-moore": dict(neighbours=8),
    "lattice-2d-sticky0.1": dict(stickiness=0.1),
    "lattice-3d": dict(dim=3),
    "offlattice-2d": dict(model="offlattice"),
    "offlattice-3d": dict(model="offlattice", dim=3),
}


def main():
    args = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    args.add_argument("--n", type=int, default=20_000)
    args.add_argument("--seeds", type=int, default=8)
    args.add_argument("--only", choices=sorted(MODELS))
    opts = args.parse_args()
    for name, params in MODELS.items():
        if opts.only and name != opts.only:
            continue
        start = time.perf_counter()
        values = []
        for seed in range(opts.seeds):
            c = dla.grow(opts.n, seed, **params)
            fit = fit_mass_radius(np.arange(1, c.n + 1), dla.radius_of_gyration(c.points))
            values.append(fit.D if fit.ok else np.nan)
        e = ensemble(np.array(values))
        print(f"{name:22s} N={opts.n} D = {e.mean:.3f} ± {e.stderr:.3f} (sd {e.std:.3f}, 95% CI "
              f"[{e.ci_lo:.3f}, {e.ci_hi:.3f}], {e.n} of {opts.seeds} fits ok) {time.perf_counter() - start:.0f} s",
              flush=True)


if __name__ == "__main__":
    main()
