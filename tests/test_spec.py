"""Sweep specs: parsing, the task grid, and one clear error per bad key."""

import numpy as np
import pytest

from conftest import ROOT, TINY_SPEC
from dlasweep.sweep.spec import SpecError, differences, load_spec, parse_spec


def test_tiny_spec_grid():
    spec = parse_spec(TINY_SPEC)
    assert spec.name == "tiny"
    assert spec.axes == {"stickiness": (1.0, 0.5)}
    assert spec.fixed == {"model": "lattice", "dim": 2}
    assert (spec.sizes, spec.counts, spec.seeds) == ((0, 24), (20, 60, 150), (0, 1, 2))
    assert spec.shape == (2, 2, 3) and spec.n_tasks == 12
    tasks = list(spec.tasks())
    assert [t.index for t in tasks] == [tuple(i) for i in np.ndindex(2, 2, 3)]
    assert len({t.key for t in tasks}) == 12
    assert tasks[7].params["stickiness"] == 0.5 and tasks[7].params["size"] == 0
    assert tasks[7].params["neighbours"] == 4  # resolved, every parameter present
    assert spec.root_seed == 12345 and spec.text == TINY_SPEC


def test_counts_sorted_and_scalars_accepted():
    spec = parse_spec("[grid]\nn_particles = [300, 100]\nsize = 0\nseeds = [4, 9]\n")
    assert spec.counts == (100, 300) and spec.sizes == (0,) and spec.seeds == (4, 9)
    assert spec.axes == {} and spec.root_seed == 0
    # A listed seed names its own stream: replicate 4 here is replicate 4 of `seeds = 10`.
    assert [t.spawn_key for t in spec.tasks()] == [(0, 4), (0, 9)]


SPECS = ROOT / "dlasweep" / "sweep" / "specs"


def test_the_quick_example_is_small_and_sweeps_an_axis():
    spec = load_spec(SPECS / "quick.toml")
    assert spec.fixed["model"] == "lattice" and spec.fixed["dim"] == 2
    assert max(spec.counts) >= 10_000 and len(spec.seeds) == 8 and spec.axes


def test_every_shipped_spec_is_valid():
    paths = sorted(SPECS.glob("*.toml"))
    assert {"quick.toml", "tradeoff.toml"} <= {path.name for path in paths}, paths
    for path in paths:
        spec = load_spec(path)
        assert spec.n_tasks > 0 and spec.name, path


