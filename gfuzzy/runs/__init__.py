"""Many queries at once: regression runs and Dask batches."""
