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
        except Exception as error:  # whatever fails, no scheduler answers: an HTTP server's bytes, read by Dask as a
            # frame length, asked for 3 EiB (MemoryError)
            reason = f"{type(error).__name__}: {error}".splitlines()[0]
            raise BrdfInputError(f"--scheduler {address}: no Dask scheduler answers there ({reason})") from None
        with client, _killed_workers(distributed, f"--scheduler {address}"):
            yield client
        return
    try:
        cluster = distributed.LocalCluster(
            n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=":0"
        )
    except Exception as error:  # Dask's event loop gives up after 10 s on a loaded machine (a bare AssertionError)
        reason = f"{type(error).__name__}: {error}".splitlines()[0].rstrip(": ")
        raise BrdfInputError(
            f"--workers {workers}: a local Dask cluster did not start ({reason}); nothing written"
        ) from None
    with cluster, distributed.Client(cluster) as client, _killed_workers(distributed, f"--workers {workers}"):
        yield client


@contextlib.contextmanager
def _killed_workers(distributed, where: str) -> Iterator[None]:
    """A fit that killed every worker it was given (Dask gives up after a few: ``KilledWorker``) as one line."""
    try:
        yield
    except distributed.KilledWorker as error:
        reason = str(error).split(". ")[0]  # "Attempted to run task … on 4 different workers, but all … died …"
        raise BrdfInputError(
            f"{where}: Dask workers died while fitting ({reason[:1].lower()}{reason[1:]}); nothing written"
        ) from None
