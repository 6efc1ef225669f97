"""The dataset: its schema, the netCDF file, ragged per-particle arrays, selection, the ``ds.dla`` accessor, exports."""
