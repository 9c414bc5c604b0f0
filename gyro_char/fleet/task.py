"""
The fleet's unit of work, run inside a Dask worker: one device's recording through its job.

The task receives a path (never data), reads the recording itself, runs the job in a private
temporary directory and returns the files the command wrote as bytes with the tidy
measurements. It touches nothing shared, so a task the scheduler re-runs after a worker died
(or runs twice) does no harm: the client writes each device's outputs once, atomically.
"""
import argparse
import ctypes
import ctypes.util
import gc
import io
import os
import resource
import shutil
import sys
import tempfile
import time
import traceback
from typing import Dict

from gyro_char.errors import InputError
from gyro_char.jobs import job_module
from gyro_char.jobs.base import Console


def package_version() -> str:
    """Return the installed gyro_char version ('unknown' outside an installed distribution)."""
    from importlib.metadata import PackageNotFoundError, version
    try:
        return version('gyro_char')
    except PackageNotFoundError:
        return 'unknown'


def peak_rss_bytes() -> int:
    """Peak resident memory of this process so far (bytes)."""
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return int(peak if sys.platform == 'darwin' else peak * 1024)


def release_memory() -> None:
    """
    Hand the previous task's freed memory back to the system before the next one.

    Keeps a worker's footprint at one recording's: without it glibc keeps freed arenas and
    each later peak lands on top of them.
    """
    gc.collect()
    name = ctypes.util.find_library('c')
    if name and sys.platform.startswith('linux'):
        try:
            ctypes.CDLL(name).malloc_trim(0)
        except (OSError, AttributeError):
            pass


def run_device(device: str, path: str, kind: str, options: Dict) -> Dict:
    """
    Run the ``kind`` job on one recording; return its outcome as plain data.

    Returns
    -------
    dict
        ``device, status ('ok' | 'error'), message, measurements, files ({name: bytes}), log,
        cacheable`` (False for errors that are not the input's: a retry may succeed),
        ``seconds, cpu_seconds, peak_rss, pid, host``.

    """
    release_memory()
    start, cpu = time.perf_counter(), time.process_time()
    job = job_module(kind)
    log = io.StringIO()
    out = tempfile.mkdtemp(prefix='gyro-char-fleet-')
    status, message, cacheable, measurements = 'ok', '', True, []
    try:
        args = argparse.Namespace(**job.recording_args(path), out=out, quiet=True, **options)
        try:
            measurements = job.run(args, Console(log, log))
        except InputError as exc:
            status, message = 'error', str(exc)
        except MemoryError:
            status, message, cacheable = 'error', 'out of memory', False
        except Exception as exc:  # noqa: B902 - one bad recording must not stop the batch
            status, cacheable = 'error', False
            message = f'internal error: {type(exc).__name__}: {exc}'.splitlines()[0]
            log.write(traceback.format_exc())
        files = {}
        for name in sorted(os.listdir(out)):
            p = os.path.join(out, name)
            if os.path.isfile(p):
                with open(p, 'rb') as fh:
                    files[name] = fh.read()
    finally:
        shutil.rmtree(out, ignore_errors=True)
    # the command's lines name its output directory: the device's, once the client wrote it
    text = log.getvalue().replace(out, os.path.join('devices', device))
    return {'device': device, 'status': status, 'message': message,
            'measurements': measurements, 'files': files, 'log': text,
            'cacheable': cacheable, 'seconds': time.perf_counter() - start,
            'cpu_seconds': time.process_time() - cpu, 'peak_rss': peak_rss_bytes(),
            'pid': os.getpid(), 'host': os.uname().nodename, 'version': package_version()}
