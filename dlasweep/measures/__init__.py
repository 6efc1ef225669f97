"""Measures of one point set, no I/O."""
