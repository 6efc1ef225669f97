"""The OUT.parts folder (dlasweep/sweep/parts.py): parts written and read back, the manifest, the lock."""

import contextlib
import errno
import json
import os
import socket
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

import dlasweep as dla
from conftest import TINY_SPEC, Interrupt, files_under, finished_clusters, interrupt_after, science
from dlasweep._version import FORMAT
from dlasweep.data import netcdf as store
from dlasweep.sweep import task as worker
from dlasweep.sweep.parts import LOCK, MANIFEST, Parts, ResumeError, _lock
from dlasweep.sweep.spec import parse_spec


def test_resume_refuses_a_changed_spec(tmp_path, dask_client, monkeypatch):
    out = tmp_path / "tiny.nc"
    interrupt_after(monkeypatch, 2)
    with pytest.raises(Interrupt):
        dla.run_sweep(parse_spec(TINY_SPEC), client=dask_client, out=out)
    monkeypatch.undo()
    changed = parse_spec(TINY_SPEC.replace("[20, 60, 150]", "[20, 60, 100]"))
    with pytest.raises(ResumeError, match=r"grid.n_particles: \[20, 60, 150\] -> \[20, 60, 100\]"):
        dla.run_sweep(changed, client=dask_client, out=out, resume=True)
    assert len(finished_clusters(out)) == 2


def test_a_part_cut_short_by_a_full_disk_leaves_no_temporary_file(tmp_path, dask_client, monkeypatch):
    out = tmp_path / "tiny.nc"
    real_savez = np.savez

    def savez(file, **members):
        if len(finished_clusters(out)) == 5:
            file.write(b"PK half a part")
            raise OSError(errno.ENOSPC, "No space left on device")
        real_savez(file, **members)

    monkeypatch.setattr(np, "savez", savez)
    with pytest.raises(OSError, match="No space left"):
        dla.run_sweep(parse_spec(TINY_SPEC), client=dask_client, out=out)
    parts = Path(f"{out}.parts")
    assert len(finished_clusters(out)) == 5
    assert sorted(p.name for p in parts.iterdir() if p.name not in (MANIFEST, LOCK)
                  and not p.name.startswith("part-")) == []


@contextlib.contextmanager
def locked_by_another_process(folder):
    """Hold the lock of a parts folder from another process, as a running sweep does; yield that process."""
    code = ("import sys, pathlib, dlasweep.sweep.parts as s; s._lock(pathlib.Path(sys.argv[1])); print(1, flush=True); "
            "input()")
    holder = subprocess.Popen([sys.executable, "-c", code, str(folder)], stdin=subprocess.PIPE,
                              stdout=subprocess.PIPE)
    try:
        assert holder.stdout.readline() == b"1\n"
        yield holder
    finally:
        holder.kill()
        holder.wait()


@pytest.fixture
def interrupted(tmp_path, dask_client, monkeypatch):
    """The output of the tiny sweep, killed after five finished tasks."""
    out = tmp_path / "tiny.nc"
    with monkeypatch.context() as patch:
        interrupt_after(patch, 5)
        with pytest.raises(Interrupt):
            dla.run_sweep(parse_spec(TINY_SPEC), client=dask_client, out=out)
    return out


@pytest.mark.parametrize("resume", [[], ["--resume"]])
def test_a_running_sweep_locks_out_a_second_one(resume, interrupted, run_cli, write_spec, dask_cluster):
    parts = Path(f"{interrupted}.parts")
    with locked_by_another_process(parts) as holder:
        before = files_under(parts)
        status, _, err = run_cli("sweep", write_spec(), "-o", interrupted, *resume,
                                 "--scheduler", dask_cluster.scheduler_address)
        assert files_under(parts) == before
    assert status == 2 and len(err.strip().splitlines()) == 1
    assert f"{parts}: in use by process {holder.pid} on " in err


def test_the_lock_of_a_killed_run_is_taken_over(interrupted, dask_client, reference, monkeypatch):
    parts = Path(f"{interrupted}.parts")
    with locked_by_another_process(parts):
        pass  # killed: its lock file stays, naming it
    assert (parts / LOCK).exists()
    holders = []
    real_write = Parts.write
    monkeypatch.setattr(Parts, "write", lambda self, results: (
        holders.append((parts / LOCK).read_text()), real_write(self, results)))
    resumed = dla.run_sweep(parse_spec(TINY_SPEC), client=dask_client, out=interrupted, resume=True)
    assert len(holders) == 7 and set(holders) == {f"process {os.getpid()} on {socket.gethostname()}"}
    xr.testing.assert_identical(science(resumed), science(reference))
    resumed.close()


