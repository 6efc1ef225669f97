"""Kernel changes keep every cluster bit-identical to the kernels of commit 4700418.

The fingerprints below were computed by that commit's code (before the
speed and memory work of issue 14): every model and variant of
``test_models.CASES`` at two seeds, and one larger cluster per model whose
growth crosses many grid enlargements. A change that alters any walk, any
draw from the random streams, or the rounding of any position changes a
fingerprint.

Renewed, with the reason: ``lattice-2d/30000/3``, ``off-2d/30000/3`` and
``off-3d/8000/3`` when the walks' distance bound far from the cluster came
from the distance pyramid instead of the dilated maps (issue 25): longer
jumps, the same law (``test_lattice.test_jumps_grow_the_clusters_single_steps_grow``,
``test_offlattice.test_the_pyramid_bound_keeps_the_clusters_of_the_maps_bound``).
``lattice-2d/30000/3`` again when lattice walkers far from the cluster jumped out of the
square free of particles instead of its inscribed circle (issue 25): the same Brownian
approximation, longer jumps (``test_lattice.test_square_exit_is_where_brownian_motion_leaves_the_square``,
``test_lattice.test_square_jumps_keep_the_2d_clusters_of_the_circle_jumps``).
``off-3d/8000/3`` again when the 3D off-lattice distance field's cap went from 4 to 6
coarse cells (issue 25): longer jumps, the same law
(``test_offlattice.test_the_pyramid_bound_keeps_the_clusters_of_the_maps_bound``).
Every off-lattice fingerprint with jumps when the field near the cluster became the
centre field (``centres.CCAP``) and the off-lattice grids grew by 2.0 instead of
1.3 (issue 25): longer jumps, the same law (the same test: 2D Rg -0.71 and Rg/Rmax -0.34
standard errors from the recorded means, 3D -0.99 and -0.43).
Those whose walkers go beyond the centre field's reach (``off-2d/30000/3``, ``off-3d/600/1``,
``off-3d/8000/3``, ``off-box/600/0``, ``off-box-launch/600/0`` and ``/1``) when the distance
pyramid above it became the centre pyramid (Euclidean, from each cell's centre:
``centres._level_rows``; issue 25): longer jumps, the same law (the same test:
2D Rg -1.62 and Rg/Rmax +0.30 standard errors, 3D -1.00 and +1.28).
The lattice's ``lattice-2d/30000/3``, ``lattice-3d/8000/3`` and both seeds of ``lattice-box``,
``lattice-box-launch``, ``lattice-kill``, ``lattice-launch-far`` and ``lattice-moore`` when the
lattice's Chebyshev pyramid above its field became the same centre pyramid (its walkers far from
the cluster jump onto circles of the Euclidean bound) and its grids grew by 2.0 instead of 1.25
(issue 25): longer jumps, the same law (``test_lattice.test_square_jumps_keep_the_2d_clusters_of_the_circle_jumps``:
Rg +0.34 and Rg/Rmax -0.64 standard errors; ``test_the_pyramid_bound_keeps_the_3d_clusters_of_the_maps_bound``:
+0.38 and -0.08; and ``test_jumps_grow_the_clusters_single_steps_grow``).
Every off-lattice fingerprint with jumps when the centre field bounded a walker's distance
from the centres of the ``2**dim`` coarse cells about it, not from its own cell's alone
(``centres.centre_bound``; issue 25): longer jumps, the same law
(``test_offlattice.test_the_pyramid_bound_keeps_the_clusters_of_the_maps_bound``: 2D Rg -2.22
and Rg/Rmax +1.40 standard errors, 3D -1.01 and +0.38; against the kernel before it, 900
clusters of 8000 each, seeds 1000-1299 and 3000-3599: 2D Rg 96.109 against 95.912, +1.7
standard errors of the difference, Rg/Rmax 0.5381 against 0.5391; 400 3D clusters, seeds
1000-1399: Rg 25.634 against 25.643, Rg/Rmax 0.5204 against 0.5192).
``off-2d/30000/3`` and ``off-3d/8000/3`` when off-lattice walkers where the centre pyramid
bounds their distance jumped out of the particle-free ball about their cell's centre instead
of the smaller one about themselves (``walk.ball_exit``; issue 25): the same law in fewer
draws (``test_offlattice.test_ball_exit_matches_brownian``; against the kernel before it,
seeds 1000-1899 of 8000 in 2D: Rg 96.021 against 96.078, -0.49 standard errors of the
difference, Rg/Rmax 0.5371 against 0.5377, -0.5; seeds 1000-1399 in 3D: Rg 25.594 against
25.634, -0.98, Rg/Rmax 0.5223 against 0.5204, +0.96).
"""

