"""The worker's task (dlasweep/sweep/task.py): a batch is what growing and measuring each cluster alone gives, and a
failure stays with its own cluster."""

import numpy as np

import dlasweep as dla
from conftest import TINY_SPEC
from dlasweep.measures import shape as measure
from dlasweep.params import Status
from dlasweep.stats.fit import growth_counts
from dlasweep.sweep import task as worker
from dlasweep.sweep.spec import parse_spec


def tiny():
    spec = parse_spec(TINY_SPEC)
    return spec, list(spec.tasks()), np.asarray(spec.counts), worker.sweep_scales(spec)


def test_a_batch_is_what_grow_and_the_measures_give_one_by_one():
    spec, tasks, counts, scales = tiny()
    stored = [k % 2 == 0 for k in range(len(tasks))]
    results = worker.measure_tasks(tasks, counts, scales, spec.root_seed, stored)
    for task, keep, result in zip(tasks, stored, results, strict=True):
        seed = np.random.SeedSequence(spec.root_seed, spawn_key=task.spawn_key)
        cluster = dla.grow(counts[-1], seed, checkpoints=counts, **task.params)
        prefix = np.minimum(counts, cluster.n)
        measured = measure.cluster_measures(cluster.points, prefix, growth_counts(counts), lattice=True, scales=scales)
        for name, values in measured.items():
            np.testing.assert_array_equal(result[name], values, err_msg=name)
        np.testing.assert_array_equal(result["n_grown"], prefix)
        np.testing.assert_array_equal(result["walk_steps"], np.cumsum(cluster.steps)[prefix - 1])
        np.testing.assert_array_equal(result["status"],
                                      np.where(counts <= cluster.n, Status.ok, Status[cluster.status]))
        np.testing.assert_array_equal(result["points"], cluster.points if keep else cluster.points[:0])
        np.testing.assert_array_equal(result["parent"], cluster.parents if keep else cluster.parents[:0])
        assert str(result["error"]) == ""


def test_a_failing_cluster_fails_alone_with_its_message(replicate_1_fails):
    spec, tasks, counts, scales = tiny()
    results = worker.measure_tasks(tasks, counts, scales, spec.root_seed, [True] * len(tasks))
    assert sum(task.spawn_key[-1] == 1 for task in tasks) == 4
    for task, result in zip(tasks, results, strict=True):
        if task.spawn_key[-1] == 1:
            assert str(result["error"]) == "RuntimeError: simulated failure"
            assert (result["status"] == Status.error).all() and (result["n_grown"] == 0).all()
            assert np.isnan(result["radius_gyration"]).all() and len(result["points"]) == 0
        else:
            assert str(result["error"]) == "" and (result["n_grown"] > 0).all()


def test_an_error_result_says_its_message_on_one_line():
    _, _, counts, scales = tiny()
    result = worker.error_result(counts, len(scales), 3, "ValueError: a message\n  over two lines")
    assert str(result["error"]) == "ValueError: a message over two lines"
    assert result["points"].shape == (0, 3) and result["box_count"].shape == (len(counts), len(scales))
