"""The package version and the format version of its files, in a module of their own so that any module can
import them without importing the package (``from ._version import __version__``)."""

__version__ = "0.2.0"

FORMAT = 3
"""The layout of the files dlasweep writes: the netCDF files' global attribute ``dlasweep_format`` and the
``format`` of a sweep's parts manifest. It changes when a file or a part of this layout would be read wrongly
by the code of another (a variable added, moved or re-encoded), or when the same spec would grow other
clusters; a release that changes neither keeps it, so a patch release reads and resumes what the one before
it wrote. Format 1 is everything written before the attribute existed (dlasweep 0.1.0): its netCDF files
still open, its parts folders cannot be resumed (they lack the clusters' parents). Format 3 samples the harmonic measure
at every count (``harmonic_entropy``, ``harmonic_entropy_half``)."""
