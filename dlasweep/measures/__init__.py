"""Measures of one point set, no I/O: box counts and their bitmaps, Rg and shape, the tree."""
