"""Statistics: fits, intervals, ensembles."""
