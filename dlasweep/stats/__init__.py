"""Ensembles of clusters: fits, bootstrap intervals, extrapolation, branch statistics, the summary."""