@pytest.mark.parametrize("change, key", [
    (("stickiness = [1.0, 0.5]", "stickiness = 0"), "model.stickiness"),
    (("stickiness = [1.0, 0.5]", "stickiness = [1.0, 1.5]"), "model.stickiness"),
    (("stickiness = [1.0, 0.5]", "stickiness = [1.0, 1.0]"), "model.stickiness"),
    (("stickiness = [1.0, 0.5]", "stickiness = []"), "model.stickiness"),
    (("stickiness = [1.0, 0.5]", "stickyness = 0.5"), "model.stickyness"),
    (("stickiness = [1.0, 0.5]", 'stickiness = "high"'), "model.stickiness"),
    (('model = "lattice"', 'model = "square"'), "model.model"),
    (("dim = 2", "dim = 4"), "model.dim"),
    (("dim = 2", "dim = 2.5"), "model.dim"),
    (("dim = 2", 'dim = 2\nlaunch = "box"'), "model.launch"),
    (("dim = 2", "dim = 2\nsize = 10"), "model.size"),
    (("dim = 2", "dim = 2\njumps = 1"), "model.jumps"),
    (("size = [0, 24]", "size = [0, 4]"), "grid.size"),
    (("size = [0, 24]", "size = [-1]"), "grid.size"),
    (("size = [0, 24]", "size = []"), "grid.size"),
    (("n_particles = [20, 60, 150]", "n_particles = [1.5e3, 2.5]"), "grid.n_particles"),
    (("n_particles = [20, 60, 150]", "n_particles = [0, 10]"), "grid.n_particles"),
    (("n_particles = [20, 60, 150]", "n_particles = [10000000000]"), "grid.n_particles"),
    (("n_particles = [20, 60, 150]", ""), "grid.n_particles"),
    (("seeds = 3", "seeds = 0"), "grid.seeds"),
    (("seeds = 3", "seeds = [1, -2]"), "grid.seeds"),
    (("seeds = 3", "seeds = true"), "grid.seeds"),
    (("seeds = 3", "seeds = 3\nreplicas = 2"), "grid.replicas"),
    (("root_seed = 12345", "root_seed = -5"), "run.root_seed"),
    (("root_seed = 12345", 'root_seed = "x"'), "run.root_seed"),
    (("root_seed = 12345", "root_seed = 1\nworkers = 0"), "run.workers"),
    (("root_seed = 12345", "root_seed = 1\nthreads = 2"), "run.threads"),
    (("root_seed = 12345", 'root_seed = 1\nstore_clusters = "some"'), "run.store_clusters"),
    (("root_seed = 12345", "root_seed = 1\nstore_clusters = -1"), "run.store_clusters"),
    (("root_seed = 12345", "root_seed = 1\nstore_clusters = 2.5"), "run.store_clusters"),
    (("root_seed = 12345", "root_seed = 1\nstore_clusters = true"), "run.store_clusters"),
    (("root_seed = 12345", "root_seed = 1\nstore_clusters = [1]"), "run.store_clusters"),
    (("[run]", "[runs]"), "runs"),
    (('name = "tiny"', "name = 3"), "name"),
    (("seeds = 3", "seeds = "), "TOML"),
])
def test_bad_values_name_their_key(change, key):
    text = TINY_SPEC.replace(*change)
    assert text != TINY_SPEC
    with pytest.raises(SpecError) as caught:
        parse_spec(text)
    message = str(caught.value)
    assert message.startswith(key + ":") or (key == "TOML" and "TOML" in message), message
    assert "\n" not in message


def test_sections_must_be_tables():
    with pytest.raises(SpecError, match=r"^grid: expected a \[grid\] table"):
        parse_spec("grid = 3")


def test_combination_errors_say_where():
    with pytest.raises(SpecError, match=r"model.launch: .* \(at .*size=0\)"):
        parse_spec(TINY_SPEC.replace("dim = 2", 'dim = 2\nlaunch = "box"'))


def test_missing_or_unreadable_file(tmp_path):
    with pytest.raises(SpecError, match="cannot read"):
        load_spec(tmp_path / "absent.toml")
    binary = tmp_path / "binary.toml"
    binary.write_bytes(b"\xff\xfe\x00garbage")
    with pytest.raises(SpecError):
        load_spec(binary)


def test_digest_follows_the_science_not_the_comments():
    spec = parse_spec(TINY_SPEC)
    assert parse_spec("# a comment\n" + TINY_SPEC).digest() == spec.digest()
    changed = parse_spec(TINY_SPEC.replace("seeds = 3", "seeds = 4"))
    assert changed.digest() != spec.digest()
    assert differences(spec.identity(), changed.identity()) == ["grid.seeds: [0, 1, 2] -> [0, 1, 2, 3]"]


@pytest.mark.parametrize("value, stored", [('"all"', None), ('"none"', 0), ("0", 0), ("2", 2), ("5", 5)])
def test_store_clusters_names_the_seeds_whose_positions_are_kept(value, stored):
    spec = parse_spec(TINY_SPEC.replace("root_seed = 12345", f"root_seed = 12345\nstore_clusters = {value}"))
    assert spec.store_clusters == stored
    kept = [t.index[-1] for t in spec.tasks() if spec.stores(t)]
    assert kept == [j for _ in range(4) for j in range(3) if stored is None or j < stored]
    # Parts without positions serve no run that stores them: a set value is in the digest, "all" is not.
    plain = parse_spec(TINY_SPEC)
    assert (spec.digest() == plain.digest()) == (stored is None)


