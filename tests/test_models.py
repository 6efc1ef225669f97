"""One invariant suite over every model and variant of ``dla.grow``."""

import importlib
import os
import subprocess
import sys
import threading
import time

import numpy as np
import pytest

import dlasweep as dla
import naive
from dlasweep.params import DEFAULTS, resolve

N = 600
CASES = {
    "lattice-2d": dict(),
    "lattice-3d": dict(dim=3),
    "lattice-moore": dict(neighbours=8),
    "lattice-3d-moore": dict(dim=3, neighbours=26),
    "lattice-sticky": dict(stickiness=0.2),
    "lattice-block": dict(seed_shape="block"),
    "lattice-line": dict(seed_shape="line", size=48),
    "lattice-3d-plane": dict(dim=3, seed_shape="line", size=24),
    "lattice-box": dict(size=128),
    "lattice-box-launch": dict(size=128, launch="box"),
    "lattice-kill": dict(kill_factor=1.5),
    "lattice-nojumps": dict(jumps=False),
    "lattice-walkers": dict(size=48, walkers=400),
    "lattice-launch-far": dict(launch_factor=2.0, launch_margin=5.0),
    "off-2d": dict(model="offlattice"),
    "off-3d": dict(model="offlattice", dim=3),
    "off-sticky": dict(model="offlattice", stickiness=0.2),
    "off-block": dict(model="offlattice", seed_shape="block"),
    "off-line": dict(model="offlattice", seed_shape="line", size=48),
    "off-3d-plane": dict(model="offlattice", dim=3, seed_shape="line", size=24),
    "off-box": dict(model="offlattice", size=128),
    "off-box-launch": dict(model="offlattice", size=128, launch="box"),
    "off-kill": dict(model="offlattice", kill_factor=1.5),
    "off-nojumps": dict(model="offlattice", jumps=False),
    "off-step": dict(model="offlattice", step=0.3),
    "off-walkers": dict(model="offlattice", size=48, walkers=400),
}
STEPPED = {"off-step"}  # fixed Gaussian steps: contact is approximate by design


def check_invariants(c):
    assert c.points.shape == (c.n, c.params["dim"])
    assert c.steps.shape == (c.n,) and (c.steps >= 0).all()
    # particles beyond the seed were carried there by walks, and the walks are counted
    assert c.n <= naive.seed_count(c.params) or c.steps.sum() > 0
    if c.params["model"] == "lattice":
        assert c.points.dtype.kind == "i"
        naive.assert_lattice_connected(c.points, c.params)
    else:
        assert c.points.dtype.kind == "f"
        naive.assert_offlattice_contacts(c.points, c.params, exact=c.params["step"] == 0)


@pytest.fixture(scope="module", params=sorted(CASES))
def grown(request):
    kw = CASES[request.param]
    return request.param, kw, dla.grow(N, seed=11, **kw)


def test_invariants(grown):
    _, _, c = grown
    assert c.status in ("ok", "boundary", "exhausted")
    assert c.n > 20
    check_invariants(c)