import hashlib

import numpy as np
import pytest

import dlasweep as dla
from test_models import CASES

FINGERPRINTS = {
    "lattice-2d/600/0": "1cdff7b56816a0f3",
    "lattice-2d/600/1": "adb3a955bef9c484",
    "lattice-3d/600/0": "3f57da8439820868",
    "lattice-3d/600/1": "1c331e9e239963bd",
    "lattice-moore/600/0": "07d58f895a52de04",
    "lattice-moore/600/1": "1bf98242bb37a922",
    "lattice-3d-moore/600/0": "3cfa30eaa203ca54",
    "lattice-3d-moore/600/1": "d2efcbd9514e39e1",
    "lattice-sticky/600/0": "3b9f2c4720e9cce5",
    "lattice-sticky/600/1": "e6eff614d8616986",
    "lattice-block/600/0": "9f1eda675e1d7bcc",
    "lattice-block/600/1": "c3c928cbd337319a",
    "lattice-line/600/0": "f33531fbe1259c05",
    "lattice-line/600/1": "ee353b087e80efef",
    "lattice-3d-plane/600/0": "2fd48a1b04a4fb4b",
    "lattice-3d-plane/600/1": "14acf6ed87fd1f2d",
    "lattice-box/600/0": "5d9cd23c8daf4f96",
    "lattice-box/600/1": "cac965d5bb727944",
    "lattice-box-launch/600/0": "aeee06db8f7f7e4f",
    "lattice-box-launch/600/1": "77be7e7a3d10a937",
    "lattice-kill/600/0": "ebadc1d2c3153ff7",
    "lattice-kill/600/1": "b8a5406ec3a332f7",
    "lattice-nojumps/600/0": "d7069d4a20732f4a",
    "lattice-nojumps/600/1": "f97183641aca48a2",
    "lattice-walkers/600/0": "4f98b3cf65a88d50",
    "lattice-walkers/600/1": "3ed2e45f425e3696",
    "lattice-launch-far/600/0": "b12d2f3506c012c5",
    "lattice-launch-far/600/1": "496e5454f08633aa",
    "off-2d/600/0": "86443b6164ee5f7d",
    "off-2d/600/1": "7c8357236329743e",
    "off-3d/600/0": "4a09b3a2f15cc58f",
    "off-3d/600/1": "30530536346909b2",
    "off-sticky/600/0": "848ee105a6d34d8e",
    "off-sticky/600/1": "db3262ed40ed3f7d",
    "off-block/600/0": "5c7799c3cd333369",
    "off-block/600/1": "de9505d49431cf62",
    "off-line/600/0": "e8720fd61a09c01d",
    "off-line/600/1": "ad175431f2e1a26b",
    "off-3d-plane/600/0": "d64a4b509976b71d",
    "off-3d-plane/600/1": "9825ef840af918a3",
    "off-box/600/0": "ade546d7ad496888",
    "off-box/600/1": "2ddbd4e34112a20a",
    "off-box-launch/600/0": "d032c797bee7931b",
    "off-box-launch/600/1": "5cd8f62396b42c87",
    "off-kill/600/0": "c785aba00ede8014",
    "off-kill/600/1": "74c0ba26e814847a",
    "off-nojumps/600/0": "ca0ba136f3984b3e",
    "off-nojumps/600/1": "862cdcd8edabfe27",
    "off-step/600/0": "dddb91a47158c910",
    "off-step/600/1": "bd96d2dd9c293fb5",
    "off-walkers/600/0": "adc7e7db07a8401a",
    "off-walkers/600/1": "225c987eeb17b42b",
    "lattice-2d/30000/3": "23a967a0e8fe2a73",
    "off-2d/30000/3": "5225adb4381b678e",
    "lattice-3d/8000/3": "dd6a7e9f5f4e5682",
    "off-3d/8000/3": "49a2a9c2b6b85b20",
}


def fingerprint(cluster) -> str:
    """The first 16 hex digits of sha256 over positions, diffusion times (int64) and status."""
    h = hashlib.sha256()
    h.update(np.ascontiguousarray(cluster.points).tobytes())
    h.update(np.ascontiguousarray(cluster.steps.astype(np.int64)).tobytes())
    h.update(cluster.status.encode())
    return h.hexdigest()[:16]


@pytest.mark.parametrize("key", sorted(FINGERPRINTS))
def test_cluster_is_bit_identical_to_the_reference_kernels(key):
    name, n, seed = key.split("/")
    assert fingerprint(dla.grow(int(n), seed=int(seed), **CASES[name])) == FINGERPRINTS[key]
