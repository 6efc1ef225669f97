"""The parts folder of a sweep: finished batches of cluster results on disk, for ``--resume``.

Finished batches go at once to ``OUT.parts/part-<id>.npz`` (written under a
temporary name, then renamed; see ``Parts``). A resumed run keeps the
clusters finished there and computes the rest; ``OUT.parts/manifest.json``
records the spec's identity and the format version (``dlasweep._version.FORMAT``) so that a changed
spec, or parts of another layout, are refused. A run holds
an flock on ``OUT.parts/.lock`` from start to end, so a second run on the
same output is refused, and a killed run's lock is free at once. The
stored clusters' positions go into ``OUT.parts/particles.nc`` while the
sweep runs (``runner``'s stream, ``netcdf.ParticleWriter``). This module
knows files and locks, not dask, netCDF or the science.
"""

from __future__ import annotations

import contextlib
import fcntl
import itertools
import json
import os
import shutil
import socket
import tempfile
import uuid
from pathlib import Path

import numpy as np

from .._version import FORMAT, __version__
from .spec import differences

MANIFEST, LOCK, PARTICLES = "manifest.json", ".lock", "particles.nc"


class ResumeError(ValueError):
    """The parts folder does not fit this run (changed spec, or no --resume), or another run holds it."""


class Interrupted(KeyboardInterrupt):
    """Ctrl-C during a sweep that writes a file: ``kept`` finished clusters stay in the parts folder
    ``parts`` for ``--resume``; ``parts`` is None when the folder was removed, nothing having finished."""

    def __init__(self, kept, parts):
        super().__init__(kept, parts)
        self.kept, self.parts = kept, parts

    def kept_line(self) -> str:
        """What the sweep kept, as the end of the command's one line."""
        if self.parts is None:
            return "; no cluster had finished, nothing is kept"
        clusters = "1 finished cluster" if self.kept == 1 else f"{self.kept} finished clusters"
        return f"; {clusters} kept in {self.parts}, continue with --resume"


