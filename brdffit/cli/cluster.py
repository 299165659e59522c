"""The Dask client of ``brdffit fit --scheduler ADDRESS`` or ``--workers N``, with one-line errors."""

import contextlib
import logging
import os
from collections.abc import Iterator

from ..errors import BrdfInputError

#: How long to wait for a scheduler to answer, in seconds.
CONNECT_SECONDS = 10


@contextlib.contextmanager
def cluster_client(address: str | None, workers: int | None) -> Iterator:
    """A ``dask.distributed.Client`` of the scheduler at ``address``, or of a local cluster of ``workers`` worker
    processes (one thread each: a fit's programs use the cores of their process) closed on leaving."""
    try:
        import distributed
    except ImportError:
        option = "--scheduler" if address else "--workers"
        raise BrdfInputError(f"{option} needs Dask: pip install 'brdffit[cluster]'") from None
    # Dask's start-up and shut-down notices, here and in the worker processes it starts (which read the variable)
    os.environ.setdefault("DASK_LOGGING__DISTRIBUTED", "error")
    logging.getLogger("distributed").setLevel(logging.ERROR)
    if address:
        try:
            client = distributed.Client(address, timeout=CONNECT_SECONDS)
        except (OSError, TimeoutError, ValueError) as error:
            raise BrdfInputError(f"--scheduler {address}: no Dask scheduler answers there ({error})") from None
        with client:
            yield client
        return
    cluster = distributed.LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=":0")
    with cluster, distributed.Client(cluster) as client:
        yield client
