"""Geometric invariants of every model variant at sizes where every walk path runs.

At 2e4 particles the far jumps (Brownian circles and squares, the pyramid's
bound, returns to the launch circle or line) all happen, also in the deep
fjords of a substrate deposit, where a jump bounded by the cluster alone would
cross the substrate. Each cluster is checked against the model's geometry:

- no particle below a substrate or outside its period, none outside a box;
- a particle with parent -1 is a seed particle or lies on the substrate;
- every other particle touches its parent (across a substrate's periodic
  sides, by the shortest image);
- lattice sites are distinct, off-lattice disks (spheres) do not overlap.

The substrate variants come in every combination of dimension, neighbours,
launch and kill rule that the kernels branch on; the rest are the variants of
``test_models.CASES`` grown larger, and drift's (``DRIFTS``, ``test_drift``).
"""

import numpy as np
import pytest

import dlasweep as dla
from dlasweep.kernels.lattice.exits import unit_moves
from naive import assert_offlattice_contacts, seed_count
from test_models import CASES

N = 20_000

SUBSTRATES = {
    "lattice-line": dict(seed_shape="line", size=256),
    "lattice-line-moore": dict(seed_shape="line", size=256, neighbours=8),
    "lattice-line-launch-box": dict(seed_shape="line", size=256, launch="box"),
    "lattice-line-kill": dict(seed_shape="line", size=256, kill_factor=1.5),
    "lattice-line-sticky": dict(seed_shape="line", size=256, stickiness=0.3),
    "lattice-line-far": dict(seed_shape="line", size=256, launch_factor=2.0, launch_margin=5.0),
    "lattice-plane": dict(dim=3, seed_shape="line", size=64),
    "lattice-plane-moore": dict(dim=3, seed_shape="line", size=64, neighbours=26),
    "lattice-plane-launch-box": dict(dim=3, seed_shape="line", size=64, launch="box"),
    "lattice-plane-kill": dict(dim=3, seed_shape="line", size=64, kill_factor=1.5),
    "off-line": dict(model="offlattice", seed_shape="line", size=256),
    "off-line-launch-box": dict(model="offlattice", seed_shape="line", size=256, launch="box"),
    "off-line-kill": dict(model="offlattice", seed_shape="line", size=256, kill_factor=1.5),
    "off-line-sticky": dict(model="offlattice", seed_shape="line", size=256, stickiness=0.3),
    "off-plane": dict(model="offlattice", dim=3, seed_shape="line", size=64),
    "off-plane-launch-box": dict(model="offlattice", dim=3, seed_shape="line", size=64, launch="box"),
    "off-plane-kill": dict(model="offlattice", dim=3, seed_shape="line", size=64, kill_factor=1.5),
    "lattice-line-drift": dict(seed_shape="line", size=256, drift=0.05, drift_angle=40.0),
    "lattice-plane-drift-sideways": dict(dim=3, seed_shape="line", size=64, drift=0.1, drift_angle=90.0,
                                         drift_azimuth=30.0),
    "off-line-drift": dict(model="offlattice", seed_shape="line", size=256, drift=0.05, drift_angle=20.0),
    "off-plane-drift-kill": dict(model="offlattice", dim=3, seed_shape="line", size=64, drift=0.2, kill_factor=1.5),
}
DRIFTS = {
    "lattice-drift": dict(drift=0.02, kill_factor=2.0),
    "lattice-drift-moore": dict(drift=0.1, drift_angle=45.0, neighbours=8, kill_factor=2.0),
    "lattice-drift-box": dict(drift=0.05, drift_angle=70.0, size=400),
    "lattice-3d-drift": dict(dim=3, drift=0.05, drift_angle=60.0, drift_azimuth=200.0, kill_factor=2.0),
    "off-drift": dict(model="offlattice", drift=0.02, kill_factor=2.0),
    "off-drift-sticky": dict(model="offlattice", drift=0.05, stickiness=0.3, kill_factor=2.0),
    "off-drift-step": dict(model="offlattice", drift=0.05, step=0.3, kill_factor=2.0),
    "off-3d-drift": dict(model="offlattice", dim=3, drift=0.1, drift_angle=150.0, kill_factor=2.0),
}
"""Drift (``test_drift``) at a point seed, where it needs a kill circle or a box, and on substrates."""
VARIANTS = {**{f"{name}-{N}": kw for name, kw in CASES.items() if kw.get("seed_shape") != "line"},
            **SUBSTRATES, **DRIFTS}


