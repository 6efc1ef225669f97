# %% [markdown]
# # A lesson on diffusion-limited aggregation (DLA)
#
# Run it from top to bottom, as a script or as a notebook:
#
#     .venv/bin/python workflows/teach.py -o results/teach      # -n 50000 --seed 1
#     jupyter lab workflows/teach.ipynb                         # the same lesson, cell by cell
#
# It grows two clusters in 2D, one on a square lattice and one of disks in
# continuous space, draws them, measures the fractal dimension D of each in
# two ways, and compares them. It writes into the output folder
#
#     lattice.png, offlattice.png   the two clusters, coloured by attachment order
#     dimension.png                 N against Rg and the box counts, log-log, both clusters
#
# and prints what it found with a short explanation. About a minute on a
# laptop, most of it the first compilation of the simulation kernels.
#
# This file is the lesson's one text: `workflows/teach.ipynb` is made from it
# by jupytext (`.venv/bin/jupytext --to ipynb workflows/teach.py`), without
# outputs, and `tests/test_teach.py` checks that the two agree and runs the
# notebook.

# %% tags=["parameters"]
# Particles in each cluster, the random seed, the folder for the pictures:
# change them here in a notebook, or with -n, --seed and -o on the command line.
n, seed, output = 50_000, 1, "results/teach"

# %%
import argparse
import sys
import textwrap
import time
from pathlib import Path

import numpy as np

import dlasweep as dla
from dlasweep.reporting.pictures import draw_cluster

MODELS = {"lattice": "square lattice", "offlattice": "disks, off the lattice"}

D_2D = 1.708
"""D of 2D off-lattice DLA from 114 clusters up to 300 000 particles (`dlasweep init dimension`)."""


def checked(n, seed, output) -> Path:
    """The output folder, created, once ``n`` and ``seed`` are found fit for the lesson; ValueError naming
    what is not."""
    if not 2_000 <= n <= 1_000_000:
        raise ValueError(f"-n: {n} is not in [2000, 1000000] (fewer leave no decade to fit)")
    if seed < 0:
        raise ValueError(f"--seed: {seed} is negative")
    output = Path(output)
    if output.exists() and not output.is_dir():
        raise ValueError(f"-o {output}: exists and is not a folder")
    output.mkdir(parents=True, exist_ok=True)
    return output


class _Parser(argparse.ArgumentParser):
    def error(self, message):
        self.exit(2, f"teach.py: {message}\n")  # one line, naming what was wrong


def command_line(argv, n, seed, output):
    """``n``, ``seed`` and ``output`` from the command line (the cell above gives the defaults); exit 2 on bad input."""
    parser = _Parser(description="Grow, look at, and measure two DLA clusters.")
    parser.add_argument("-o", "--output", type=Path, default=Path(output), help="folder for the pictures")
    parser.add_argument("-n", type=int, default=n, help=f"particles in each cluster (default {n})")
    parser.add_argument("--seed", type=int, default=seed, help=f"random seed (default {seed})")
    args = parser.parse_args(argv)
    try:
        return args.n, args.seed, checked(args.n, args.seed, args.output)
    except ValueError as err:
        parser.error(str(err))


