"""Growing one cluster: ``Cluster``, ``grow`` and ``grow_many`` over the numba kernels."""
