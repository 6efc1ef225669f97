"""The package version, in a module of its own so that any module can import it without
importing the package (``from ._version import __version__``)."""

__version__ = "0.2.0"
