"""
The Dask side of the fleet: a cluster to run on and the tasks' results as they finish.

Without an address the fleet starts a ``LocalCluster`` of worker processes (one thread each:
one recording in memory per worker) on the loopback interface; with ``--scheduler`` it joins an
existing cluster started with ``dask scheduler`` / ``dask worker`` (an address
``tcp://HOST:PORT`` or a scheduler file). A worker that dies mid-task has its task re-run
elsewhere by the scheduler; a task that kills ``distributed.scheduler.allowed-failures``
workers comes back as an error.
"""
from typing import Callable, Dict, List, Tuple


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