def plot_dimensions(results, path):
    """N against Rg and box counts against box side, log-log, with each fitted slope over its window."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(10, 4.2), layout="constrained")
    mass_ax, box_ax = fig.subplots(1, 2)
    for colour, (model, result) in zip(("C0", "C1"), results.items()):
        rg, mass, scales, counts, box = (result[k] for k in ("rg", "mass", "scales", "counts", "box"))
        n = np.arange(1, len(rg) + 1)
        shown = np.unique(np.geomspace(1, len(rg), 300).astype(int)) - 1  # evenly spaced on the log axis
        mass_ax.loglog(rg[shown], n[shown], color=colour, label=f"{MODELS[model]}: D = {mass.D:.3f}")
        window = (n >= mass.range_lo) & (n <= mass.range_hi)
        draw_slope(mass_ax, rg[window], n[window], mass.D)
        box_ax.loglog(scales, counts, "o", color=colour, markersize=4, label=f"{MODELS[model]}: D = {box.D:.3f}")
        window = (scales >= box.range_lo) & (scales <= box.range_hi)
        draw_slope(box_ax, scales[window], counts[window], -box.D)
    mass_ax.set(xlabel="radius of gyration Rg", ylabel="particles N",
                title="mass-radius: N ~ Rg^D (dashed: the fit)")
    box_ax.set(xlabel="box side s", ylabel="boxes holding particles N(s)",
               title="box counting: N(s) ~ s^-D (dashed: the fit)")
    for ax in (mass_ax, box_ax):
        ax.legend(fontsize=8)
    fig.savefig(path, dpi=110)
    return path


def draw_slope(ax, x, y, slope):
    """A dashed line of the fitted slope through the middle of the points it was fitted to."""
    if len(x) == 0:
        return
    shift = np.mean(np.log(y) - slope * np.log(x))
    ends = np.array([x.min(), x.max()])
    ax.loglog(ends, np.exp(shift) * ends**slope, "--", color="k", linewidth=1)


if __name__ == "__main__" and "ipykernel" not in sys.modules:  # a script: the command line decides
    n, seed, output = command_line(sys.argv[1:], n, seed, output)
else:
    output = checked(n, seed, output)

# %% [markdown]
# ## 1. Grow
#
# Walkers are released one at a time far from the cluster, wander at random,
# and stick where they first touch it. Tips reach out and catch the walkers
# before they can enter the fjords between them, so the cluster branches
# instead of filling in.

# %%
clusters = {}
for model in MODELS:
    start = time.perf_counter()
    clusters[model] = dla.grow(n, seed=seed, model=model)
    print(f"grew the {model} cluster: {clusters[model].n} particles in {time.perf_counter() - start:.1f} s")

# %% [markdown]
# ## 2. Look
#
# Colour runs from purple (the first particles) to yellow (the last): the
# outer tips are young, the inside stopped growing long ago. In a notebook a
# cluster shows as its picture; the files are drawn at a resolution that fits
# the cluster.

# %%
for model, cluster in clusters.items():
    print(f"drew {draw_cluster(cluster.points, cluster.params, output / f'{model}.png', seed=seed)}")
clusters["lattice"]

# %%
clusters["offlattice"]

# %% [markdown]
# ## 3. Measure D, twice
#
# *Mass-radius*: the radius of gyration Rg of the first N particles, for
# every N. A fractal of dimension D holds N ~ Rg**D particles, so D is the
# slope of log N against log Rg (2 for a filled disk, 1 for a line).
#
# *Box counting*: cover the cluster with boxes of side s and count the boxes
# that hold a particle: N(s) ~ s**-D.
#
# Each fit chooses the widest range over which the slope stays constant and
# gives a 95% confidence interval for D.

# %%
results = {}
for model, cluster in clusters.items():
    rg = dla.radius_of_gyration(cluster.points)
    mass = dla.fit_mass_radius(rg)
    scales, counts = dla.box_counts(cluster.points, lattice=model == "lattice")
    box = dla.fit_dimension(scales, counts)
    results[model] = dict(rg=rg, mass=mass, scales=scales, counts=counts, box=box)
    print(f"{MODELS[model]:>22}: mass-radius D = {mass.D:.3f}, 95% CI [{mass.ci_lo:.3f}, {mass.ci_hi:.3f}] "
          f"over N = {mass.range_lo:.0f} to {mass.range_hi:.0f}" + ("" if mass.ok else f" ({mass.reason})"))
    print(f"{'':>22}  box counting D = {box.D:.3f}, 95% CI [{box.ci_lo:.3f}, {box.ci_hi:.3f}] "
          f"over boxes of {box.range_lo:.0f} to {box.range_hi:.0f}" + ("" if box.ok else f" ({box.reason})"))

# %% [markdown]
# ## 4. Plot both measurements
#
# On log-log axes, where a power law is a straight line.

# %%
print(f"drew {plot_dimensions(results, output / 'dimension.png')}")

# %% [markdown]
# ## 5. Compare lattice and off-lattice

# %%
lattice, disks = results["lattice"]["mass"], results["offlattice"]["mass"]
if lattice.ci_lo <= disks.ci_hi and disks.ci_lo <= lattice.ci_hi:
    verdict = ("agree within their 95% intervals, as universality says: D does not depend on the "
               "small-scale details of the model.")
else:
    verdict = ("differ by more than their 95% intervals. Universality says D does not depend on the "
               "small-scale details of the model: grow larger clusters, or more of them.")
print("\nWhat this shows")
for paragraph in (
    f"Both clusters are fractals: D is well below 2 (near {D_2D}, the value from many large clusters), "
    "so the larger a cluster grows, the emptier it is on average: its density falls as Rg**(D - 2).",
    f"The mass-radius dimensions of the lattice and of the disks {verdict} The shape does depend on "
    "them: very large lattice clusters grow arms along the lattice axes, a cross you can begin to see "
    "in lattice.png.",
    "Box counting on one finite cluster reads low: its smallest boxes see the particles, its largest "
    "the cluster's edge. The mass-radius fit uses the whole growth history and is the better estimate.",
    "One cluster's interval is that of its own growth curve; a precise D averages many clusters: "
    "`dlasweep init dimension && dlasweep sweep dimension.toml`.",
):
    print(textwrap.fill(paragraph, 78, initial_indent="  ", subsequent_indent="  ", break_on_hyphens=False))
