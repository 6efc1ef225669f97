"""One stored cluster read back from the ragged array (dlasweep/ragged.py): by its index or its parameters."""

import numpy as np
import pytest

from dlasweep import ragged
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