def test_the_lock_is_held_for_every_batch_and_the_final_file(tmp_path, dask_client, monkeypatch):
    out = tmp_path / "t.nc"
    parts = Path(f"{out}.parts")
    spec = parse_spec(TINY_SPEC + "target_ci = 1e-4\nmax_seeds = 6\n")
    held = []

    def check(real):
        def checked(*args):
            with pytest.raises(ResumeError, match=f"in use by process {os.getpid()} "):
                _lock(parts)
            held.append(real.__name__)
            return real(*args)
        return checked

    monkeypatch.setattr(Parts, "write", check(Parts.write))
    monkeypatch.setattr(store.ParticleWriter, "finish", check(store.ParticleWriter.finish))
    dla.run_sweep(spec, client=dask_client, out=out).close()
    assert held == ["write"] * 24 + ["finish"]
    assert files_under(tmp_path) == {Path("t.nc")}


@pytest.mark.parametrize("kept", [0, 1, 3])
def test_parts_kept_in_memory_read_as_the_files(tmp_path, monkeypatch, kept):
    # Results read back from what the run kept (none, the first part, all three) equal those read from disk.
    spec = parse_spec(TINY_SPEC)
    tasks = list(spec.tasks())
    counts, scales = np.asarray(spec.counts), worker.sweep_scales(spec)
    parts = Parts(tmp_path)
    monkeypatch.setattr(Parts, "KEEP_BYTES", 1 << 28 if kept else 0)
    for batch in (tasks[:3], tasks[3:4], tasks[4:]):
        results = worker.measure_tasks(batch, counts, scales, 1, [True] * len(batch))
        parts.write({t.key: r for t, r in zip(batch, results)})
        if kept == 1:  # both budgets spent
            parts._kept_bytes = dict.fromkeys(parts._kept_bytes, Parts.KEEP_BYTES)
    assert len(parts._kept) == kept and all({"points", "box_count"} <= set(k) for k in parts._kept.values())
    keys = [t.key for t in tasks][::-1]
    for names, release in ((("box_count", "radius_gyration_history", "status", "points.shape", "error"), False),
                           (("points", "diffusion_time"), True), (("points", "diffusion_time"), False)):
        from_disk = list(Parts(tmp_path).results(keys, names))
        for a, b in zip(parts.results(keys, names, release=release), from_disk, strict=True):
            assert a.keys() == b.keys()
            for name in a:
                np.testing.assert_array_equal(a[name], b[name])
    # Released positions are read from the files from then on (the third pass).
    assert not any("points" in k for k in parts._kept.values()) and (kept != 3 or parts._kept_bytes["clusters"] == 0)


def test_a_part_of_one_cluster_keeps_its_positions_without_a_copy(tmp_path):
    # A 1e8 cluster's positions are 800 MB and more: the part written for it (and kept for the file) holds
    # the task's own arrays, not concatenated copies; a part of several clusters holds each in turn.
    spec = parse_spec(TINY_SPEC)
    tasks = list(spec.tasks())
    counts, scales = np.asarray(spec.counts), worker.sweep_scales(spec)
    results = worker.measure_tasks(tasks[:2], counts, scales, 1, [True, True])
    parts = Parts(tmp_path)
    parts.write({tasks[0].key: results[0]})
    kept = next(iter(parts._kept.values()))
    for name in Parts.PER_PARTICLE:
        assert np.shares_memory(kept[name], results[0][name]), name
    parts.write({t.key: r for t, r in zip(tasks[:2], results)})
    both = list(parts._kept.values())[1]
    np.testing.assert_array_equal(both["points"], np.concatenate([r["points"].ravel() for r in results]))
    assert not np.shares_memory(both["points"], results[0]["points"])


def test_parts_table_stacks_what_results_gives(tmp_path):
    # The whole-part route of _assemble equals the result-by-result one: keys in any order, across parts,
    # a failed result (its message longer than the first part's) replaced by a finished one in a later part.
    spec = parse_spec(TINY_SPEC)
    tasks = list(spec.tasks())
    counts, scales = np.asarray(spec.counts), worker.sweep_scales(spec)
    parts = Parts(tmp_path)
    measured = dict(zip((t.key for t in tasks), worker.measure_tasks(tasks, counts, scales, 1, [True] * len(tasks))))
    failed = worker.error_result(counts, len(scales), 2, "ValueError: " + "a long message " * 10)
    parts.write({t.key: measured[t.key] for t in tasks[:2]})
    parts.write({tasks[2].key: failed, tasks[3].key: failed, **{t.key: measured[t.key] for t in tasks[4:]}})
    parts.write({tasks[3].key: measured[tasks[3].key]})
    names = ("box_count", "radius_gyration_history", "status", "wall_time", "points.shape", "error")
    # Kept in memory and from the files; the first part read has only empty messages, or the long one.
    for reader, keys in ((parts, [t.key for t in tasks]), (Parts(tmp_path), [t.key for t in tasks][::-1])):
        table = reader.table(keys, names)
        for i, result in enumerate(reader.results(keys, names)):
            for name in names:
                np.testing.assert_array_equal(table[name][i], result[name])
        assert [str(e) for e in table["error"]].count(str(failed["error"])) == 1


