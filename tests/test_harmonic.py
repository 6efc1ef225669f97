"""The harmonic measure of a frozen cluster: growth's walkers, the cluster left unchanged, and sets whose
measure is known exactly (a circle, a sphere, a segment, a square)."""

import numpy as np
import pytest

import dlasweep as dla
from dlasweep import params
from dlasweep.growth.cluster import Cluster, rng_for
from dlasweep.kernels.harmonic import BLOCK, frozen_walks
from dlasweep.measures.harmonic import blocks, harmonic_measure
from dlasweep.stats.fit import Z95, _line
from dlasweep.stats.multifractal import multifractal_spectrum
from test_models import CASES

Q = np.arange(0.0, 4.01, 1.0)
FAST = ("lattice-2d", "lattice-sticky", "lattice-kill", "lattice-nojumps", "lattice-line", "lattice-moore",
        "off-2d", "off-sticky", "off-kill", "off-line", "off-step", "off-nojumps", "off-box-launch")
"""2D models whose kernels the other tests compile; the 3D ones and the rest run in the slow test."""


def frozen(points, **model):
    """A 'cluster' that was never grown: a point set and a model."""
    return Cluster(np.asarray(points), np.zeros(len(points), np.uint32), "ok", params.resolve(**model))


def check_measure(c, h, walkers):
    """What every measurement must satisfy: each walker accounted for, next to the particle it names."""
    p = c.params
    assert h.status == "ok" and h.walkers == walkers
    assert h.hits.sum() + h.substrate == walkers
    assert h.hits.shape == (c.n,) and (h.hits >= 0).all()
    on = h.touched >= 0
    assert (h.touched < c.n).all()
    line = p["seed_shape"] == "line"
    assert h.substrate == 0 or line
    x = c.points.astype(np.float64)
    own = x[h.touched[on], -1] if line else np.sqrt((x[h.touched[on]] ** 2).sum(axis=1))
    # the walker stuck within a contact of its particle (off-lattice: at distance 1; a lattice neighbour:
    # at most a diagonal; a Gaussian step ends at contact to rounding)
    reach = (1.0 if p["model"] == "offlattice" else np.sqrt(p["dim"])) + 1e-6
    assert (np.abs(h.where[on] - own) <= reach).all()
    assert h.where.min() >= 0


@pytest.mark.parametrize("name", FAST)
def test_every_model(name):
    c = dla.grow(300, seed=2, **CASES[name])
    before = c.points.copy()
    h = harmonic_measure(c, 700, seed=3)
    check_measure(c, h, 700)
    assert np.array_equal(c.points, before)
    # the walkers reach the outside, not the seed buried in the middle of the cluster
    mean, spread = h.depth
    assert 0.3 < mean <= 1.0 + 1.0 / h.radius and spread > 0
    again = harmonic_measure(c, 700, seed=3)
    assert np.array_equal(again.touched, h.touched) and np.array_equal(again.where, h.where)
    assert not np.array_equal(harmonic_measure(c, 700, seed=4).touched, h.touched)


@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(set(CASES) - set(FAST)))
def test_every_other_model(name):
    c = dla.grow(300, seed=2, **CASES[name])
    h = harmonic_measure(c, 300, seed=3)
    check_measure(c, h, 300)


@pytest.mark.parametrize("name", ["lattice-2d", "lattice-sticky", "lattice-kill", "lattice-block", "lattice-moore",
                                  "off-2d", "off-sticky", "off-kill", "off-block", "off-step", "off-box-launch"])
def test_first_walker_is_growths(name):
    """Against the seed alone, a block's first walker is growth's first, from the same Generator:
    released, moved and stuck as growth's (the same place, the same moves)."""
    grown = dla.grow(10, seed=11, **CASES[name])
    nseed = 4 if CASES[name].get("seed_shape") == "block" else 1
    seeds = grown.points[:nseed]
    touched, where, steps, status = frozen_walks(seeds, grown.params, [rng_for(11)], 1)
    assert status == 0
    first = grown.points[nseed].astype(np.float64)
    assert np.isclose(where[0], np.sqrt((first ** 2).sum()), rtol=1e-12, atol=0)
    assert steps[0] == grown.steps[nseed]
    assert touched[0] == grown.parents[nseed]


@pytest.mark.parametrize("model", ["lattice", "offlattice"])
def test_blocks_do_not_depend_on_batching(model):
    """The first k walkers of a measurement are those of a larger one, and a block walked alone is itself."""
    c = dla.grow(200, seed=1, model=model)
    whole = harmonic_measure(c, 2 * BLOCK + 50, seed=5)
    part = harmonic_measure(c, BLOCK + 10, seed=5)
    assert np.array_equal(part.touched, whole.touched[:BLOCK + 10])
    assert np.array_equal(part.where, whole.where[:BLOCK + 10])
    touched, where, steps, _ = frozen_walks(c.points, c.params, blocks(5, 2 * BLOCK + 50, BLOCK), BLOCK + 50)
    assert np.array_equal(touched, whole.touched[BLOCK:]) and np.array_equal(steps, whole.steps[BLOCK:])


