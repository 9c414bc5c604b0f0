"""
The Dask side of the fleet: a cluster to run on and the tasks' results as they finish.

Without an address the fleet starts a ``LocalCluster`` of worker processes (one thread each:
one recording in memory per worker) on the loopback interface; with ``--scheduler`` it joins an
existing cluster started with ``dask scheduler`` / ``dask worker`` (an address
``tcp://HOST:PORT`` or a scheduler file). A worker that dies mid-task has its task re-run
elsewhere by the scheduler; a task that kills ``distributed.scheduler.allowed-failures``
workers comes back as an error.
"""
from contextlib import contextmanager
import logging
import os
from typing import Callable, Dict, Iterator, List, Optional, Tuple

from gyro_char.errors import InputError

CONNECT_TIMEOUT_S = 30


def _client(workers: Optional[int], scheduler: Optional[str]):
    from distributed import Client, LocalCluster

    if scheduler:
        try:
            if os.path.isfile(scheduler):
                return Client(scheduler_file=scheduler, timeout=CONNECT_TIMEOUT_S), None
            return Client(scheduler, timeout=CONNECT_TIMEOUT_S), None
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


def run_tasks(client, func: Callable, tasks: List[Tuple[str, Tuple]],
              on_result: Callable[[Dict], None]) -> None:
    """
    Submit ``func(*args)`` for each ``(key, args)`` and pass each outcome to ``on_result``.

    An exception from the task machinery (e.g. ``KilledWorker`` after repeated worker deaths)
    becomes an error outcome of that task; the others go on. On interruption (Ctrl-C) the
    pending tasks are cancelled before the exception propagates.
    """
    from distributed import as_completed

    futures = {client.submit(func, *args, key=key, pure=False): args for key, args in tasks}
    try:
        for fut in as_completed(list(futures)):
            try:
                result = fut.result()
            except Exception as exc:  # noqa: B902 - the task failed outside the job: an error row
                result = {'device': futures[fut][0], 'status': 'error',
                          'message': _describe(exc), 'measurements': [], 'files': {},
                          'log': '', 'cacheable': False, 'seconds': float('nan'),
                          'cpu_seconds': float('nan'), 'peak_rss': 0, 'pid': 0, 'host': ''}
            on_result(result)
            fut.release()
    except BaseException:
        client.cancel(list(futures), force=True)
        raise


def _describe(exc: BaseException) -> str:
    name = type(exc).__name__
    if name == 'KilledWorker':
        return ('the workers running this recording died repeatedly (e.g. out of memory); '
                'see the worker logs')
    if name == 'CancelledError':
        return 'the task was cancelled (scheduler lost or shut down)'
    text = str(exc).splitlines()[0] if str(exc) else ''
    return f'task failed: {name}: {text}' if text else f'task failed: {name}'