def test_prefix_property(grown):
    _, kw, c = grown
    short = dla.grow(c.n // 2, seed=11, **kw)
    np.testing.assert_array_equal(short.points, c.points[: c.n // 2])
    np.testing.assert_array_equal(short.steps, c.steps[: c.n // 2])


def test_same_seed_same_cluster_other_seed_differs(grown):
    _, kw, c = grown
    again = dla.grow(N, seed=11, **kw)
    np.testing.assert_array_equal(again.points, c.points)
    other = dla.grow(min(N, 200), seed=12, **kw)
    assert not np.array_equal(other.points, c.points[: other.n])


def test_params_record_every_default(grown):
    _, kw, c = grown
    assert set(c.params) == set(DEFAULTS)
    for key, value in kw.items():
        assert c.params[key] == value


@pytest.mark.parametrize("model", ["lattice", "offlattice"])
def test_statuses_where_growth_cannot_go_on(model):
    boxed = dla.grow(100_000, seed=1, model=model, size=40)
    assert boxed.status == "boundary" and 10 < boxed.n < 100_000
    budget = dla.grow(100_000, seed=1, model=model, max_steps=2_000)
    assert budget.status == "step_limit" and budget.n < 100_000
    few = dla.grow(100_000, seed=1, model=model, size=40, walkers=50)
    assert few.status == "exhausted" and few.n <= 51


@pytest.mark.parametrize("model", ["lattice", "offlattice"])
def test_stickiness_makes_denser_clusters(model):
    """Low stickiness lets walkers penetrate: smaller radius at equal mass."""

    def rg(c):
        x = c.points - c.points.mean(0)
        return np.sqrt((x**2).sum(1).mean())

    sticky = [rg(dla.grow(1500, seed=s, model=model)) for s in range(3)]
    slippery = [rg(dla.grow(1500, seed=s, model=model, stickiness=0.05)) for s in range(3)]
    # seed-to-seed spread of Rg at N=1500 is ~5%; the effect is ~20%
    assert max(slippery) < min(sticky)


@pytest.mark.parametrize(
    "bad, name",
    [
        (dict(stickiness=0.0), "stickiness"),
        (dict(stickiness=1.5), "stickiness"),
        (dict(dim=4), "dim"),
        (dict(model="hexagonal"), "model"),
        (dict(neighbours=5), "neighbours"),
        (dict(kill_factor=0.5), "kill_factor"),
        (dict(kill_factor=1.0), "kill_factor"),
        (dict(kill_factor=2.0, size=64, launch="box"), "kill_factor"),
        (dict(launch="box"), "launch"),
        (dict(step=0.5), "step"),
        (dict(walkers=10), "walkers"),
        (dict(seed_shape="line"), "seed_shape"),
        (dict(colour="red"), "colour"),
        (dict(jumps="yes"), "jumps"),
    ],
)
def test_invalid_parameters_name_themselves(bad, name):
    with pytest.raises(ValueError, match=name):
        dla.grow(10, **bad)


@pytest.mark.parametrize("n", [0, -3, 2.5, True])
def test_invalid_count(n):
    with pytest.raises(ValueError, match="n"):
        dla.grow(n)


@pytest.mark.parametrize("checkpoints, message", [
    ([10.5], "whole counts"), ([[10, 20]], "whole counts"), (["10"], "whole counts"), ([True], "whole counts"),
    ([float("nan")], "whole counts"), ([0], r"in \[1, 30\]"), ([31], r"in \[1, 30\]"),
])
def test_invalid_checkpoints_are_refused_before_growing(checkpoints, message):
    with pytest.raises(ValueError, match=f"checkpoints: .*{message}"):
        dla.grow(30, checkpoints=checkpoints)


def test_whole_counts_written_as_floats_are_checkpoints():
    assert list(dla.grow(30, checkpoints=[1e1, 20.0, 30]).checkpoints) == [10, 20, 30]


def test_shortcuts_agree_where_they_should_and_depart_where_they_should():
    """Final Rg of 16 off-lattice clusters of 1000, each variant against the exact method.

    Seed-to-seed spread of Rg here is 3.4%, so a difference of two 16-seed
    means has a standard error of about 1.2%. A kill circle at 3x the launch
    radius agrees within 3 standard errors; at 1.2x it loses the walkers
    that would wrap around to the far side, which favours the tips (measured
    +4.0%, asserted > +1%); Gaussian steps of 2 diameters tunnel into the
    cluster and compact it (measured -26%, asserted < -15%).
    """

    def mean_rg(**variant):
        return np.mean([dla.radius_of_gyration(dla.grow(1000, seed=100 + s, model="offlattice", **variant).points)[-1]
                        for s in range(16)])

    exact = mean_rg()
    assert abs(mean_rg(kill_factor=3.0) / exact - 1) < 0.036
    assert mean_rg(kill_factor=1.2) / exact - 1 > 0.01
    assert mean_rg(step=2.0) / exact - 1 < -0.15


@pytest.mark.parametrize("model", ["lattice", "offlattice"])
def test_a_watched_growth_reports_its_particles_and_grows_the_same_cluster(model, monkeypatch):
    growing = importlib.import_module("dlasweep.growth.cluster")  # the package attribute is the function

    monkeypatch.setattr(growing, "WATCH_SECONDS", 1e-3)
    seen = []
    marks = [10, 3000, 30_000]
    watched = dla.grow(30_000, 4, checkpoints=marks, model=model, progress=lambda k, s: seen.append((k, s)))
    plain = dla.grow(30_000, 4, checkpoints=marks, model=model)
    np.testing.assert_array_equal(watched.points, plain.points)
    np.testing.assert_array_equal(watched.steps, plain.steps)
    assert watched.status == plain.status and list(watched.checkpoints) == marks
    assert np.all(np.diff(watched.times) >= 0) and not np.isnan(watched.times).any()
    # unwatched, the kernel is given the checkpoints alone: a time for each
    assert plain.times.shape == (len(marks),) and np.all(np.diff(plain.times) >= 0) and not np.isnan(plain.times).any()
    particles, seconds = np.array(seen).T
    assert np.all(np.diff(particles) >= 0) and np.all(np.diff(seconds) >= 0) and particles[-1] == 30_000
    # reported as it grows, at the watch marks (every n / WATCH_MARKS) or the checkpoints
    middle = particles[(particles > 0) & (particles < 30_000)]
    assert len(middle) and np.all((middle % (30_000 // growing.WATCH_MARKS) == 0) | np.isin(middle, marks))


def test_a_watched_growth_raises_what_the_kernel_raises(monkeypatch):
    growing = importlib.import_module("dlasweep.growth.cluster")  # the package attribute is the function

    def broken(n, p, marks, rng, times=None):
        raise MemoryError("simulated")

    monkeypatch.setitem(growing.KERNELS, "lattice", broken)
    with pytest.raises(MemoryError, match="simulated"):
        dla.grow(100, 0, progress=lambda k, s: None)
    with pytest.raises(MemoryError, match="simulated"):
        dla.grow(100, 0)


@pytest.mark.parametrize("many", [False, True])
def test_a_waiting_growth_gives_up_within_a_watch_once_stop_is_set(monkeypatch, many):
    """What an interrupted sweep's closing relies on (``growth.cluster.STOP``): ``grow`` and ``grow_many``
    raise ``Interrupted`` within ``WATCH_SECONDS`` of it, while their kernel still runs."""
    growing = importlib.import_module("dlasweep.growth.cluster")
    release = threading.Event()

    def slow(n, p, marks, rngs, times=None):
        release.wait(30)  # a kernel that runs on until the test ends
        raise AssertionError("given up before this")

    monkeypatch.setitem(growing.KERNELS, "lattice", slow)
    threading.Timer(0.3, growing.STOP.set).start()
    start = time.monotonic()
    try:
        with pytest.raises(growing.Interrupted):
            growing.grow_many(100, [1, 2]) if many else dla.grow(100, 0)
        assert 0.3 <= time.monotonic() - start < 0.3 + 3 * growing.WATCH_SECONDS
    finally:
        growing.STOP.clear()
        release.set()
    monkeypatch.undo()
    assert dla.grow(100, 0).n == 100  # STOP cleared: growth as before


def test_a_growth_that_ended_as_stop_was_set_is_kept(monkeypatch):
    growing = importlib.import_module("dlasweep.growth.cluster")
    kernel = growing.KERNELS["lattice"]

    def stopping(n, p, marks, rngs):
        growing.STOP.set()  # the sweep interrupted while this growth's last stretch ran
        return kernel(n, p, marks, rngs)

    monkeypatch.setitem(growing.KERNELS, "lattice", stopping)
    try:
        assert [c.n for c in growing.grow_many(100, [1, 2])] == [100, 100]
    finally:
        growing.STOP.clear()


@pytest.mark.parametrize("kw", [{"model": "lattice"}, {"model": "offlattice"}, {"model": "lattice", "dim": 3},
                                {"model": "offlattice", "size": 30}, {"model": "lattice", "walkers": 4, "size": 60}])
def test_grow_many_grows_the_clusters_grow_grows_one_by_one(kw):
    growing = importlib.import_module("dlasweep.growth.cluster")
    seeds = [np.random.SeedSequence(5, spawn_key=(k,)) for k in range(4)]
    marks = [10, 200, 2000]
    many = growing.grow_many(2000, seeds, checkpoints=marks, **kw)
    for got, seed in zip(many, seeds, strict=True):
        want = dla.grow(2000, seed, checkpoints=marks, **kw)
        np.testing.assert_array_equal(got.points, want.points)
        np.testing.assert_array_equal(got.steps, want.steps)
        assert got.points.dtype == want.points.dtype and got.status == want.status and got.params == want.params
        np.testing.assert_array_equal(np.isnan(got.times), np.isnan(want.times))
        # the whole growth's seconds: at least those to the last count reached
        assert got.seconds > 0 and (np.isnan(got.times) | (got.times <= got.seconds)).all()
    assert many[0].params is not many[1].params
    if kw.get("size") == 30:  # a small box: stopped short, its last counts never reached
        assert all(c.status == "boundary" and np.isnan(c.times[-1]) for c in many)


def test_the_kernels_clock_reads_the_monotonic_clock():
    from dlasweep._jit import clock

    before = time.clock_gettime(time.CLOCK_MONOTONIC)
    now = clock()
    after = time.clock_gettime(time.CLOCK_MONOTONIC)
    assert before <= now <= after


def test_prefetch_is_a_hint_that_changes_nothing():
    """``_jit.prefetch`` compiles for the arrays the kernels hint at (1D, and rows of 2D ones, to their
    last element) and neither writes nor reads them: the arrays and what the kernel computes stay."""
    import numba

    from dlasweep._jit import prefetch

    @numba.njit
    def hinted(rows, links):
        total = 0.0
        for i in range(len(links)):
            prefetch(rows, i)
            prefetch(links, i)
            total += rows[i, 0] * links[i]
        return total

    rows, links = np.arange(30.0).reshape(10, 3), np.arange(10, dtype=np.int32)
    before = rows.copy(), links.copy()
    assert hinted(rows, links) == float((rows[:, 0] * links).sum())
    np.testing.assert_array_equal(rows, before[0])
    np.testing.assert_array_equal(links, before[1])


def test_diffusion_times_are_four_bytes_and_saturate():
    """A particle's diffusion time is stored in 4 bytes; a count beyond them reads as the largest, not wrapped."""
    from dlasweep.kernels.model import MOST_STEPS, STEPS_DTYPE, diffusion_time
    assert [int(diffusion_time(k)) for k in (0, 7, MOST_STEPS - 1, MOST_STEPS, MOST_STEPS + 1, 1 << 40)] == [
        0, 7, MOST_STEPS - 1, MOST_STEPS, MOST_STEPS, MOST_STEPS]
    assert dla.grow(300, seed=1).steps.dtype == STEPS_DTYPE == dla.grow(300, seed=1, model="offlattice").steps.dtype


def test_compiled_reads_numba_s_cache_of_each_growth_kernel(tmp_path):
    """``growth.cluster.compiled`` (the CLI's "compiling kernels" notice) is true once a kernel is cached, false
    where numba's cache is empty."""
    growth = importlib.import_module("dlasweep.growth.cluster")
    for model in ("lattice", "offlattice"):
        for dim in (2, 3):
            dla.grow(20, seed=1, model=model, dim=dim)
            assert growth.compiled(resolve(model=model, dim=dim))
        assert not growth.compiled({**resolve(model=model), "dim": 4})  # each dimension's kernel is compiled apart
    code = ("import importlib; from dlasweep.params import resolve; "
            "g = importlib.import_module('dlasweep.growth.cluster'); "
            "print(g.compiled(resolve(model='lattice')), g.compiled(resolve(model='offlattice')))")
    fresh = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                           env={**os.environ, "NUMBA_CACHE_DIR": str(tmp_path)})
    assert fresh.stdout.split() == ["False", "False"]