def test_bad_input():
    c = dla.grow(20, seed=1)
    for walkers in (0, -3, 2.5, "10"):
        with pytest.raises(ValueError, match="walkers"):
            harmonic_measure(c, walkers, 1)
    with pytest.raises(ValueError, match="seed"):
        harmonic_measure(c, 10, -1)


def ring(radius):
    """Touching unit disks on a circle of ``radius``, a closed chain: walkers cannot get inside."""
    n = int(np.ceil(np.pi / np.arcsin(1 / (2 * radius))))
    a = 2 * np.pi * np.arange(n) / n
    return np.stack([radius * np.cos(a), radius * np.sin(a)], axis=1)


def lattice_ring(radius):
    """The sites within half a site of a circle, and those that close its diagonal gaps: a 4-connected loop."""
    r = int(radius) + 2
    xy = np.stack(np.meshgrid(np.arange(-r, r + 1), np.arange(-r, r + 1)), -1).reshape(-1, 2)
    d = np.sqrt((xy.astype(float) ** 2).sum(axis=1))
    return xy[np.abs(d - radius) <= 0.75].astype(np.int32)


def assert_flat(s, value, widest=0.15):
    """D(q) = value at every q, within each 95% interval, trusted, and each standard error below ``widest``
    (not so wide that it would hold anything)."""
    assert s.ok.all(), s.reasons
    assert (np.abs(s.D - value) <= Z95 * s.stderr).all(), (s.D, s.stderr)
    assert (s.stderr < widest).all(), s.stderr


@pytest.mark.parametrize("model", ["offlattice", "lattice"])
def test_circle_uniform(model):
    """A circle's harmonic measure is uniform: D(q) = 1 for all q, and walkers land at its radius."""
    points = ring(100.0) if model == "offlattice" else lattice_ring(100.0)
    c = frozen(points, model=model)
    h = harmonic_measure(c, 100_000, seed=1)
    check_measure(c, h, 100_000)
    assert_flat(multifractal_spectrum(h, q=Q), 1.0)
    if model == "offlattice":  # uniform: the disks, equal shares of the circle, take Poisson counts
        share = h.hits / h.walkers * len(points)
        assert share.std() < 1.2 * np.sqrt(len(points) / h.walkers)


@pytest.mark.slow
def test_sphere_uniform():
    """A sphere's harmonic measure is uniform: D(q) = 2."""
    n = 30_000
    k = np.arange(n) + 0.5  # a Fibonacci sphere, the disks less than a diameter apart
    radius = 0.85 * np.sqrt(n / (4 * np.pi))
    z = 1 - 2 * k / n
    phi = np.pi * (1 + 5 ** 0.5) * k
    rho = np.sqrt(1 - z * z)
    points = radius * np.stack([rho * np.cos(phi), rho * np.sin(phi), z], axis=1)
    c = frozen(points, model="offlattice", dim=3)
    h = harmonic_measure(c, 150_000, seed=1)
    check_measure(c, h, 150_000)
    # a radius of 40 diameters: sides of 2 to 40, 1.3 decades (the circle's 1.7), the largest bent by the
    # sphere's curvature: errors of 0.12 to 0.26 (D 2.02 to 2.06)
    assert_flat(multifractal_spectrum(h, q=Q, max_fraction=0.5), 2.0, widest=0.3)


def end_exponent(h, points, near, sizes):
    """The slope of log(measure within r of the points ``near``) on log r, and its standard error."""
    d = np.min(np.linalg.norm(points[:, None, :] - near[None], axis=2), axis=1)
    mass = np.array([h.hits[d <= r].sum() for r in sizes]) / h.walkers
    return _line(np.log(sizes), np.log(mass))