def test_the_stream_writes_a_finished_cluster_from_memory_and_a_later_one_from_its_part(tmp_path, monkeypatch):
    # A cluster finished in order is written to the file from the results in hand, not read back from its
    # part (a 1e8 cluster, too large to keep, was read back beside its own 1.6 GB); one that finished
    # before an earlier cluster is read from its part once that earlier one is in.
    from dlasweep.sweep.runner import _Stream

    spec = parse_spec(TINY_SPEC)
    tasks = [t for t in spec.tasks() if spec.stores(t)][:3]
    counts, scales = np.asarray(spec.counts), worker.sweep_scales(spec)
    results = dict(zip((t.key for t in tasks), worker.measure_tasks(tasks, counts, scales, 1, [True] * 3)))
    monkeypatch.setattr(Parts, "KEEP_BYTES", 0)  # nothing kept: a read is a read of the file
    read = []
    results_of = Parts.results

    def spy(self, keys, names, release=False):
        keys = list(keys)
        read.extend(keys)
        return results_of(self, keys, names, release)

    monkeypatch.setattr(Parts, "results", spy)
    parts = Parts(tmp_path)
    stream = _Stream(spec, list(spec.tasks()), parts, list(spec.tasks()))
    first, second, third = (t.key for t in tasks)
    for keys, expected_reads in (([first], []), ([third], []), ([second], [third])):
        finished = {key: results[key] for key in keys}
        parts.write(finished)
        stream.feed(finished)
        assert read == expected_reads
        read.clear()
    assert stream.next == 3
    assert stream.writer.written + stream.writer._filled == sum(len(r["points"]) for r in results.values())


def test_walk_steps_at_each_count_are_the_cumulative_sums():
    from dlasweep.sweep.task import _prefix_sums

    steps = np.random.default_rng(2).integers(0, 2**32 - 1, 1000, dtype=np.uint64).astype(np.uint32)
    prefix = np.array([1, 1, 7, 500, 1000])
    np.testing.assert_array_equal(_prefix_sums(steps, prefix), np.cumsum(steps, dtype=np.int64)[prefix - 1])


def as_written_by_0_1_0(parts):
    """Make a parts folder what dlasweep 0.1.0 left: parts without the clusters' parents, a manifest without a
    format (its identity naming the package version instead)."""
    for file in parts.glob("part-*.npz"):
        with np.load(file) as z:
            members = {name: z[name] for name in z.files if not name.startswith("parent")}
        np.savez(file, **members)
    manifest = json.loads((parts / MANIFEST).read_text())
    identity = {k: v for k, v in manifest["identity"].items() if k != "dlasweep format"}
    (parts / MANIFEST).write_text(json.dumps({"digest": manifest["digest"],
                                              "identity": {**identity, "dlasweep version": "0.1.0"}}))


@pytest.mark.parametrize("resume", [[], ["--resume"]])
def test_parts_of_another_format_are_refused_in_one_line_saying_what_to_do(resume, interrupted, run_cli, write_spec,
                                                                          dask_cluster):
    # Before the format version, resuming these read the first part, missed its parents and said "unreadable;
    # delete it and run again with --resume", which failed again at the next part.
    parts = Path(f"{interrupted}.parts")
    manifest = json.loads((parts / MANIFEST).read_text())
    assert manifest["format"] == FORMAT and manifest["dlasweep"] == dla.__version__
    as_written_by_0_1_0(parts)
    before = files_under(parts)
    status, out, err = run_cli("sweep", write_spec(), "-o", interrupted, *resume,
                               "--scheduler", dask_cluster.scheduler_address)
    assert status == 2 and out == "" and len(err.strip().splitlines()) == 1, err
    assert f"{parts}: parts of format 1 (dlasweep 0.1.0); this dlasweep ({dla.__version__}) resumes format " \
           f"{FORMAT} only: finish the sweep with dlasweep 0.1.0, or delete {parts}" in err
    assert files_under(parts) == before


def test_the_identity_holds_the_format_not_the_package_version(monkeypatch):
    # A patch release (same format) resumes the parts of the one before it; a new format does not.
    from dlasweep.sweep import spec as spec_module

    spec = parse_spec(TINY_SPEC)
    digest = spec.digest()
    monkeypatch.setattr(dla, "__version__", "0.2.1")
    assert "dlasweep version" not in spec.identity() and spec.digest() == digest
    monkeypatch.setattr(spec_module, "FORMAT", FORMAT + 1)
    assert spec.digest() != digest
