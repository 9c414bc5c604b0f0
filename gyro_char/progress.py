"""Progress bars for long steps: shown only on a terminal and never with ``--quiet``."""
import sys
from typing import Iterable, Optional

from tqdm import tqdm


def progress(iterable: Optional[Iterable] = None, *, total: Optional[int] = None,
             desc: str = '', quiet: bool = False, unit: str = 'it') -> tqdm:
    """Wrap ``iterable`` (or return a manual bar) that stays silent off a terminal."""
    disable = quiet or not sys.stderr.isatty()
    return tqdm(iterable, total=total, desc=desc, unit=unit, disable=disable,
                leave=False, dynamic_ncols=True)