def test_segment_arcsine_and_ends():
    """A segment's harmonic measure has density 1 / (pi sqrt(L**2 - x**2)) on [-L, L]: the arcsine law,
    and near an end the measure within r grows as r**(1/2) (alpha_min = 1/2)."""
    half = 200
    points = np.stack([np.arange(-half, half + 1.0), np.zeros(2 * half + 1)], axis=1)
    c = frozen(points, model="offlattice")
    h = harmonic_measure(c, 100_000, seed=1)
    check_measure(c, h, 100_000)
    # away from the ends (where the disks' round caps differ from a thin segment's ends within a few
    # diameters), the arcsine law's distribution function against the hits' (a disk's spread over its width)
    x = np.repeat(points[:, 0], h.hits) + np.random.default_rng(0).uniform(-0.5, 0.5, h.walkers)
    edge = 0.9 * (half + 0.5)
    x = np.sort(x[np.abs(x) <= edge])
    span = np.arcsin(edge / (half + 0.5))
    law = (np.arcsin(x / (half + 0.5)) + span) / (2 * span)
    ks = np.abs(law - np.arange(1, len(x) + 1) / len(x)).max()
    assert ks < 1.63 / np.sqrt(len(x)) + 0.002, ks  # 1% Kolmogorov quantile, and the disks' rounding
    # within r of the ends the measure is the arcsine law's, 2 arccos(1 - r / L) / pi, which goes as
    # r**(1/2) for r << L (alpha = 1/2 at the ends): the hits' share, the end disks' round caps' excess
    # fading within a few tens of diameters
    d = np.abs(np.abs(points[:, 0]) - half)
    sizes = np.array([8, 16, 32, 64, 100])
    share = np.array([h.hits[d <= r].sum() for r in sizes]) / h.walkers
    law = 2 * np.arccos(1 - (sizes + 0.5) / (half + 0.5)) / np.pi
    ratio = share / law
    assert (np.diff(ratio) < 0.01).all() and (np.abs(ratio[2:] - 1) < 0.05).all(), ratio
    s = multifractal_spectrum(h, q=[1.0, 6.0, 8.0])
    assert s.ok.all(), s.reasons
    exact = np.array([1.0, 6 / 10, 8 / 14])  # D(q) = q / (2 (q - 1)) beyond q = 2, from the ends
    assert (np.abs(s.D - exact) <= Z95 * s.stderr).all(), (s.D, s.stderr)
    assert (np.abs(s.alpha[1:] - 0.5) <= Z95 * s.alpha_err[1:]).all(), (s.alpha, s.alpha_err)


def test_square_corners():
    """Outside a square the measure within r of a corner grows as r**(2/3) (the exterior angle 3 pi / 2)."""
    half = 300
    e = np.arange(-half, half + 1.0)
    sides = [np.stack([e, np.full_like(e, v)], 1) for v in (-half, half)]
    sides += [np.stack([np.full_like(e, v), e], 1) for v in (-half, half)]
    points = np.unique(np.concatenate(sides), axis=0)
    c = frozen(points, model="offlattice")
    h = harmonic_measure(c, 100_000, seed=1)
    check_measure(c, h, 100_000)
    corners = np.array([[a, b] for a in (-half, half) for b in (-half, half)], np.float64)
    # between the corner disk's excess (below 2/3, fading with r) and the far corners' pull (above
    # 2/3 once r nears the side): the local slope crosses 2/3 within this range
    slope, err = end_exponent(h, points, corners, np.geomspace(16, 128, 8))
    assert abs(slope - 2 / 3) < 0.04, (slope, err)
    s = multifractal_spectrum(h, q=[1.0, 6.0, 8.0])
    assert s.ok.all(), s.reasons
    exact = np.array([1.0, 12 / 15, 16 / 21])  # D(q) = 2 q / (3 (q - 1)) beyond q = 3, from the corners
    assert (np.abs(s.D - exact) <= Z95 * s.stderr).all(), (s.D, s.stderr)
    assert (np.abs(s.alpha[1:] - 2 / 3) <= Z95 * s.alpha_err[1:]).all(), (s.alpha, s.alpha_err)


@pytest.mark.slow
def test_dla_makarov_and_halsey():
    """A 2D off-lattice DLA cluster: D(1) = 1 (Makarov) and D(3) = D(0) / 2 (Halsey), D(0) the cluster's
    box-counting dimension, each within its 95% interval. (3e4 particles here for CI's time; the 1e5
    check by hand is in the report of issue 73.)"""
    c = dla.grow(30_000, seed=1, model="offlattice")
    h = harmonic_measure(c, 300_000, seed=1)
    check_measure(c, h, 300_000)
    s = multifractal_spectrum(h, q=[1.0, 3.0])
    assert s.ok.all(), s.reasons
    assert abs(s.D[0] - 1) <= Z95 * s.stderr[0], (s.D[0], s.stderr[0])
    d0 = dla.fit_dimension(*dla.box_counts(c.points, lattice=False))
    assert d0.ok
    assert abs(s.D[1] - d0.D / 2) <= Z95 * np.hypot(s.stderr[1], d0.stderr / 2), (s.D[1], s.stderr[1], d0.D)
    mean, spread = h.depth
    assert 0.5 < mean < 1 and 0 < spread < 0.5


def test_public():
    assert dla.harmonic_measure is harmonic_measure and dla.multifractal_spectrum is multifractal_spectrum
    assert {"harmonic_measure", "multifractal_spectrum"} <= set(dir(dla))