@pytest.fixture(scope="module", params=sorted(VARIANTS))
def grown(request):
    return request.param, dla.grow(N, seed=20240601, **VARIANTS[request.param])


def _offsets(points, parents, params):
    """Each particle minus its parent, the shortest periodic image across a substrate's sides."""
    d = (points - points[parents]).astype(np.float64)
    if params["seed_shape"] == "line":
        d[:, :-1] -= params["size"] * np.round(d[:, :-1] / params["size"])
    return d


def test_particles_stay_above_the_substrate_and_in_the_box(grown):
    name, c = grown
    p, size = c.points.astype(np.float64), c.params["size"]
    if c.params["seed_shape"] == "line":
        assert p[:, -1].min() >= 0, f"{name}: {(p[:, -1] < 0).sum()} particles below the substrate"
        assert ((p[:, :-1] >= 0) & (p[:, :-1] < size)).all(), f"{name}: a particle outside the period"
    elif size > 0:
        lo, hi = (-(size // 2), size - 1 - size // 2) if c.params["model"] == "lattice" else (-size / 2, size / 2)
        assert ((p >= lo) & (p <= hi)).all(), f"{name}: a particle outside the box"


def test_roots_are_seeds_or_rest_on_the_substrate(grown):
    name, c = grown
    on_substrate = (c.params["seed_shape"] == "line") & (np.abs(c.points[:, -1]) < 1e-9)
    seed = np.arange(c.n) < seed_count(c.params)
    roots = np.flatnonzero(c.parents == -1)
    bad = roots[~(seed[roots] | on_substrate[roots])]
    assert bad.size == 0, f"{name}: particles {bad[:5]} have no parent, at {c.points[bad[:5]].tolist()}"
    assert (c.parents[~seed & ~on_substrate] >= 0).all()


def test_every_particle_touches_its_parent(grown):
    name, c = grown
    child = np.flatnonzero(c.parents >= 0)
    d = _offsets(c.points, c.parents, c.params)[child]
    if c.params["model"] == "lattice":
        dim = c.params["dim"]
        moves = unit_moves(dim, c.params["neighbours"] != 2 * dim)[:, :dim]
        touching = (np.abs(d[:, None, :] - moves[None]).max(axis=2) == 0).any(axis=1)
        assert touching.all(), f"{name}: particles {child[~touching][:5]} do not touch their parents"
    else:
        gap = np.abs(np.linalg.norm(d, axis=1) - 1.0)
        assert gap.max() < 1e-9, f"{name}: particle {child[np.argmax(gap)]} is {gap.max():.3g} off its parent"


def test_sites_are_distinct_and_disks_do_not_overlap(grown):
    name, c = grown
    if c.params["model"] == "lattice":
        assert len(np.unique(c.points, axis=0)) == c.n, f"{name}: a site holds two particles"
    else:
        assert_offlattice_contacts(c.points, c.params, exact=False)


def test_clusters_reach_the_size_where_far_jumps_happen(grown):
    """Every variant that is not stopped by its box or its walkers grows all N particles, so that the
    checks above run at the size they are meant for."""
    name, c = grown
    if c.params.get("walkers", 1) > 1 or c.status == "boundary":
        return
    assert c.n == N, f"{name}: grew {c.n} ({c.status})"
