"""Numba kernels: no I/O, RNG state passed in explicitly."""
