"""Many records at once: :func:`identify_many` fits a model per record on local processes or
a Dask cluster and streams one row per record to a Parquet table."""