class Parts:
    """The folder of finished cluster results of one sweep.

    Each ``part-<id>.npz`` holds a batch of results: its ``keys`` and
    ``failed`` arrays index them, member ``<name>`` holds variable ``name`` of
    them all, flattened and concatenated, and ``<name>.shape`` the shape of
    each: a few zip members per part, since one per variable and cluster
    would cost as much to write and read as small clusters take to grow
    (docs/performance.md, "Sweeps").
    A cluster is finished when a part holds it without
    error; a failed one is computed again on resume, and a later part then
    holds it too. Knowing what is done reads only the indexes, once. The
    sweep sets ``done`` once its file is complete: the folder is removed.

    The parts this run writes are also kept in memory, up to ``KEEP_BYTES``
    for the clusters' positions and diffusion times and as much again for
    the rest: assembling the dataset and writing its file then read back
    only what an earlier run wrote, or what did not fit.
    """

    KEEP_BYTES = 1 << 28
    PER_PARTICLE = ("points", "diffusion_time", "parent")

    def __init__(self, path: Path):
        self.path = path
        self.done = False
        self._where = None
        self._kept, self._kept_bytes = {}, {"clusters": 0, "science": 0}

    @property
    def where(self) -> dict:
        """Task key -> (part file, position in it, failed); a finished result wins over a failed one."""
        if self._where is None:
            self._where = {}
            for file in sorted(self.path.glob("part-*.npz")):
                with self._reading(file), np.load(file) as z:
                    self._add(self._where, file, z["keys"], z["failed"])
        return self._where

    @staticmethod
    def _add(index, file, keys, failed):
        for i, (key, fail) in enumerate(zip(keys.tolist(), failed.tolist())):
            if not (fail and key in index):
                index[key] = (file, i, fail)

    @staticmethod
    @contextlib.contextmanager
    def _reading(file):
        try:
            yield
        except Exception as err:  # only a crash of the machine itself can leave one damaged
            raise OSError(f"{file}: unreadable ({err}); delete it and run again with --resume") from None

    def write(self, results: dict):
        """Save a batch of results (by task key) as one part."""
        index = self.where  # read before the new part is there
        file = self.path / f"part-{uuid.uuid4().hex}.npz"
        tmp = self.path / f".{file.name}.tmp"
        keys = np.array(list(results))
        failed = np.array([str(r["error"]) != "" for r in results.values()])
        members = {}
        for name in next(iter(results.values())):
            each = [np.asarray(r[name]) for r in results.values()]
            # Empty arrays (a failed cluster's points) must not set the dtype of the others; one
            # array alone is not copied (a 1e8 cluster's positions are 8e8 bytes and more).
            filled = [v.ravel() for v in each if v.size] or [each[0].ravel()]
            members[name] = filled[0] if len(filled) == 1 else np.concatenate(filled)
            members[f"{name}.shape"] = np.array([v.shape for v in each], np.int64).reshape(len(each), -1)
        try:
            with open(tmp, "wb") as f:
                np.savez(f, keys=keys, failed=failed, **members)
        except BaseException:  # a full disk, a kill: no half-written part stays
            tmp.unlink(missing_ok=True)
            raise
        os.replace(tmp, file)
        self._add(index, file, keys, failed)
        clusters = {name: members[name] for name in self.PER_PARTICLE}
        science = {name: values for name, values in members.items() if name not in self.PER_PARTICLE}
        kept = {"keys": keys}
        for group, values in (("clusters", clusters), ("science", science)):
            size = sum(v.nbytes for v in values.values())
            if self._kept_bytes[group] + size <= self.KEEP_BYTES:
                kept.update(values)
                self._kept_bytes[group] += size
        if self.PER_PARTICLE[0] in kept:  # their shapes come along (tiny: not counted)
            kept.update({f"{name}.shape": members[f"{name}.shape"] for name in self.PER_PARTICLE})
        if len(kept) > 1:
            self._kept[file] = kept

    def finished(self, key) -> bool:
        return key in self.where and not self.where[key][2]

    @property
    def n_finished(self) -> int:
        """How many clusters the folder holds finished (failed ones are computed again on resume)."""
        return sum(not failed for _, _, failed in self.where.values())

    @contextlib.contextmanager
    def _members(self, file, kept, names):
        """A part's members: those ``kept`` in memory when they hold every one of ``names``, else its file."""
        with self._reading(file), (contextlib.nullcontext(kept) if all(name in kept for name in names)
                                   else np.load(file)) as z:
            yield z

    def results(self, keys, names, release=False):
        """Variables ``names`` of the result of each key, in order; a part is read once for each run of its keys.

        Only those members are read: the clusters' positions, say, or
        everything but them. ``<name>.shape`` gives a variable's shape
        without reading it. ``release``: the positions kept in memory of
        each part read are let go (a later read takes them from its file).
        """
        for file, run in itertools.groupby(keys, lambda key: self.where[key][0]):
            kept = self._kept.get(file, {})
            if release:
                kept = {**kept, **self._release(file)}  # for this read
            with self._members(file, kept, names) as z:
                part = [{} for _ in z["keys"]]
                for name in names:
                    if name.endswith(".shape"):
                        for result, shape in zip(part, z[name]):
                            result[name] = shape
                        continue
                    flat, shapes = z[name], z[f"{name}.shape"]
                    sizes = shapes.prod(axis=1)
                    ends = np.cumsum(sizes)
                    for result, shape, start, end in zip(part, shapes.tolist(), (ends - sizes).tolist(), ends.tolist()):
                        result[name] = flat[start:end].reshape(shape)
            yield from (part[self.where[key][1]] for key in run)

    def release(self, keys):
        """Let go of the positions kept in memory of the parts that hold ``keys`` (later reads take them from
        the files)."""
        for file in {self.where[key][0] for key in keys}:
            self._release(file)

    def _release(self, file) -> dict:
        """The positions kept of one part, no longer kept (none: empty)."""
        if self.PER_PARTICLE[0] not in self._kept.get(file, {}):
            return {}
        clusters = {name: self._kept[file].pop(name) for name in self.PER_PARTICLE}
        self._kept_bytes["clusters"] -= sum(values.nbytes for values in clusters.values())
        return clusters

    def table(self, keys, names) -> dict:
        """Variables ``names`` of the results of ``keys``, each stacked on a first axis in key order.

        For variables of one shape in every result (the science, and the
        ``<name>.shape`` rows): a part's values are taken whole, not a result
        at a time, so assembling 10^4 small clusters costs milliseconds.
        """
        keys = list(keys)
        table = {}
        for file, run in itertools.groupby(enumerate(keys), lambda item: self.where[item[1]][0]):
            rows, at = zip(*((i, self.where[key][1]) for i, key in run))
            with self._members(file, self._kept.get(file, {}), names) as z:
                for name in names:
                    values = z[name]
                    if not name.endswith(".shape"):
                        shapes = z[f"{name}.shape"]
                        if (shapes != shapes[0]).any():
                            raise ValueError(f"{file}: {name} differs in shape between results")
                        values = values.reshape(len(shapes), *shapes[0])
                    if name not in table:
                        table[name] = np.empty((len(keys), *values.shape[1:]), values.dtype)
                    elif np.result_type(table[name], values) != table[name].dtype:  # a longer error message
                        table[name] = table[name].astype(np.result_type(table[name], values))
                    table[name][list(rows)] = values[list(at)]
        return table


