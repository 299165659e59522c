"""Many fits: the datasets cut into buckets and batches (``buckets.py``), fitted on threads (``threads.py``) by
:func:`~brdffit.fitting.many.batch.fit_many` (``batch.py``), or spread over a Dask cluster (``cluster.py``)."""
