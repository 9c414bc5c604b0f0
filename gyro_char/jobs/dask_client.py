"""
One way to get a Dask client: a local cluster of worker processes, or an existing scheduler.

Used by the fleet (many recordings) and by ``gyro-char diagnose --scheduler`` (its channels and
records). An address is ``tcp://HOST:PORT`` or the path of a scheduler file; a local cluster
listens on the loopback interface only. How long to try a scheduler is Dask's own setting
``distributed.comm.timeouts.connect`` (30 s unless set, e.g. by the environment variable
``DASK_DISTRIBUTED__COMM__TIMEOUTS__CONNECT=5s``).
"""
from contextlib import contextmanager
import logging
import os
from typing import Iterator, Optional

from gyro_char.errors import InputError


def _client(workers: Optional[int], scheduler: Optional[str]):
    from distributed import Client, LocalCluster

    if scheduler:
        try:
            if os.path.isfile(scheduler):
                return Client(scheduler_file=scheduler), None
            return Client(scheduler), None
        except (OSError, TimeoutError, ValueError) as exc:
            raise InputError(f'cannot reach the Dask scheduler {scheduler}: '
                             f'{str(exc).splitlines()[0] if str(exc) else type(exc).__name__}'
                             ) from None
    cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                           host='127.0.0.1', dashboard_address=None,
                           silence_logs=logging.ERROR)
    return Client(cluster), cluster


@contextmanager
def connect(workers: Optional[int], scheduler: Optional[str]) -> Iterator:
    """
    Yield a Dask client: a local cluster of ``workers`` processes, or the given scheduler.

    Raises
    ------
    InputError
        When the scheduler cannot be reached.

    """
    client, cluster = _client(workers, scheduler)
    try:
        yield client
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
