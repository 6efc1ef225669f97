"""A sweep's plan: what it grows, its memory and disk, and the refusal of what does not fit."""

import re

import numpy as np
import pytest

from conftest import TINY_SPEC
from dlasweep.data.schema import ragged_columns
from dlasweep.sweep import plan
from dlasweep.sweep.spec import SpecError, parse_spec

GB = 10 ** 9
LATTICE_2D_BYTES = sum(np.dtype(d).itemsize for d in ragged_columns(["lattice"], [2]).values())
"""A stored 2D lattice particle: x, y (int32), its diffusion time and its parent (16 bytes)."""


def test_the_plan_counts_every_cluster_to_the_largest_count():
    spec = parse_spec(TINY_SPEC)  # 2 stickiness x 2 sizes x 3 seeds, to 150 particles, lattice 2D
    the_plan = plan.plan(spec, threads=2)
    assert (the_plan.clusters, the_plan.particles, the_plan.stored) == (12, 1800, 1800)
    # two lattice 2D clusters at once: the kernel's bytes and two copies of the stored particle
    assert LATTICE_2D_BYTES == 16
    assert the_plan.growing == 2 * (plan.KERNEL_BYTES["lattice", 2] + 2 * LATTICE_2D_BYTES) * 150
    assert the_plan.disk >= 2 * 1800 * LATTICE_2D_BYTES and the_plan.memory > plan.BASE_BYTES
    assert str(the_plan).startswith("plan: 12 clusters, 1,800 particles (1,800 stored); about ")
    assert plan.plan(spec, threads=64).growing == 12 * (plan.KERNEL_BYTES["lattice", 2] + 2 * LATTICE_2D_BYTES) * 150


def test_a_plan_of_one_says_one_cluster_and_one_particle():
    the_plan = plan.plan(parse_spec("[grid]\nn_particles = [1]\nseeds = 1\n"), threads=2)
    assert str(the_plan).startswith("plan: 1 cluster, 1 particle (1 stored); about ")


def test_a_target_sweep_is_planned_at_its_max_seeds_and_stored_clusters_are_counted():
    spec = parse_spec(TINY_SPEC.replace("root_seed = 12345", "target_ci = 0.01\nmax_seeds = 40\nstore_clusters = 2"))
    the_plan = plan.plan(spec, threads=1)
    assert (the_plan.clusters, the_plan.particles, the_plan.stored) == (160, 160 * 150, 4 * 2 * 150)


@pytest.mark.parametrize("room, local, key", [
    (plan.Room(memory=GB // 10, disk=None), True, r"grid.n_particles: the sweep needs about 1\.\d GB of memory, "
                                                  r"100\.0 MB available \(4 clusters of up to 10,000,000 particles\)"),
    (plan.Room(memory=None, disk=GB // 10), True,
     r"grid.seeds: the sweep needs about 1\.\d GB of disk, 100\.0 MB free"),
    (plan.Room(memory=GB // 10, disk=GB // 10), False, r"grid.seeds: the sweep needs about 1\.\d GB of disk"),
])
def test_what_does_not_fit_is_refused_naming_the_key(room, local, key):
    # two clusters of 10^7 growing: 2 x (KERNEL_BYTES + 2 x 16) x 10^7, about 1.3 GB, and the process;
    # on disk 2 x 4e7 x 16 bytes
    spec = parse_spec("[grid]\nn_particles = [1e7]\nseeds = 4\n")
    with pytest.raises(SpecError) as caught:
        plan.check(plan.plan(spec, threads=2), spec, room, local=local)
    assert re.match(key, str(caught.value)), str(caught.value)


def test_what_fits_passes_and_the_room_is_read_here(tmp_path):
    spec = parse_spec(TINY_SPEC)
    there = plan.room(tmp_path)
    assert there.memory > 0 and there.disk > 0
    plan.check(plan.plan(spec, threads=2), spec, there)
    plan.check(plan.plan(spec, threads=2), spec, plan.Room(None, None))
