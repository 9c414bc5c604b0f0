"""Write an output file atomically: to a temporary name beside it, then renamed over it."""
import os
from typing import Callable


def atomic_write(path: str, write: Callable[[str], None]) -> None:
    """
    Call ``write(tmp)`` for a temporary path beside ``path``, then move it into place.

    A reader (or a batch interrupted mid-write) sees the old file or the new one, never half.
    """
    tmp = f'{path}.tmp-{os.getpid()}'
    write(tmp)
    os.replace(tmp, path)