def test_integral_numbers_follow_the_command_lines_rule():
    # TOML reads 1e5 as a float: accepted as `-n 1e5` is, and typed as the parameter is.
    spec = parse_spec("[grid]\nn_particles = [1e5, 2.5e2]\nseeds = 2e0\nsize = [3.2e1]\n"
                      "[model]\nwalkers = [1, 2e0]\nmax_steps = 1e9\n[run]\nroot_seed = 7.0\nworkers = 2.0\n"
                      "store_clusters = 1.0\n")
    assert spec.counts == (250, 100_000) and spec.seeds == (0, 1) and spec.sizes == (32,)
    assert spec.axes == {"walkers": (1, 2)} and spec.fixed == {"max_steps": 10 ** 9}
    assert all(type(v) is int for v in (*spec.counts, *spec.axes["walkers"], spec.fixed["max_steps"],
                                         spec.root_seed, spec.workers, spec.store_clusters))
    # The same value twice, once as a float, is the same value.
    with pytest.raises(SpecError, match=r"^model.walkers: 1 appears twice"):
        parse_spec("[grid]\nn_particles = 10\nsize = 32\n[model]\nwalkers = [1, 1.0]\n")


@pytest.mark.parametrize("line, message", [
    ("n_particles = [1e20]", "grid.n_particles: 1e+20 is not in [1, 100000000]"),
    ("n_particles = [1.7e308]", "grid.n_particles: 1.7e+308 is not in [1, 100000000]"),
    ("n_particles = 10\nseeds = 100000000000", "grid.seeds: 100000000000 is not in [1, 10000000]"),
    ("n_particles = 10\nseeds = [1e19]", "grid.seeds: 1e+19 is not in [0, 9223372036854775807]"),
    ("n_particles = 10\nsize = [1e6]", "grid.size: 1000000.0 is not in [0, 100000]"),
    ("n_particles = 10\n[run]\nroot_seed = 1e30", "run.root_seed: 1e+30 is not in [0, 9223372036854775807]"),
    ("n_particles = 10\n[run]\nworkers = 100000", "run.workers: 100000 is not in [1, 1024]"),
    ("n_particles = 10\n[run]\nstore_clusters = 1e300", "run.store_clusters: 1e+300 is not in [0, 10000000]"),
    ("n_particles = 10\nseeds = 2\n[run]\ntarget_ci = 1e-7\nmax_seeds = 100000000000000",
     "run.max_seeds: 100000000000000 is not in [1, 10000000]"),
    ("n_particles = 10\nsize = [0, 32]\nseeds = 6000000", "grid.seeds: the sweep would grow 12,000,000 clusters"),
    ("n_particles = 10\nsize = [0, 32]\nseeds = 2\n[run]\ntarget_ci = 0.01\nmax_seeds = 6000000",
     "run.max_seeds: the sweep would grow 12,000,000 clusters"),
    ("n_particles = 10\n[model]\nmax_steps = 1e25", "model.max_steps: 10000000000000000905969664 is above 2**62"),
    ('n_particles = 10\n[model]\nmodel = "offlattice"\nstep = 1e9', "model.step: 1000000000.0 is above 100"),
])
def test_every_integer_is_bounded_by_what_can_run(line, message):
    with pytest.raises(SpecError) as caught:
        parse_spec("[grid]\n" + line + "\n")
    assert str(caught.value).startswith(message), str(caught.value)


def test_the_first_replicates_of_each_configuration():
    """``tasks(replicates=k)``: each configuration's first k tasks of the whole listing, not the whole grid's."""
    spec = parse_spec(TINY_SPEC)
    every, seeds = list(spec.tasks()), len(spec.seeds)
    assert seeds > 1
    assert list(spec.tasks(replicates=1)) == every[::seeds]
    assert list(spec.tasks(replicates=2)) == [t for t in every if t.index[-1] < 2]