@contextlib.contextmanager
def parts_folder(spec, out, resume):
    """The parts folder of ``out``, checked against the spec and locked for the whole run.

    A new folder is made whole (manifest written, lock held) under a
    temporary name and renamed into place, so no other run sees it half made.
    It is removed when the run sets ``done``, and when a run that made it
    fails before any part is saved: renamed away under the lock, so no other
    run finds it half deleted, then deleted once the lock is released.
    """
    identity = {"format": FORMAT, "dlasweep": __version__, "digest": spec.digest(), "identity": spec.identity()}
    if out is None:
        with tempfile.TemporaryDirectory(prefix="dlasweep-") as tmp:
            yield Parts(Path(tmp))
        return
    path = Path(f"{out}.parts")
    aside = path.with_name(f".{path.name}.{uuid.uuid4().hex[:12]}")
    lock = None if path.exists() else _new_folder(path, aside, identity)
    made = lock is not None
    if not made:
        lock = _lock(path)
    parts, removed = Parts(path), False  # reads nothing before the manifest is checked
    try:
        if not made:
            _check_manifest(path, identity, resume)
        try:
            yield parts
        except BaseException as err:
            parts.done = parts.done or (made and not any(path.glob("*.npz")))
            if isinstance(err, KeyboardInterrupt) and not isinstance(err, Interrupted):
                raise (Interrupted(0, None) if parts.done else Interrupted(parts.n_finished, path)) from err
            raise
        finally:
            if parts.done:
                path.rename(aside)
                removed = True
    finally:
        if not removed:
            # A folder that stays keeps no lock file naming an ended run; ``_lock``
            # never holds one deleted under it.
            (path / LOCK).unlink(missing_ok=True)
        os.close(lock)
        if removed:
            shutil.rmtree(aside, ignore_errors=True)


def _new_folder(path, staging, identity):
    """Make the parts folder ``path`` in ``staging``; its lock, or None if another run made it first."""
    staging.mkdir()
    lock = _lock(staging)
    try:
        (staging / MANIFEST).write_text(json.dumps(identity, indent=1))
        staging.rename(path)
    except OSError:
        os.close(lock)
        shutil.rmtree(staging, ignore_errors=True)
        if path.is_dir():  # another run made it first
            return None
        raise
    return lock


def _lock(folder) -> int:
    """Lock a parts folder for this process; return the lock file's descriptor.

    An flock ends with its process, so the lock file of a killed run is
    taken over at once. The file names its holder, for the runs it refuses.

    Raises
    ------
    ResumeError
        When another run holds the lock, or has just removed the folder.
    """
    file = folder / LOCK
    while True:
        try:
            fd = os.open(file, os.O_RDWR | os.O_CREAT, 0o644)
        except FileNotFoundError:
            raise ResumeError(f"{folder}: removed by the run that held it, which has ended") from None
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = os.read(fd, 256).decode(errors="replace") or "another process"
            os.close(fd)
            raise ResumeError(f"{folder}: in use by {holder}; wait for it to end, or stop it") from None
        with contextlib.suppress(FileNotFoundError):
            if os.path.samestat(os.fstat(fd), os.stat(file)):
                break
        os.close(fd)  # its holder deleted it on leaving, after we opened it: lock the one there now
    os.ftruncate(fd, 0)
    os.write(fd, f"process {os.getpid()} on {socket.gethostname()}".encode())
    return fd


def _check_manifest(path, identity, resume):
    """Refuse an existing parts folder of another format, without ``resume``, or from another spec
    (``ResumeError``).

    The format comes first: parts of another layout cannot be resumed
    whatever the spec, so the message says so rather than asking for
    ``--resume``. A manifest without one is of format 1 (dlasweep 0.1.0).
    """
    manifest = path / MANIFEST
    try:
        old = json.loads(manifest.read_text())
    except (OSError, ValueError):
        raise ResumeError(f"{manifest}: missing or damaged; delete {path} to start afresh") from None
    if not isinstance(old, dict):
        raise ResumeError(f"{manifest}: missing or damaged; delete {path} to start afresh")
    written = old.get("format", 1)
    if written != FORMAT:
        by = old.get("dlasweep", "0.1.0" if written == 1 else "another version")
        raise ResumeError(f"{path}: parts of format {written} (dlasweep {by}); this dlasweep ({__version__}) "
                          f"resumes format {FORMAT} only: finish the sweep with dlasweep {by}, or delete "
                          f"{path} and run it afresh")
    if not resume:
        raise ResumeError(f"{path}: left by an earlier run; pass --resume to continue it, or delete it")
    if old.get("digest") != identity["digest"]:
        changes = differences(old.get("identity", {}), identity["identity"])
        raise ResumeError(f"cannot resume: the spec differs from the one in {path} ("
                          + "; ".join(changes) + ")")
