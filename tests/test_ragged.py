"""One stored cluster read back from the ragged array (dlasweep/data/ragged.py): by its index or its parameters."""

import numpy as np
import pytest

from dlasweep.data import ragged
from test_store import synthetic_dataset


def test_a_cluster_is_found_by_its_index_or_its_parameters():
    ds = synthetic_dataset()
    counts = ds["cluster_particles"].values
    k = int(np.flatnonzero(counts)[2])
    start = counts[:k].sum()
    expected = np.stack([ds["x"].values, ds["y"].values], axis=1)[start:start + counts[k]]
    np.testing.assert_array_equal(ragged.cluster_points(ds, k), expected)
    where = {name.removeprefix("cluster_"): ds[name].values[k]
             for name in ds.coords if name.startswith("cluster_")}
    np.testing.assert_array_equal(ragged.cluster_points(ds, **where), expected)
    parents = ragged.cluster_parents(ds, **where)
    assert parents.dtype == np.int32
    np.testing.assert_array_equal(parents, ds["parent"].values[start:start + counts[k]])
    with pytest.raises(ValueError, match="matches 8 clusters"):
        ragged.cluster_points(ds, model="lattice")
    with pytest.raises(ValueError, match="colour: not a cluster parameter"):
        ragged.cluster_points(ds, colour="red")
    with pytest.raises(IndexError):
        ragged.cluster_points(ds, 99)
    np.testing.assert_array_equal(ragged.cluster_points(ds, np.int64(k - len(counts))), expected)  # from the end


@pytest.mark.parametrize("index", [1.5, "2", True])
def test_an_index_that_is_not_an_integer_is_refused(index):
    with pytest.raises(TypeError, match=f"^cluster: index {index!r} is not an integer$"):
        ragged.read_cluster(synthetic_dataset(), index)


def test_a_path_in_place_of_a_dataset_is_refused_naming_ds():
    for where in ({"index": 0}, {"seed": 0}):
        with pytest.raises(TypeError, match="^ds: expected an xarray.Dataset .*got str$"):
            ragged.read_cluster("sweep.nc", **where)
