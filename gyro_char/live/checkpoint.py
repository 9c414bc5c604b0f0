"""
Atomic checkpoints of plain-array state, for nodes that must survive ``kill -9``.

A checkpoint is one ``.npz`` file holding named numpy arrays. Nested state dicts are flattened
with ``/`` in the keys (``accumulator/sum_sq``) and restored by ``load_checkpoint``. Writing goes
to a temporary file in the same directory, is flushed and fsynced, then ``os.replace``-d over the
old file and the directory is fsynced: at any instant the path holds either the previous or the
new complete checkpoint, never a torn one. Pickle is never used (``allow_pickle=False``).
"""
import os
from pathlib import Path
import time
from typing import Any, Dict, Optional

from gyro_char.errors import InputError
import numpy as np

FORMAT_VERSION = 1


def flatten(state: Dict[str, Any], prefix: str = '') -> Dict[str, np.ndarray]:
    """Nested dict of arrays/scalars/strings -> flat dict with ``a/b`` keys."""
    flat = {}
    for key, value in state.items():
        if '/' in key:
            raise ValueError(f'checkpoint key {key!r} must not contain "/"')
        name = prefix + key
        if isinstance(value, dict):
            flat.update(flatten(value, name + '/'))
        else:
            arr = np.asarray(value)
            if arr.dtype == object:
                raise ValueError(f'checkpoint entry {name!r} is not a plain array')
            flat[name] = arr
    return flat


def unflatten(flat: Dict[str, np.ndarray]) -> Dict[str, Any]:
    """Inverse of ``flatten``; 0-d arrays stay 0-d arrays (callers convert)."""
    out: Dict[str, Any] = {}
    for name, value in flat.items():
        node = out
        parts = name.split('/')
        for part in parts[:-1]:
            node = node.setdefault(part, {})
        node[parts[-1]] = value
    return out


def save_checkpoint(path: os.PathLike, state: Dict[str, Any]) -> None:
    """Write ``state`` atomically to ``path`` (an ``.npz`` file)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    flat = flatten(state)
    flat['__format__'] = np.asarray(FORMAT_VERSION)
    tmp = path.with_name(f'.{path.name}.{os.getpid()}.tmp')
    try:
        with open(tmp, 'wb') as f:
            np.savez(f, **flat)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            tmp.unlink()
    # Make the rename itself durable.
    dir_fd = os.open(path.parent, os.O_RDONLY)
    try:
        os.fsync(dir_fd)
    finally:
        os.close(dir_fd)


def load_checkpoint(path: os.PathLike) -> Optional[Dict[str, Any]]:
    """Read a checkpoint; None when there is none; ``InputError`` when it is unreadable."""
    path = Path(path)
    if not path.exists():
        return None
    try:
        with np.load(path, allow_pickle=False) as data:
            flat = {k: data[k] for k in data.files}
    except (OSError, ValueError, EOFError) as exc:
        raise InputError(f'checkpoint {path} is unreadable: {exc}') from exc
    version = int(flat.pop('__format__', -1))
    if version != FORMAT_VERSION:
        raise InputError(f'checkpoint {path} has format {version}, expected {FORMAT_VERSION}')
    return unflatten(flat)


class PeriodicCheckpoint:
    """Decides when a periodic checkpoint is due and writes it (clock injectable for tests)."""

    def __init__(self, path: os.PathLike, period_s: float, clock=time.monotonic) -> None:
        self.path = Path(path)
        self.period_s = float(period_s)
        self.clock = clock
        self.last_write: Optional[float] = None
        self.writes = 0
        self.last_duration_s = 0.0

    def due(self) -> bool:
        """Return True when no checkpoint was written yet or the period has passed."""
        return self.last_write is None or self.clock() - self.last_write >= self.period_s

    def write(self, state: Dict[str, Any]) -> None:
        """Write now (whether due or not) and restart the period."""
        start = self.clock()
        save_checkpoint(self.path, state)
        self.last_write = self.clock()
        self.last_duration_s = self.last_write - start
        self.writes += 1

    def maybe_write(self, make_state) -> bool:
        """Call ``make_state()`` and write when due; return whether it wrote."""
        if not self.due():
            return False
        self.write(make_state())
        return True

    def age_s(self) -> Optional[float]:
        """Seconds since the last write, None before the first one."""
        return None if self.last_write is None else self.clock() - self.last_write
