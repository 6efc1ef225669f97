"""Outputs whose target cannot be written are refused before any work, naming the path, in the API as on the
command line (``paths.writable``)."""

import os

import pytest

import dlasweep as dla
from dlasweep.data import netcdf as store
from dlasweep.data.paths import writable


def test_each_way_a_target_cannot_be_written_names_it(tmp_path):
    (tmp_path / "file.nc").write_text("")
    (tmp_path / "folder").mkdir()
    assert writable(tmp_path / "new.nc") == tmp_path / "new.nc"
    assert writable(tmp_path / "folder", folder=True) == tmp_path / "folder"
    assert writable(tmp_path / "new", folder=True) == tmp_path / "new"
    with pytest.raises(IsADirectoryError, match=r"folder: is a folder$"):
        writable(tmp_path / "folder")
    with pytest.raises(NotADirectoryError, match=r"file.nc: exists and is not a folder$"):
        writable(tmp_path / "file.nc", folder=True)
    with pytest.raises(FileNotFoundError, match=r"missing/x.nc: folder .*missing does not exist$"):
        writable(tmp_path / "missing" / "x.nc")
    assert {p.name for p in tmp_path.iterdir()} == {"file.nc", "folder"}


@pytest.mark.skipif(not os.path.isdir("/proc/self"), reason="needs Linux's /proc, a folder nobody may write in")
def test_a_folder_that_cannot_be_written_is_named():
    # /proc refuses new files even to root, whatever its permission bits say
    with pytest.raises(PermissionError, match=r"^/proc/x.nc: folder /proc is not writable$"):
        writable("/proc/x.nc")


def test_the_api_writers_refuse_a_missing_folder_naming_the_path_not_a_temporary_one(tmp_path):
    cluster = dla.grow(30)
    spec = tmp_path / "spec.toml"
    spec.write_text("[grid]\nn_particles = [10]\nseeds = 1\n")
    target = tmp_path / "missing" / "out"
    writers = {
        ".csv": lambda path: dla.export_cluster(cluster, path),
        ".nc": lambda path: store.save(store.cluster_dataset(cluster, 0), path),
    }
    for suffix, write in writers.items():
        with pytest.raises(FileNotFoundError, match=rf"^{target}{suffix}: folder {target.parent} does not exist$"):
            write(target.with_suffix(suffix))
    with pytest.raises(FileNotFoundError, match=rf"^{target}.nc: folder {target.parent} does not exist$"):
        dla.run_sweep(spec, out=target.with_suffix(".nc"))
    assert [p.name for p in tmp_path.iterdir()] == ["spec.toml"]
